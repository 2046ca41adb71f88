// The experiment behind `dentsim demo`: a scripted hand presses the tool tip of an ideal
// rigid-body device into a stiff flat wall (validation/wall_loop.h), once per method (explicit,
// pmi, pmi-pd), and what each rendered is reported: the force fed back f [N] and the device tip's
// depth d [m] at the end, the static stiffness f / d [N/m] (the series coupling-wall stiffness
// K_vc K_tooth / (K_vc + K_tooth) for VC at rest), and the energy the virtual side put into the
// device E_v [J] (passive: E_v <= 1 uJ).
//
// The device is the apparent tip of a Phantom Premium (75 g, 2e-4 kg m^2, damping 0.5 N s/m and
// 0.002 N m s/rad), the proxy 20 g / 2e-6 kg m^2 with the handpiece, coupling damping 0.05 N s/m,
// rotational coupling 0.3 N m/rad and 1e-4 N m s/rad, observer gain 100 1/s; the hand is a force
// source (no stiffness, 2 N s/m of damping) so that at rest the force fed back equals the push.
#pragma once

#include <nlohmann/json.hpp>
#include <vector>

#include "validation/wall_loop.h"

namespace dentsim {

struct WallDemo {
  double duration_s = 1.0;  // simulated time per method [s]
  double k_vc = 400.0;      // translational coupling stiffness [N/m]
  double k_tooth = 1500.0;  // wall stiffness [N/m]
  double tick = 1e-3;       // T [s]
  double push_n = 2.0;      // hand push into the wall [N]
  std::vector<Method> methods = {Method::kExplicitVc, Method::kPmiVc, Method::kPmiPd};
};

struct WallDemoRun {
  Method method = Method::kExplicitVc;
  WallLoopResult loop;
  double static_stiffness_n_per_m = 0.0;  // final force / final device depth (0 if not in the wall)
  bool passive = false;                   // E_v <= 1e-6 J
};

// The wall loop of `method` in the demo.
WallLoopConfig wall_demo_config(const WallDemo& demo, Method method);

std::vector<WallDemoRun> run_wall_demo(const WallDemo& demo);

// `dentsim demo --json`: the demo's numbers and one object per method.
nlohmann::json wall_demo_json(const WallDemo& demo, const std::vector<WallDemoRun>& runs);

}  // namespace dentsim
