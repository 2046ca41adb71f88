// Cross-check of the analytic Phantom model (reference/phantom/phantom_model.h) against its MuJoCo
// 2.2.2 model (plant/mujoco_phantom.h), both built from one device model file (issue #3).
//
// Static part: at `samples` random states (q uniform in the joint-limit box, qd uniform in
// +-qd_max) compare M, C qd ("bias"), g ("gravity"), the tip pose and the tool Jacobian J_t
// (V1 = J_t qd). Error metric (docs/phantom.md "Tolerance policy"), per quantity and sample:
//   abs = max_ij |analytic_ij - mujoco_ij|,   rel = abs / max_ij |mujoco_ij|
// (the max-norm of the difference over the max-norm of the reference, so zero entries do not
// divide); the pose stacks x1 [m] and the entries of R1. Reported: the maxima over samples.
// Dynamic part: from one random state, both models run `trajectory_s` under one random torque
// sequence (uniform noise scaled to a joint acceleration, plus each model's own gravity
// compensation, clamped to the torque limits, held over each control_dt_s tick);
// the analytic model is integrated by classical RK4 with MuJoCo's timestep, MuJoCo by its own
// RK4 with the closed chain held by its equality constraints. Reported: max_t |q_a - q_mj| with
// Coulomb friction removed from both models (MuJoCo 2.2.2 has it only as the soft `frictionloss`
// constraint, a different law from the analytic f_c tanh(qd / v_s)), and separately the same run
// with the file's Coulomb friction (trajectory.coulomb_max_abs_rad).
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>

#include "plant/phantom_mjcf.h"
#include "reference/phantom/phantom_params.h"

namespace dentsim {

struct DeviceCrosscheckOptions {
  int samples = 1000;
  std::uint64_t seed = 20021;
  double qd_max_rad_s = 3.0;
  double trajectory_s = 1.0;
  double control_dt_s = 1e-3;
  // Torque at tick k: a uniform random torque of amplitude accel_rad_s2 * M_jj(q_0) per joint,
  // the same for both models, plus (gravity_compensation) each model's own g(q_k), as the device
  // is gravity-compensated (thesis (2.1)); clamped to the torque limits. Without compensation the
  // gimbal is an inverted pendulum near its upper equilibria and amplifies any difference by
  // ~e^17 per second (docs/phantom.md), which measures the pendulum, not the models.
  double accel_rad_s2 = 20.0;
  bool gravity_compensation = true;
  PhantomMjcfOptions mjcf;  // timestep, integrator, friction on/off, closure stiffness
};

struct QuantityError {
  double max_abs = 0.0;
  double max_rel = 0.0;
  double max_ref = 0.0;  // largest reference max-norm seen (the signal, for the guard)
  void add(double abs_err, double ref_norm);
};

struct DeviceCrosscheckResult {
  int samples = 0;
  std::uint64_t seed = 0;
  QuantityError mass_matrix, bias, gravity, pose, jacobian;
  double trajectory_max_abs_rad = 0.0;
  double trajectory_final_abs_rad = 0.0;
  double trajectory_range_rad = 0.0;            // max |q(t) - q(0)|: how far the device moved
  double trajectory_max_closure_rad = 0.0;      // largest equality violation of MuJoCo's chain
  double trajectory_coulomb_max_abs_rad = 0.0;  // the same run with the file's Coulomb friction
  double trajectory_coulomb_range_rad = 0.0;
  double trajectory_s = 0.0;
  double timestep_s = 0.0;
};

DeviceCrosscheckResult crosscheck_device(const PhantomParams& params,
                                         const DeviceCrosscheckOptions& options = {});

// The JSON report: {"samples", "seed", "mass_matrix": {"max_abs", "max_rel"}, "bias", "gravity",
// "pose", "jacobian", "trajectory": {"max_abs_rad", ...}} (keys are a CLI contract).
nlohmann::json crosscheck_device_json(const DeviceCrosscheckResult& r);

}  // namespace dentsim
