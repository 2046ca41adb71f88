#include "device/safety_chain.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "device/simulated_phantom.h"
#include "reference/core/io.h"

namespace dentsim {

SafetyLimits phantom_safety_limits(const VecX& q_min, const VecX& q_max) {
  SafetyLimits l;
  l.tau_max = phantom_tau_max();
  l.tau_fault = 4.0 * l.tau_max;
  l.tau_rate = 200.0 * l.tau_max;
  l.qd_max = VecX::Constant(6, 20.0);
  l.q_min = q_min;
  l.q_max = q_max;
  l.watchdog_s = 1e-3;
  l.monotonic_time = true;
  l.max_joint_step = 0.1;
  l.max_saturation_s = 2.0;
  return l;
}

namespace {

void check_size(const VecX& v, Eigen::Index n, bool required, const char* field) {
  if ((required || v.size() != 0) && v.size() != n) {
    throw InputError(std::string("safety limits: ") + field + " has " + std::to_string(v.size()) +
                     " entries, expected " + std::to_string(n) + (required ? "" : " or none"));
  }
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    if (std::isnan(v[i])) throw InputError(std::string("safety limits: ") + field + " is NaN");
  }
}

}  // namespace

SafetyChain::SafetyChain(SafetyLimits limits) : limits_(std::move(limits)) {
  const Eigen::Index n = limits_.tau_max.size();
  if (n == 0) throw InputError("safety limits: tau_max is empty, expected one entry per joint");
  check_size(limits_.tau_max, n, true, "tau_max");
  if (limits_.tau_fault.size() == 0) limits_.tau_fault = 4.0 * limits_.tau_max;
  check_size(limits_.tau_fault, n, true, "tau_fault");
  check_size(limits_.tau_rate, n, false, "tau_rate");
  check_size(limits_.qd_max, n, false, "qd_max");
  check_size(limits_.q_min, n, false, "q_min");
  check_size(limits_.q_max, n, false, "q_max");
  if (limits_.q_min.size() != limits_.q_max.size()) {
    throw InputError("safety limits: q_min and q_max must both be given or both be empty");
  }
  if (!(limits_.tau_max.minCoeff() > 0.0)) {
    throw InputError("safety limits: tau_max must be positive on every joint");
  }
  if (!(limits_.ramp_time_s >= 0.0) || !(limits_.watchdog_s >= 0.0) ||
      !(limits_.nominal_period > 0.0) || !(limits_.max_joint_step >= 0.0) ||
      !(limits_.max_saturation_s >= 0.0)) {
    throw InputError(
        "safety limits: ramp_time_s, watchdog_s, max_joint_step, max_saturation_s must be >= 0, "
        "nominal_period > 0");
  }
  tau_prev_ = VecX::Zero(n);
  q_prev_ = VecX::Zero(n);
  saturated_since_ = VecX::Constant(n, -1.0);
}

void SafetyChain::start(double t) {
  faults_ = kFaultNone;
  tau_prev_.setZero();
  saturated_since_.setConstant(-1.0);
  t_start_ = t;
  have_prev_ = false;
}

void SafetyChain::clear_faults(double t) noexcept {
  faults_ = kFaultNone;
  tau_prev_.setZero();
  saturated_since_.setConstant(-1.0);
  t_start_ = t;
}

double SafetyChain::ramp(double t) const {
  if (limits_.ramp_time_s <= 0.0) return 1.0;
  return std::clamp((t - t_start_) / limits_.ramp_time_s, 0.0, 1.0);
}

std::uint32_t SafetyChain::apply(const DeviceSample& s, const VecX& tau_cmd, double tick_exec_s,
                                 const double* motor_temperature, VecX& tau_out) noexcept {
  const Eigen::Index n = tau_prev_.size();
  const double T = have_prev_ && s.t > t_prev_ ? s.t - t_prev_ : limits_.nominal_period;
  const bool had_prev = have_prev_;
  const double t_last = t_prev_;
  t_prev_ = s.t;
  have_prev_ = true;
  std::uint32_t f = kFaultNone;
  if (tau_cmd.size() != n || s.q.size() != n || s.qd.size() != n || tau_out.size() != n) {
    // A size mismatch is a programming error; treat it as a non-finite command (safe stop).
    faults_ |= kFaultNonFiniteTorque;
    if (tau_out.size() == n) tau_out.setZero();
    return faults_;
  }
  // 1. finite check and fault threshold.
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!std::isfinite(tau_cmd[i])) {
      f |= kFaultNonFiniteTorque;
    } else if (std::abs(tau_cmd[i]) > limits_.tau_fault[i]) {
      f |= kFaultTorqueBeyondLimit;
    }
  }
  // 4. guards on the sample and the device's signals.
  if (had_prev && limits_.monotonic_time && !(s.t > t_last)) f |= kFaultNonMonotonicTime;
  // The encoder step is credible per nominal period: a late sample (a callback the scheduler ran
  // late, the arm moving meanwhile) may have moved by as many steps as periods elapsed.
  const double max_step = limits_.max_joint_step * std::max(1.0, T / limits_.nominal_period);
  for (Eigen::Index i = 0; i < n; ++i) {
    if (had_prev && limits_.max_joint_step > 0.0 &&
        !(std::abs(s.q[i] - q_prev_[i]) <= max_step)) {
      f |= kFaultEncoderJump;
    }
    q_prev_[i] = s.q[i];
    if (limits_.qd_max.size() == n && !(std::abs(s.qd[i]) <= limits_.qd_max[i])) {
      f |= kFaultVelocityLimit;
    }
    if (limits_.q_min.size() == n && !(s.q[i] >= limits_.q_min[i] && s.q[i] <= limits_.q_max[i])) {
      f |= kFaultWorkspaceLimit;
    }
    if (motor_temperature != nullptr && !(motor_temperature[i] < limits_.motor_temperature_max)) {
      f |= kFaultMotorTemperature;
    }
  }
  if (limits_.watchdog_s > 0.0 && tick_exec_s > limits_.watchdog_s) f |= kFaultWatchdog;
  if (limits_.max_saturation_s > 0.0) {
    for (Eigen::Index i = 0; i < n; ++i) {
      if (!(std::abs(tau_cmd[i]) >= limits_.tau_max[i] * (1.0 - 1e-12))) {
        saturated_since_[i] = -1.0;
      } else if (saturated_since_[i] < 0.0) {
        saturated_since_[i] = s.t;
      } else if (s.t - saturated_since_[i] > limits_.max_saturation_s) {
        f |= kFaultSustainedSaturation;
      }
    }
  }
  // 5. latch.
  faults_ |= f;
  if (faults_ != kFaultNone) {
    tau_out.setZero();
    tau_prev_.setZero();
    return faults_;
  }
  // 2. rate limit, 3. saturation, 6. ramp-in.
  const double r = ramp(s.t);
  for (Eigen::Index i = 0; i < n; ++i) {
    double u = tau_cmd[i];
    if (limits_.tau_rate.size() == n) {
      const double du = limits_.tau_rate[i] * T;
      u = std::clamp(u, tau_prev_[i] - du, tau_prev_[i] + du);
    }
    u = std::clamp(u, -limits_.tau_max[i], limits_.tau_max[i]);
    tau_prev_[i] = u;
    tau_out[i] = r * u;
  }
  return kFaultNone;
}

}  // namespace dentsim
