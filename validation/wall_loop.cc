#include "validation/wall_loop.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "reference/core/so3.h"

namespace dentsim {

namespace {

// Continuous-time state of the simulated rigid-body device.
struct BodyState {
  Vec3 x;
  Mat3 R;
  Vec3 v;  // world
  Vec3 w;  // body
};

struct Deriv {
  Vec3 xd, th_d, vd, wd;
};

}  // namespace

WallLoopResult run_wall_loop(const WallLoopConfig& cfg,
                             const std::function<void(const WallLoopRecord&)>& on_tick) {
  const RigidBodyDevice model(cfg.device);
  ReferencePipeline pipeline(model, cfg.pipeline);
  HalfSpaceWall wall(cfg.wall_point, cfg.wall_normal, cfg.tip_radius, cfg.wall_stiffness,
                     cfg.wall_damping);
  const Vec3 n = wall.normal();
  const RigidBodyDeviceParams& dp = cfg.device;
  const Mat3 Jinv = dp.inertia.inverse();
  const Mat3 R_ref = Mat3::Identity();

  BodyState s{cfg.start, Mat3::Identity(), Vec3::Zero(), Vec3::Zero()};
  auto sample_of = [&](const BodyState& b, double t) {
    DeviceSample smp;
    smp.q = model.joint_position(Pose{b.x, b.R});
    smp.qd = model.joint_velocity(smp.q, stack(b.v, b.w));
    smp.t = t;
    return smp;
  };

  const WallHand& h = cfg.hand;
  auto hand_wrench = [&](const BodyState& b, double t) {
    const double along = std::min(h.speed * t, h.travel);
    const Vec3 x_ref = h.x_start + along * h.direction.normalized();
    const double ramp = h.push_ramp_s > 0.0 ? std::min(1.0, t / h.push_ramp_s) : 1.0;
    const Vec3 f = h.stiffness * (x_ref - b.x) - h.damping * b.v + ramp * h.push;
    const Vec3 tau = -h.stiffness_ang * log_so3(R_ref.transpose() * b.R) - h.damping_ang * b.w;
    return stack(f, tau);
  };

  // Wrench on the device from the motors (joint torque held), the hand and joint friction.
  auto dynamics = [&](const BodyState& b, double t, const VecX& tau, Vec6* motor) {
    const DeviceSample smp = sample_of(b, t);
    const Mat6 J1 = model.twist_to_joint(smp.q);
    const Vec6 T_motor = J1.transpose() * tau;
    const Vec6 T_fric = -(J1.transpose() * model.friction_torque(smp.q, smp.qd));
    const Vec6 T_hand = hand_wrench(b, t);
    Vec6 F = T_motor + T_fric + T_hand;
    F(2) -= dp.mass * dp.gravity;
    if (motor) *motor = T_motor;
    Deriv d;
    d.xd = b.v;
    d.th_d = b.w;  // integrated as R = R0 exp(S(theta)); theta small within a substep
    d.vd = F.head<3>() / dp.mass;
    d.wd = Jinv * (Vec3(F.tail<3>()) - b.w.cross(dp.inertia * b.w));
    return d;
  };
  auto advance = [](const BodyState& b0, const Deriv& d, double dt) {
    BodyState b = b0;
    b.x += dt * d.xd;
    b.R = b0.R * exp_so3(dt * d.th_d);
    b.v += dt * d.vd;
    b.w += dt * d.wd;
    return b;
  };

  WallLoopResult res;
  const long n_ticks = static_cast<long>(std::llround(cfg.duration / cfg.tick));
  const int sub = std::max(1, cfg.substeps);
  const double dt = cfg.tick / sub;
  const long tail_start = n_ticks - std::max(1L, n_ticks / 10);
  double tail_force = 0.0, tail_depth = 0.0;
  long tail_n = 0;

  double t = 0.0;
  pipeline.reset(sample_of(s, t));
  for (long k = 0; k < n_ticks; ++k) {
    const TickResult& r = pipeline.tick(sample_of(s, t), cfg.tick, wall);
    const VecX tau = r.tau;
    // Continuous device over the tick with the torque held (ZOH): RK4 substeps.
    for (int i = 0; i < sub; ++i) {
      Vec6 m0, m1;
      const Deriv k1 = dynamics(s, t, tau, &m0);
      const Deriv k2 = dynamics(advance(s, k1, dt / 2), t + dt / 2, tau, nullptr);
      const Deriv k3 = dynamics(advance(s, k2, dt / 2), t + dt / 2, tau, nullptr);
      const Deriv k4 = dynamics(advance(s, k3, dt), t + dt, tau, nullptr);
      Deriv d;
      d.xd = (k1.xd + 2 * k2.xd + 2 * k3.xd + k4.xd) / 6;
      d.th_d = (k1.th_d + 2 * k2.th_d + 2 * k3.th_d + k4.th_d) / 6;
      d.vd = (k1.vd + 2 * k2.vd + 2 * k3.vd + k4.vd) / 6;
      d.wd = (k1.wd + 2 * k2.wd + 2 * k3.wd + k4.wd) / 6;
      const Vec6 V0 = stack(s.v, s.w);
      s = advance(s, d, dt);
      t += dt;
      dynamics(s, t, tau, &m1);
      const Vec6 V1 = stack(s.v, s.w);
      res.energy_virtual_j += 0.5 * dt * (V0.dot(m0) + V1.dot(m1));  // trapezoid on V1^T T1
    }
    ++res.ticks;
    if (!s.x.allFinite() || !s.v.allFinite() || !s.R.allFinite() ||
        !pipeline.proxy().pose.x.allFinite()) {
      res.finite = false;
      break;
    }
    const double force = std::max(0.0, n.dot(Vec3(r.T1.head<3>())));
    const double ddepth = std::max(0.0, wall.depth(s.x));
    const double pdepth = std::max(0.0, wall.depth(pipeline.proxy().pose.x));
    if (!r.contacts.empty()) ++res.contact_ticks;
    res.max_force_n = std::max(res.max_force_n, force);
    res.max_device_depth_m = std::max(res.max_device_depth_m, ddepth);
    res.max_proxy_depth_m = std::max(res.max_proxy_depth_m, pdepth);
    res.max_energy_virtual_j = std::max(res.max_energy_virtual_j, res.energy_virtual_j);
    if (k >= tail_start) {
      tail_force += force;
      tail_depth += ddepth;
      ++tail_n;
    }
    if (on_tick) {
      const Vec6 Fh = hand_wrench(s, t);
      on_tick(WallLoopRecord{t, force, ddepth, pdepth, res.energy_virtual_j,
                             -n.dot(Vec3(Fh.head<3>()))});
    }
  }
  if (tail_n > 0) {
    res.final_force_n = tail_force / tail_n;
    res.final_device_depth_m = tail_depth / tail_n;
  }
  return res;
}

}  // namespace dentsim
