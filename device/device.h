// The haptic-device interface of dentsim (issue #3): what every backend (the MuJoCo-simulated
// Phantom, the OpenHaptics backend, log replay) implements and what the servo loop talks to.
//
// One servo tick, as on hardware (docs/design.md "One servo tick"):
//     device.read(sample);        // q [rad], qd [rad/s] (estimated), t [s] at the start of tick k
//     ... pipeline computes tau ...
//     device.write(tau);          // joint torques [N m], held (zero-order hold) over tick k
//     device.advance();           // the device runs tick k (length T_k); a real backend waits
//
// Units: SI. q and tau are in the device's joint coordinates (for the Phantom: q1 base yaw, q2
// upper-arm elevation, q3 absolute forearm angle, q4..q6 gimbal), index 1 = device.
//
// Command chain (docs/design.md "The real-time loop"): finite check -> fault threshold
// -> saturation to the device limits. A fault (non-finite torque, torque beyond the fault
// threshold, non-monotonic time, encoder jump) latches a named flag and brings the device to a
// safe stop: zero torque until clear_faults(). Nothing in read/write/advance allocates once the
// sample has been sized with make_sample().
#pragma once

#include <cstdint>
#include <string>

#include "reference/core/device_model.h"
#include "reference/core/types.h"
#include "reference/observer.h"

namespace dentsim {

// DeviceSample (q, qd, t) is shared with the pipeline: reference/core/device_model.h.

// Latched fault flags (bit set). A set flag means the device is in safe stop (zero torque).
enum DeviceFault : std::uint32_t {
  kFaultNone = 0,
  kFaultNonFiniteTorque = 1u << 0,    // a commanded torque was NaN or infinite
  kFaultTorqueBeyondLimit = 1u << 1,  // |tau_cmd_i| > tau_fault_i
  kFaultNonMonotonicTime = 1u << 2,   // sample time did not increase (t_k <= t_k-1)
  kFaultEncoderJump = 1u << 3,        // |q_k - q_k-1| > max_joint_step on some joint
  // The safety chain (device/safety_chain.h).
  kFaultVelocityLimit = 1u << 4,         // |qd_i| > qd_max_i
  kFaultWorkspaceLimit = 1u << 5,        // q_i outside [q_min_i, q_max_i]
  kFaultWatchdog = 1u << 6,              // a tick did not finish within its time budget
  kFaultMotorTemperature = 1u << 7,      // the device reported a motor at or above its limit
  kFaultSchedulerStopped = 1u << 8,      // the device's clock stopped calling the servo tick
  kFaultSustainedSaturation = 1u << 10,  // a joint held at its torque limit longer than allowed
  // Errors of the OpenHaptics HDAPI (device/hdapi/): one flag per HD error code, named after the
  // code in lower case (HD_COMM_ERROR -> "hd_comm_error"); hd_fault_for_error() maps a code.
  kFaultHdUnknownError = 1u << 9,  // an HD error code not in the list below
  kFaultHdInvalidEnum = 1u << 11,
  kFaultHdInvalidValue = 1u << 12,
  kFaultHdInvalidOperation = 1u << 13,
  kFaultHdInvalidInputType = 1u << 14,
  kFaultHdBadHandle = 1u << 15,
  kFaultHdWarmMotors = 1u << 16,
  kFaultHdExceededMaxForce = 1u << 17,
  kFaultHdExceededMaxForceImpulse = 1u << 18,
  kFaultHdExceededMaxVelocity = 1u << 19,
  kFaultHdForceError = 1u << 20,
  kFaultHdDeviceFault = 1u << 21,
  kFaultHdDeviceAlreadyInitiated = 1u << 22,
  kFaultHdCommError = 1u << 23,
  kFaultHdCommConfigError = 1u << 24,
  kFaultHdTimerError = 1u << 25,
  kFaultHdIllegalBegin = 1u << 26,
  kFaultHdIllegalEnd = 1u << 27,
  kFaultHdFrameError = 1u << 28,
  kFaultHdInvalidPriority = 1u << 29,
  kFaultHdSchedulerFull = 1u << 30,
  kFaultHdInvalidLicense = 1u << 31,
};

// Name of one flag ("non_finite_torque", "hd_comm_error", ...); "none" for kFaultNone, "unknown"
// otherwise.
const char* fault_name(DeviceFault f);
// All set flags, comma separated ("none" when no flag is set).
std::string fault_string(std::uint32_t faults);

// Limits of a device, per joint.
struct DeviceLimits {
  VecX tau_max;    // saturation [N m]: the torque applied is clipped to [-tau_max, tau_max]
  VecX tau_fault;  // fault threshold [N m]: |tau_cmd| > tau_fault is a fault (safe stop)
  double max_joint_step = 0.1;  // [rad] largest credible encoder change in one tick
};

// What a device can do and report.
struct DeviceCapabilities {
  int dof = 0;
  bool measures_velocity = false;  // false: qd is differentiated from q by the driver
  bool has_force_sensor = false;
  bool simulated = false;
  double nominal_period = 1e-3;  // nominal servo tick [s]
  VecX encoder_quantum;          // joint-angle resolution [rad] (0 = not quantised)
  // When measures_velocity is false: the driver's qd is the backward difference of the angles,
  // low-passed (first order) at this cut-off [Hz]; 0 = no low-pass (device/velocity_estimator.h).
  double velocity_lowpass_hz = 0.0;
};

// The momentum observer's input matched to this device's velocity estimate
// (reference/observer.h "Input matched to the velocity estimate"): a backward difference pairs
// with the torque averaged over the two ticks it spans, and the driver's low-pass is applied to
// the torque as well. A device that measures velocity gets the unmatched (thesis) input.
ObserverInput matched_observer_input(const DeviceCapabilities& caps);

class Device {
 public:
  virtual ~Device() = default;
  virtual const DeviceCapabilities& capabilities() const = 0;
  virtual const DeviceLimits& limits() const = 0;
  int dof() const { return capabilities().dof; }

  // Writes the latest sample into `out` (sized by make_sample(): no allocation).
  virtual void read(DeviceSample& out) const = 0;
  // Commands joint torques [N m] for the next tick; they pass the command chain and are held.
  virtual void write(const VecX& tau) = 0;
  // Runs one servo tick.
  virtual void advance() = 0;
  // The torque actually applied over the last (or next) tick, after the command chain [N m].
  virtual const VecX& applied_torque() const = 0;

  virtual std::uint32_t faults() const = 0;
  virtual void clear_faults() = 0;

  // A sample sized for this device (allocate once, before the loop).
  DeviceSample make_sample() const {
    DeviceSample s;
    s.q = VecX::Zero(dof());
    s.qd = VecX::Zero(dof());
    return s;
  }
};

// The command chain shared by all backends: finite check -> fault threshold -> saturation
// (when `saturate`). Writes the torque to apply into `tau_out` (same size as tau_cmd; zero on a
// fault) and returns the fault flags found (kFaultNone if the command is acceptable). Throws
// InputError if the sizes of tau_cmd and the limits differ. Does not allocate when tau_out has the
// right size.
std::uint32_t condition_command(const VecX& tau_cmd, const DeviceLimits& limits, bool saturate,
                                VecX& tau_out);

// Faults visible in a new sample given the previous one: non-monotonic time and encoder jumps.
// With nominal_period > 0 the encoder step allowed is max_joint_step per nominal period elapsed
// (at least one): a late sample (a callback the scheduler ran late, the arm moving meanwhile) may
// have moved by that many steps (issue #33).
std::uint32_t check_sample(const VecX& q_prev, double t_prev, const VecX& q, double t,
                           const DeviceLimits& limits, double nominal_period = 0.0);

}  // namespace dentsim
