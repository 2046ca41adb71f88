#include "validation/crosscheck_device.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "plant/mujoco_phantom.h"
#include "reference/phantom/phantom_model.h"

namespace dentsim {

void QuantityError::add(double abs_err, double ref_norm) {
  max_abs = std::max(max_abs, abs_err);
  max_ref = std::max(max_ref, ref_norm);
  if (ref_norm > 0.0) {
    max_rel = std::max(max_rel, abs_err / ref_norm);
  } else if (abs_err > 0.0) {
    max_rel = std::numeric_limits<double>::infinity();
  }
}

namespace {

template <typename A, typename B>
void compare(const A& analytic, const B& reference, QuantityError* e) {
  e->add((analytic - reference).cwiseAbs().maxCoeff(), reference.cwiseAbs().maxCoeff());
}

// One classical RK4 step of the analytic model, torque held.
Vec6 rk4_step(const PhantomModelD& model, Vec6* q, Vec6* qd, const Vec6& tau, double h) {
  auto f = [&](const Vec6& x, const Vec6& v) { return model.forward_dynamics(x, v, tau); };
  const Vec6 k1v = f(*q, *qd);
  const Vec6 k1x = *qd;
  const Vec6 k2v = f(*q + 0.5 * h * k1x, *qd + 0.5 * h * k1v);
  const Vec6 k2x = *qd + 0.5 * h * k1v;
  const Vec6 k3v = f(*q + 0.5 * h * k2x, *qd + 0.5 * h * k2v);
  const Vec6 k3x = *qd + 0.5 * h * k2v;
  const Vec6 k4v = f(*q + h * k3x, *qd + h * k3v);
  const Vec6 k4x = *qd + h * k3v;
  *q += h / 6.0 * (k1x + 2 * k2x + 2 * k3x + k4x);
  *qd += h / 6.0 * (k1v + 2 * k2v + 2 * k3v + k4v);
  return *q;
}

struct TrajectoryResult {
  double max_abs = 0.0, final_abs = 0.0, range = 0.0, closure = 0.0, duration = 0.0;
};

// Both models from the same state under the same random torques (see the header).
TrajectoryResult run_trajectory(const PhantomParams& params, const DeviceCrosscheckOptions& o,
                                const PhantomMjcfOptions& mjcf, std::uint64_t seed) {
  TrajectoryResult r;
  const PhantomModelD model(params);
  MujocoPhantom mj(params, mjcf);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double h = mjcf.timestep_s;
  const int substeps = std::max(1, static_cast<int>(std::lround(o.control_dt_s / h)));
  const int ticks = static_cast<int>(std::lround(o.trajectory_s / (substeps * h)));
  Vec6 q = 0.5 * (params.q_min_rad + params.q_max_rad);
  for (int j = 0; j < 6; ++j) {
    q(j) += 0.25 * (2.0 * u(rng) - 1.0) * (params.q_max_rad(j) - params.q_min_rad(j));
  }
  Vec6 qd = Vec6::Zero();
  const Vec6 q0 = q;
  mj.set_state(q, qd);
  const Mat6 M0 = model.M(q);
  for (int k = 0; k < ticks; ++k) {
    // The same random torque for both; each model compensates its own gravity at the tick.
    Vec6 noise;
    for (int j = 0; j < 6; ++j) noise(j) = o.accel_rad_s2 * M0(j, j) * (2.0 * u(rng) - 1.0);
    Vec6 tau_a = noise, tau_m = noise;
    if (o.gravity_compensation) {
      tau_a += model.g(q);
      tau_m += mj.reduced_gravity();
    }
    for (int j = 0; j < 6; ++j) {
      const double lim = params.torque_limit_n_m(j);
      tau_a(j) = std::clamp(tau_a(j), -lim, lim);
      tau_m(j) = std::clamp(tau_m(j), -lim, lim);
    }
    mj.set_torque(tau_m);
    for (int i = 0; i < substeps; ++i) {
      rk4_step(model, &q, &qd, tau_a, h);
      mj.step();
    }
    const double err = (q - mj.q()).cwiseAbs().maxCoeff();
    r.max_abs = std::max(r.max_abs, err);
    r.final_abs = err;
    r.range = std::max(r.range, (q - q0).cwiseAbs().maxCoeff());
    r.closure = std::max(r.closure, mj.closure_error());
  }
  r.duration = ticks * substeps * h;
  return r;
}

}  // namespace

DeviceCrosscheckResult crosscheck_device(const PhantomParams& params,
                                         const DeviceCrosscheckOptions& o) {
  DeviceCrosscheckResult r;
  r.samples = o.samples;
  r.seed = o.seed;
  const PhantomModelD model(params);
  PhantomMjcfOptions mjcf = o.mjcf;
  mjcf.joint_limits = false;  // the analytic model has no joint limits
  MujocoPhantom mj(params, mjcf);
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  auto random_q = [&] {
    Vec6 q;
    for (int j = 0; j < 6; ++j) {
      q(j) = params.q_min_rad(j) + u(rng) * (params.q_max_rad(j) - params.q_min_rad(j));
    }
    return q;
  };
  auto random_qd = [&] {
    Vec6 qd;
    for (int j = 0; j < 6; ++j) qd(j) = o.qd_max_rad_s * (2.0 * u(rng) - 1.0);
    return qd;
  };

  for (int s = 0; s < o.samples; ++s) {
    const Vec6 q = random_q();
    const Vec6 qd = random_qd();
    mj.set_state(q, qd);
    compare(model.M(q), mj.reduced_mass_matrix(), &r.mass_matrix);
    compare(model.bias(q, qd), mj.reduced_bias(), &r.bias);
    compare(model.g(q), mj.reduced_gravity(), &r.gravity);
    Vec3 x1;
    Mat3 R1;
    model.fk(q, &x1, &R1);
    const Pose ref = mj.tip_pose();
    const double pose_abs =
        std::max((x1 - ref.x).cwiseAbs().maxCoeff(), (R1 - ref.R).cwiseAbs().maxCoeff());
    const double pose_ref = std::max(ref.x.cwiseAbs().maxCoeff(), ref.R.cwiseAbs().maxCoeff());
    r.pose.add(pose_abs, pose_ref);
    compare(model.tool_jacobian(q), mj.tip_jacobian(), &r.jacobian);
  }

  // Trajectories: the model as in the file, and with Coulomb friction removed from both (the
  // two implement different friction laws; docs/phantom.md).
  const TrajectoryResult full = run_trajectory(params, o, mjcf, o.seed + 1);
  PhantomParams smooth = params;
  smooth.coulomb_n_m.setZero();
  PhantomMjcfOptions smooth_mjcf = mjcf;
  smooth_mjcf.joint_friction = false;
  const TrajectoryResult rigid = run_trajectory(smooth, o, smooth_mjcf, o.seed + 1);
  r.trajectory_max_abs_rad = rigid.max_abs;
  r.trajectory_final_abs_rad = rigid.final_abs;
  r.trajectory_range_rad = rigid.range;
  r.trajectory_max_closure_rad = rigid.closure;
  r.trajectory_coulomb_max_abs_rad = full.max_abs;
  r.trajectory_coulomb_range_rad = full.range;
  r.trajectory_s = rigid.duration;
  r.timestep_s = mjcf.timestep_s;
  return r;
}
nlohmann::json crosscheck_device_json(const DeviceCrosscheckResult& r) {
  auto q = [](const QuantityError& e) {
    return nlohmann::json{{"max_abs", e.max_abs}, {"max_rel", e.max_rel}, {"max_ref", e.max_ref}};
  };
  return nlohmann::json{
      {"samples", r.samples},
      {"seed", r.seed},
      {"mass_matrix", q(r.mass_matrix)},
      {"bias", q(r.bias)},
      {"gravity", q(r.gravity)},
      {"pose", q(r.pose)},
      {"jacobian", q(r.jacobian)},
      {"trajectory",
       {{"max_abs_rad", r.trajectory_max_abs_rad},
        {"final_abs_rad", r.trajectory_final_abs_rad},
        {"range_rad", r.trajectory_range_rad},
        {"max_closure_rad", r.trajectory_max_closure_rad},
        {"coulomb_max_abs_rad", r.trajectory_coulomb_max_abs_rad},
        {"coulomb_range_rad", r.trajectory_coulomb_range_rad},
        {"duration_s", r.trajectory_s},
        {"timestep_s", r.timestep_s}}},
  };
}

}  // namespace dentsim
