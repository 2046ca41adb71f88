// The safety chain (issue #15): one definition for every backend, run on every servo tick between
// the pipeline's torque and the device (docs/design.md "The real-time loop"; libfranka, CHAI3D):
//
//   1. finite check        any tau_cmd,i NaN/inf                      -> non_finite_torque
//      fault threshold     |tau_cmd,i| > tau_fault_i                  -> torque_beyond_limit
//   2. torque rate limit   tau_i = clamp(tau_cmd,i, tau_prev,i -+ rate_i T_k)  (T_k = t_k - t_k-1,
//                          the nominal period on the first tick; tau_prev the last output)
//   3. saturation          tau_i = clamp(tau_i, -tau_max,i, tau_max,i)
//   4. guards              t_k <= t_k-1 (monotonic_time)              -> non_monotonic_time
//                          |q_k,i - q_k-1,i| > max_joint_step x max(1, (t_k - t_k-1) / T_nom)
//                                                                     -> encoder_jump
//                          |qd_i| > qd_max,i                          -> velocity_limit
//                          q_i outside [q_min,i, q_max,i]             -> workspace_limit
//                          watchdog: last tick's execution time > budget -> watchdog
//                          motor temperature_i >= max (warm motors)   -> motor_temperature
//                          |tau_cmd,i| >= tau_max,i on every tick for longer than
//                          max_saturation_s (the motors held at their peak: a hand pushing
//                          harder than the device can render, a blocked proxy)
//                                                                     -> sustained_saturation
//   5. fault latch         any fault: tau = 0 on this tick and every tick until clear_faults()
//   6. ramp-in             tau *= r(t) = min(1, (t - t_start) / ramp_time) after start() and after
//                          clear_faults() (force engages gradually, CHAI3D)
// Units: q [rad], qd [rad/s], tau [N m], rate [N m/s], t [s]; joint order of the device.
// A limit vector left empty disables its guard (rate, velocity, workspace, temperature).
// apply() never allocates (tau_out sized once) and never throws; the constructor validates the
// limits and throws InputError naming the field.
#pragma once

#include <cstdint>

#include "device/device.h"

namespace dentsim {

struct SafetyLimits {
  VecX tau_max;             // [N m] saturation (required)
  VecX tau_fault;           // [N m] fault threshold (empty: 4 tau_max)
  VecX tau_rate;            // [N m/s] largest torque change per second (empty: no rate limit)
  VecX qd_max;              // [rad/s] velocity guard (empty: none)
  VecX q_min, q_max;        // [rad] workspace guard in joint space (empty: none)
  double watchdog_s = 0.0;  // execution-time budget of a tick [s] (0: no watchdog)
  double motor_temperature_max = 0.9;  // normalised 0..1 (device's HD_MOTOR_TEMPERATURE scale)
  double ramp_time_s = 0.5;            // ramp-in duration [s] (0: no ramp)
  // [s] longest time any joint's command may stay at or beyond its saturation (0: no guard).
  double max_saturation_s = 0.0;
  double nominal_period = 1e-3;        // T of the first tick [s]
  // The sample's own guards: a clock that does not advance (a frozen or backwards device clock,
  // the same sample repeated) and an encoder that jumps (a lost frame, a cable fault).
  bool monotonic_time = false;  // t_k <= t_k-1 is a fault
  // [rad] |q_k - q_k-1| beyond it on any joint, per nominal period elapsed (a late sample may have
  // moved by that many steps); 0: no guard
  double max_joint_step = 0.0;
};

// Defaults for the Phantom Premium 1.5/6DoF: tau_max = phantom_tau_max(), rate 200 tau_max per s
// (full scale in 5 ms), qd_max 20 rad/s per joint (the hardware trips HD_EXCEEDED_MAX_VELOCITY
// beyond; unpublished, an assumption), workspace = joint ranges (`q_min`, `q_max`), watchdog 1 ms,
// monotonic time, encoder jumps beyond 0.1 rad per tick, saturation held at most 2 s (the motors'
// peak torque is for short contacts; their continuous rating is about a third of it).
SafetyLimits phantom_safety_limits(const VecX& q_min, const VecX& q_max);

class SafetyChain {
 public:
  explicit SafetyChain(SafetyLimits limits);

  // Arms the chain at time t: no fault, previous torque 0, ramp starts.
  void start(double t);
  // One tick. `s` the sample the command was computed from, `tick_exec_s` the execution time of
  // the previous tick (watchdog input; negative: not measured), `motor_temperature` the device's
  // normalised temperatures (nullptr: not reported). Writes the torque to send into tau_out and
  // returns the latched faults (kFaultNone: tau_out is the conditioned command).
  std::uint32_t apply(const DeviceSample& s, const VecX& tau_cmd, double tick_exec_s,
                      const double* motor_temperature, VecX& tau_out) noexcept;
  // Latches external faults (e.g. the device's own) so the chain outputs zero torque.
  void latch(std::uint32_t faults) noexcept { faults_ |= faults; }
  // Clears the latch at time t; the ramp-in restarts there.
  void clear_faults(double t) noexcept;

  std::uint32_t faults() const { return faults_; }
  const SafetyLimits& limits() const { return limits_; }
  double ramp(double t) const;  // r(t) in [0, 1]

 private:
  SafetyLimits limits_;
  VecX tau_prev_, q_prev_;
  VecX saturated_since_;  // per joint: time its command reached saturation (-1: not saturated)
  double t_prev_ = 0.0, t_start_ = 0.0;
  bool have_prev_ = false;
  std::uint32_t faults_ = kFaultNone;
};

}  // namespace dentsim
