#include "validation/wall_loop.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <utility>

#include "device/closed_loop.h"
#include "device/device.h"
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

// The ideal rigid-body device as a Device: the torque written is held over the tick (ZOH) and
// the body is integrated with RK4 substeps under the motors, the hand and joint friction. It
// keeps the motor-port energy E_v = ∫ V1^T T_motor dt (trapezoid per substep).
class RigidBodyPlant : public Device {
 public:
  RigidBodyPlant(const WallLoopConfig& cfg, const RigidBodyDevice& model, HandWrenchFn hand)
      : cfg_(cfg),
        model_(model),
        hand_(std::move(hand)),
        s_{cfg.start, Mat3::Identity(), Vec3::Zero(), Vec3::Zero()} {
    caps_.dof = 6;
    caps_.measures_velocity = true;
    caps_.simulated = true;
    caps_.nominal_period = cfg.tick;
    caps_.encoder_quantum = VecX::Zero(6);
    tau_ = VecX::Zero(6);
  }
  const DeviceCapabilities& capabilities() const override { return caps_; }
  const DeviceLimits& limits() const override { return limits_; }
  void read(DeviceSample& out) const override {
    out.q = model_.joint_position(Pose{s_.x, s_.R});
    out.qd = model_.joint_velocity(out.q, stack(s_.v, s_.w));
    out.t = t_;
  }
  void write(const VecX& tau) override { tau_ = tau; }
  const VecX& applied_torque() const override { return tau_; }
  std::uint32_t faults() const override { return kFaultNone; }
  void clear_faults() override {}

  void advance() override {
    // Continuous device over the tick with the torque held (ZOH): RK4 substeps.
    const int sub = std::max(1, cfg_.substeps);
    const double dt = cfg_.tick / sub;
    for (int i = 0; i < sub; ++i) {
      Vec6 m0, m1;
      const Deriv k1 = dynamics(s_, t_, &m0);
      const Deriv k2 = dynamics(step(s_, k1, dt / 2), t_ + dt / 2, nullptr);
      const Deriv k3 = dynamics(step(s_, k2, dt / 2), t_ + dt / 2, nullptr);
      const Deriv k4 = dynamics(step(s_, k3, dt), t_ + dt, nullptr);
      Deriv d;
      d.xd = (k1.xd + 2 * k2.xd + 2 * k3.xd + k4.xd) / 6;
      d.th_d = (k1.th_d + 2 * k2.th_d + 2 * k3.th_d + k4.th_d) / 6;
      d.vd = (k1.vd + 2 * k2.vd + 2 * k3.vd + k4.vd) / 6;
      d.wd = (k1.wd + 2 * k2.wd + 2 * k3.wd + k4.wd) / 6;
      const Vec6 V0 = stack(s_.v, s_.w);
      s_ = step(s_, d, dt);
      t_ += dt;
      dynamics(s_, t_, &m1);
      const Vec6 V1 = stack(s_.v, s_.w);
      energy_ += 0.5 * dt * (V0.dot(m0) + V1.dot(m1));  // trapezoid on V1^T T1
    }
  }

  const BodyState& state() const { return s_; }
  double time() const { return t_; }
  double energy() const { return energy_; }
  bool finite() const {
    return s_.x.allFinite() && s_.v.allFinite() && s_.R.allFinite() && s_.w.allFinite();
  }
  Vec6 hand_wrench(const BodyState& b, double t) const { return hand_(t, b.x, b.R, b.v, b.w); }

 private:
  // Wrench on the device from the motors (joint torque held), the hand and joint friction.
  Deriv dynamics(const BodyState& b, double t, Vec6* motor) const {
    const RigidBodyDeviceParams& dp = cfg_.device;
    const VecX q = model_.joint_position(Pose{b.x, b.R});
    const VecX qd = model_.joint_velocity(q, stack(b.v, b.w));
    const Mat6 J1 = model_.twist_to_joint(q);
    const Vec6 T_motor = J1.transpose() * tau_;
    const Vec6 T_fric = -(J1.transpose() * model_.friction_torque(q, qd));
    const Vec6 T_hand = hand_wrench(b, t);
    Vec6 F = T_motor + T_fric + T_hand;
    F(2) -= dp.mass * dp.gravity;
    if (motor) *motor = T_motor;
    Deriv d;
    d.xd = b.v;
    d.th_d = b.w;  // integrated as R = R0 exp(S(theta)); theta small within a substep
    d.vd = F.head<3>() / dp.mass;
    d.wd = dp.inertia.inverse() * (Vec3(F.tail<3>()) - b.w.cross(dp.inertia * b.w));
    return d;
  }
  static BodyState step(const BodyState& b0, const Deriv& d, double dt) {
    BodyState b = b0;
    b.x += dt * d.xd;
    b.R = b0.R * exp_so3(dt * d.th_d);
    b.v += dt * d.vd;
    b.w += dt * d.wd;
    return b;
  }

  const WallLoopConfig& cfg_;
  const RigidBodyDevice& model_;
  HandWrenchFn hand_;
  DeviceCapabilities caps_;
  DeviceLimits limits_;
  BodyState s_;
  double t_ = 0.0;
  double energy_ = 0.0;
  VecX tau_;
};

// The scripted hand of WallHand: spring-damper to the moving reference plus the ramped push.
Vec6 wall_hand_wrench(const WallHand& h, double t, const Vec3& x, const Mat3& R, const Vec3& v,
                      const Vec3& w) {
  const double along = std::min(h.speed * t, h.travel);
  const Vec3 x_ref = h.x_start + along * h.direction.normalized();
  const double ramp = h.push_ramp_s > 0.0 ? std::min(1.0, t / h.push_ramp_s) : 1.0;
  const Vec3 f = h.stiffness * (x_ref - x) - h.damping * v + ramp * h.push;
  const Vec3 tau = -h.stiffness_ang * log_so3(R) - h.damping_ang * w;  // R_ref = I
  return stack(f, tau);
}

}  // namespace

bool run_provider_loop(const WallLoopConfig& cfg, ContactProvider& provider,
                       const HandWrenchFn& hand,
                       const std::function<void(const ProviderLoopRecord&)>& on_tick) {
  const RigidBodyDevice model(cfg.device);
  ReferencePipeline pipeline(model, cfg.pipeline);
  RigidBodyPlant plant(cfg, model, hand);
  ClosedLoop loop(plant, pipeline, provider);
  loop.use_nominal_period(true);
  const long n_ticks = static_cast<long>(std::llround(cfg.duration / cfg.tick));
  loop.start();
  for (long k = 0; k < n_ticks; ++k) {
    const TickResult& r = loop.step();
    if (loop.faulted() || !plant.finite() || !pipeline.proxy().pose.x.allFinite()) return false;
    if (on_tick) {
      on_tick(ProviderLoopRecord{plant.time(), plant.state().x, Vec3(r.T1.head<3>()),
                                 pipeline.proxy().pose.x, &r});
    }
  }
  return true;
}

WallLoopResult run_wall_loop(const WallLoopConfig& cfg,
                             const std::function<void(const WallLoopRecord&)>& on_tick) {
  const RigidBodyDevice model(cfg.device);
  ReferencePipeline pipeline(model, cfg.pipeline);
  HalfSpaceWall wall(cfg.wall_point, cfg.wall_normal, cfg.tip_radius, cfg.wall_stiffness,
                     cfg.wall_damping);
  const Vec3 n = wall.normal();
  RigidBodyPlant plant(cfg, model,
                       [&cfg](double t, const Vec3& x, const Mat3& R, const Vec3& v, const Vec3& w) {
                         return wall_hand_wrench(cfg.hand, t, x, R, v, w);
                       });
  ClosedLoop loop(plant, pipeline, wall);
  loop.use_nominal_period(true);  // the ideal device's tick is exactly cfg.tick

  WallLoopResult res;
  const long n_ticks = static_cast<long>(std::llround(cfg.duration / cfg.tick));
  const long tail_start = n_ticks - std::max(1L, n_ticks / 10);
  double tail_force = 0.0, tail_depth = 0.0;
  long tail_n = 0;

  loop.start();
  for (long k = 0; k < n_ticks; ++k) {
    const TickResult& r = loop.step();
    res.energy_virtual_j = plant.energy();
    ++res.ticks;
    if (loop.faulted() || !plant.finite() || !pipeline.proxy().pose.x.allFinite()) {
      res.finite = false;
      break;
    }
    const BodyState& s = plant.state();
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
      const Vec6 Fh = plant.hand_wrench(s, plant.time());
      on_tick(WallLoopRecord{plant.time(), force, ddepth, pdepth, res.energy_virtual_j,
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
