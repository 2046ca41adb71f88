// A closed loop for tests, the demo and quick experiments: an ideal rigid-body device
// (reference/rigid_body_device.h, simulated in continuous time with RK4 substeps and a
// zero-order hold on the joint torques), a scripted hand (spring-damper to a moving reference
// plus a feed-forward push), a flat wall (half-space) as the contact provider, and a Pipeline.
//
// It measures what the Z-width protocol needs: the force fed back to the hand, the device's and
// the proxy's penetration, and the energy the virtual side put into the device,
// E_v = ∫ V1^T T1 dt (T1 = J1^T tau, the wrench the motors apply), integrated per substep; E_v <= 0
// means the rendering was passive at the device port.
#pragma once

#include <functional>
#include <string>

#include "reference/half_space_wall.h"
#include "reference/rigid_body_device.h"
#include "reference/tick.h"

namespace dentsim {

// The scripted hand: F_h = K (x_ref(t) - x1) - B v1 + push(t), torque -K_w log(R_ref^T R1) - B_w w1.
// x_ref moves from x_start along `direction` at `speed` for `travel` metres, then holds;
// push(t) ramps linearly to `push` over `push_ramp_s`.
struct WallHand {
  double stiffness = 200.0;       // K [N/m]
  double damping = 2.0;           // B [N s/m]
  double stiffness_ang = 0.5;     // K_w [N m/rad]
  double damping_ang = 0.005;     // B_w [N m s/rad]
  Vec3 x_start = Vec3::Zero();
  Vec3 direction = -Vec3::UnitZ();
  double speed = 0.02;            // [m/s]
  double travel = 0.01;           // [m]
  Vec3 push = Vec3::Zero();       // feed-forward force [N]
  double push_ramp_s = 0.2;
};

struct WallLoopConfig {
  RigidBodyDeviceParams device;
  PipelineConfig pipeline;
  WallHand hand;
  Vec3 wall_point = Vec3::Zero();
  Vec3 wall_normal = Vec3::UnitZ();
  double tip_radius = 0.001;      // [m]
  double wall_stiffness = 1500.0; // K_tooth [N/m]
  double wall_damping = 0.0;      // B_tooth [N s/m]
  Vec3 start = Vec3(0.0, 0.0, 0.003);  // device tip start position [m]
  double tick = 1e-3;             // T [s]
  int substeps = 10;              // RK4 substeps per tick
  double duration = 1.0;          // [s]
};

struct WallLoopRecord {
  double t;
  double force_n;           // |f| of the wrench fed back to the device, along the wall normal
  double device_depth_m;    // penetration of the device tip sphere
  double proxy_depth_m;     // penetration of the proxy tip sphere
  double energy_j;          // E_v so far
  double hand_force_n;      // hand force along -normal
};

struct WallLoopResult {
  long ticks = 0;
  long contact_ticks = 0;
  double max_force_n = 0.0;        // max normal force fed back to the device
  double max_device_depth_m = 0.0;
  double max_proxy_depth_m = 0.0;
  double energy_virtual_j = 0.0;   // E_v at the end (<= 0: passive)
  double max_energy_virtual_j = 0.0;
  double final_force_n = 0.0;      // mean normal force over the last 10 % of the run
  double final_device_depth_m = 0.0;  // mean device penetration over the last 10 %
  bool finite = true;              // false if the state blew up (NaN/inf): the run stopped early
  // Force fed back / max device penetration (the thesis's Z-width measure).
  double rendered_stiffness() const {
    return max_device_depth_m > 0.0 ? max_force_n / max_device_depth_m : 0.0;
  }
};

WallLoopResult run_wall_loop(const WallLoopConfig& cfg,
                             const std::function<void(const WallLoopRecord&)>& on_tick = {});

// The same loop (the ideal device, cfg.pipeline, cfg.tick, cfg.substeps, cfg.start,
// cfg.duration) on any environment and any scripted hand; cfg.hand and the wall fields are not
// used. `hand` gives the wrench on the device (world force [N], torque [N m] as WallHand's) from
// the time and the device's state (tip position, orientation, world velocity, body angular
// velocity).
using HandWrenchFn = std::function<Vec6(double t, const Vec3& x, const Mat3& R, const Vec3& v,
                                        const Vec3& w)>;

struct ProviderLoopRecord {
  double t;                 // time at the end of the tick [s]
  Vec3 device_x;            // device tip position after the tick [m]
  Vec3 device_force;        // force part of T1, the wrench the motors apply to the device [N]
  Vec3 proxy_x;             // the virtual tool's position after the tick [m]
  const TickResult* tick;   // the tick's result (contacts, F_contact, ...)
};

// Returns false when the loop faulted or its state blew up (the run stopped there).
bool run_provider_loop(const WallLoopConfig& cfg, ContactProvider& provider,
                       const HandWrenchFn& hand,
                       const std::function<void(const ProviderLoopRecord&)>& on_tick);

}  // namespace dentsim
