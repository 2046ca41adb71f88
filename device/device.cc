#include "device/device.h"

#include <algorithm>
#include <cmath>

#include "reference/core/io.h"

namespace dentsim {

const char* fault_name(DeviceFault f) {
  switch (f) {
    case kFaultNone:
      return "none";
    case kFaultNonFiniteTorque:
      return "non_finite_torque";
    case kFaultTorqueBeyondLimit:
      return "torque_beyond_limit";
    case kFaultNonMonotonicTime:
      return "non_monotonic_time";
    case kFaultEncoderJump:
      return "encoder_jump";
    case kFaultVelocityLimit:
      return "velocity_limit";
    case kFaultWorkspaceLimit:
      return "workspace_limit";
    case kFaultWatchdog:
      return "watchdog";
    case kFaultMotorTemperature:
      return "motor_temperature";
    case kFaultSchedulerStopped:
      return "scheduler_stopped";
    case kFaultSustainedSaturation:
      return "sustained_saturation";
    case kFaultHdUnknownError:
      return "hd_unknown_error";
    case kFaultHdInvalidEnum:
      return "hd_invalid_enum";
    case kFaultHdInvalidValue:
      return "hd_invalid_value";
    case kFaultHdInvalidOperation:
      return "hd_invalid_operation";
    case kFaultHdInvalidInputType:
      return "hd_invalid_input_type";
    case kFaultHdBadHandle:
      return "hd_bad_handle";
    case kFaultHdWarmMotors:
      return "hd_warm_motors";
    case kFaultHdExceededMaxForce:
      return "hd_exceeded_max_force";
    case kFaultHdExceededMaxForceImpulse:
      return "hd_exceeded_max_force_impulse";
    case kFaultHdExceededMaxVelocity:
      return "hd_exceeded_max_velocity";
    case kFaultHdForceError:
      return "hd_force_error";
    case kFaultHdDeviceFault:
      return "hd_device_fault";
    case kFaultHdDeviceAlreadyInitiated:
      return "hd_device_already_initiated";
    case kFaultHdCommError:
      return "hd_comm_error";
    case kFaultHdCommConfigError:
      return "hd_comm_config_error";
    case kFaultHdTimerError:
      return "hd_timer_error";
    case kFaultHdIllegalBegin:
      return "hd_illegal_begin";
    case kFaultHdIllegalEnd:
      return "hd_illegal_end";
    case kFaultHdFrameError:
      return "hd_frame_error";
    case kFaultHdInvalidPriority:
      return "hd_invalid_priority";
    case kFaultHdSchedulerFull:
      return "hd_scheduler_full";
    case kFaultHdInvalidLicense:
      return "hd_invalid_license";
  }
  return "unknown";
}

std::string fault_string(std::uint32_t faults) {
  if (faults == kFaultNone) return "none";
  std::string s;
  for (std::uint32_t bit = 1; bit != 0; bit <<= 1) {
    if ((faults & bit) == 0) continue;
    if (!s.empty()) s += ",";
    s += fault_name(static_cast<DeviceFault>(bit));
  }
  return s;
}

std::uint32_t condition_command(const VecX& tau_cmd, const DeviceLimits& limits, bool saturate,
                                VecX& tau_out) {
  const Eigen::Index n = tau_cmd.size();
  if (limits.tau_max.size() != n || limits.tau_fault.size() != n) {
    throw InputError("device command: torque has " + std::to_string(n) +
                     " entries, limits tau_max/tau_fault have " +
                     std::to_string(limits.tau_max.size()) + "/" +
                     std::to_string(limits.tau_fault.size()) + "; expected equal sizes");
  }
  if (tau_out.size() != n) tau_out.resize(n);
  std::uint32_t faults = kFaultNone;
  for (Eigen::Index i = 0; i < n; ++i) {
    const double u = tau_cmd[i];
    if (!std::isfinite(u)) {
      faults |= kFaultNonFiniteTorque;
    } else if (std::abs(u) > limits.tau_fault[i]) {
      faults |= kFaultTorqueBeyondLimit;
    }
  }
  if (faults != kFaultNone) {
    tau_out.setZero();  // safe stop
    return faults;
  }
  for (Eigen::Index i = 0; i < n; ++i) {
    const double u = tau_cmd[i];
    const double lim = limits.tau_max[i];
    tau_out[i] = saturate ? std::clamp(u, -lim, lim) : u;
  }
  return kFaultNone;
}

std::uint32_t check_sample(const VecX& q_prev, double t_prev, const VecX& q, double t,
                           const DeviceLimits& limits, double nominal_period) {
  std::uint32_t faults = kFaultNone;
  if (!(t > t_prev)) faults |= kFaultNonMonotonicTime;
  const double periods =
      nominal_period > 0.0 && t > t_prev ? std::max(1.0, (t - t_prev) / nominal_period) : 1.0;
  const double max_step = limits.max_joint_step * periods;
  for (Eigen::Index i = 0; i < q.size(); ++i) {
    if (!(std::abs(q[i] - q_prev[i]) <= max_step)) faults |= kFaultEncoderJump;
  }
  return faults;
}

ObserverInput matched_observer_input(const DeviceCapabilities& caps) {
  ObserverInput in;
  if (caps.measures_velocity) return in;
  in.match_backward_difference = true;
  in.lowpass_hz = caps.velocity_lowpass_hz;
  return in;
}

}  // namespace dentsim
