#include "validation/zwidth_1dof.h"

#include <cmath>
#include <string>

#include "reference/core/io.h"

namespace dentsim {

namespace {

void require(bool ok, const std::string& field, const std::string& expected, double got) {
  if (!ok) {
    throw InputError("AxisDeviceParams." + field + ": expected " + expected + ", got " +
                     std::to_string(got));
  }
}

}  // namespace

AxisDevice::AxisDevice(AxisDeviceParams params, const Vec3& start)
    : p_(params), start_(start), vel_(6, params.velocity), rng_(params.seed) {
  require(std::isfinite(p_.mass) && p_.mass > 0.0, "mass", "> 0 kg", p_.mass);
  require(std::isfinite(p_.damping) && p_.damping >= 0.0, "damping", ">= 0 N s/m", p_.damping);
  require(std::isfinite(p_.coulomb) && p_.coulomb >= 0.0, "coulomb", ">= 0 N", p_.coulomb);
  require(p_.coulomb_velocity > 0.0, "coulomb_velocity", "> 0 m/s", p_.coulomb_velocity);
  require(std::isfinite(p_.force_limit) && p_.force_limit > 0.0, "force_limit", "> 0 N",
          p_.force_limit);
  require(std::isfinite(p_.quantum) && p_.quantum >= 0.0, "quantum", ">= 0 m", p_.quantum);
  require(std::isfinite(p_.period) && p_.period > 0.0, "period", "> 0 s", p_.period);
  require(p_.jitter_half_width >= 0.0 && p_.jitter_half_width < p_.period, "jitter_half_width",
          "in [0, period)", p_.jitter_half_width);
  require(p_.substeps >= 1, "substeps", ">= 1", p_.substeps);
  require(start.allFinite(), "start", "finite", start.norm());

  caps_.dof = 6;
  caps_.measures_velocity = false;
  caps_.has_force_sensor = false;
  caps_.simulated = true;
  caps_.nominal_period = p_.period;
  caps_.velocity_lowpass_hz =
      p_.velocity.filter == VelocityFilter::kFirstOrderLowPass ? p_.velocity.cutoff_hz : 0.0;
  caps_.encoder_quantum = VecX::Zero(6);
  caps_.encoder_quantum(2) = p_.quantum;
  limits_.tau_max = VecX::Constant(6, p_.force_limit);
  limits_.tau_fault = VecX::Constant(6, 4.0 * p_.force_limit);
  limits_.max_joint_step = 1.0;  // [m] per tick: a jump beyond this is not physical here
  tau_applied_ = VecX::Zero(6);
  q_meas_ = VecX::Zero(6);
  z_ = start.z();
  sample_encoders();
  vel_.reset(q_meas_, 0.0, VecX::Zero(6));
}

void AxisDevice::sample_encoders() {
  q_meas_.head<3>() = start_;
  q_meas_.tail<3>().setZero();
  q_meas_(2) = p_.quantum > 0.0 ? p_.quantum * std::floor(z_ / p_.quantum) : z_;
}

void AxisDevice::read(DeviceSample& out) const {
  out.q = q_meas_;
  out.qd = vel_.estimate();
  out.t = t_;
}

void AxisDevice::write(const VecX& tau) {
  VecX tau_z = VecX::Zero(6);
  if (tau.size() == 6) tau_z(2) = tau(2);  // the constrained coordinates take the rest
  faults_ |= condition_command(tau.size() == 6 ? tau_z : tau, limits_, true, tau_applied_);
  if (faults_ != kFaultNone) tau_applied_.setZero();
}

double AxisDevice::accel(double z, double v, double t) const {
  double f = tau_applied_(2) - p_.damping * v - p_.coulomb * std::tanh(v / p_.coulomb_velocity);
  double m = p_.mass;
  if (hand_ != nullptr) {
    Pose tip;
    tip.x = Vec3(start_.x(), start_.y(), z);
    Vec6 V = Vec6::Zero();
    V(2) = v;
    f += hand_->wrench(tip, V, t)(2);
    m += hand_->impedance().mass;
  }
  return f / m;
}

void AxisDevice::advance() {
  double T = p_.period;
  if (p_.jitter_half_width > 0.0) {
    std::uniform_real_distribution<double> u(p_.period - p_.jitter_half_width,
                                             p_.period + p_.jitter_half_width);
    T = u(rng_);
  }
  // RK4 on (z, v) with the force held over the tick.
  const double h = T / p_.substeps;
  for (int i = 0; i < p_.substeps; ++i) {
    const double t0 = t_ + i * h;
    const double z1 = z_, v1 = v_, a1 = accel(z1, v1, t0);
    const double z2 = z_ + 0.5 * h * v1, v2 = v_ + 0.5 * h * a1, a2 = accel(z2, v2, t0 + 0.5 * h);
    const double z3 = z_ + 0.5 * h * v2, v3 = v_ + 0.5 * h * a2, a3 = accel(z3, v3, t0 + 0.5 * h);
    const double z4 = z_ + h * v3, v4 = v_ + h * a3, a4 = accel(z4, v4, t0 + h);
    z_ += h / 6.0 * (v1 + 2.0 * v2 + 2.0 * v3 + v4);
    v_ += h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
  }
  t_ += T;
  const VecX q_prev = q_meas_;
  sample_encoders();
  faults_ |= check_sample(q_prev, t_ - T, q_meas_, t_, limits_);
  vel_.update(q_meas_, t_);
}

Pose AxisDevice::tip_pose() const {
  Pose p;
  p.x = Vec3(start_.x(), start_.y(), z_);
  return p;
}

RigidBodyDeviceParams axis_device_model_params(double mass, double damping) {
  RigidBodyDeviceParams p;
  p.mass = mass;
  p.damping_lin = damping;
  return p;
}

}  // namespace dentsim
