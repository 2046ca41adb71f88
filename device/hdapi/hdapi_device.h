// The OpenHaptics backend (issue #15): a Device (device.h) driving a Phantom through the vendor's
// HDAPI library, loaded at run time (hdapi_library.h), or through any library exporting the same
// C symbols with the documented behaviour (the project's emulator, libdentsim_hd_emulator.so).
//
// Start-up (docs/device_facts.md §5): hdInitDevice(HD_DEFAULT_DEVICE), retried with the
// name "Default PHANToM" (some installs need it) -> HD error and handle checked ->
// hdMakeCurrentDevice -> device queries (model, serial, DoF, update rate, nominal limits) ->
// hdEnable(HD_FORCE_OUTPUT) -> hdScheduleAsynchronous(servo callback, HD_MAX_SCHEDULER_PRIORITY)
// -> hdSetSchedulerRate(rate) -> hdStartScheduler. A failing step throws HdapiError naming the
// step, the HD error code and its name, and the usual causes.
//
// The servo callback (the vendor's scheduler thread, once per tick):
//   t_k = steady clock at the callback's start [s, since start-up]   (measured tick lengths: the
//         real rate dips below 1 kHz at times)
//   hdBeginFrame; q_v = HD_CURRENT_JOINT_ANGLES, HD_CURRENT_GIMBAL_ANGLES [rad]
//   q = s .* q_v + o   (joint convention below);  qd = velocity estimate of q (no joint velocity
//                       is reported: backward difference, low-passed; velocity_estimator.h)
//   tau = the servo function's torque (set_servo_function) or the last write(), through the
//         command chain (condition_command); zero while a fault is latched
//   HD_CURRENT_JOINT_TORQUE, HD_CURRENT_GIMBAL_TORQUE = 1000 s .* tau  [mN m]; hdEndFrame
//   every error on the HD error stack (hdGetError until HD_SUCCESS) latches its fault flag,
//   named after the code (HD_COMM_ERROR -> hd_comm_error; device.h), and zero torque follows.
// Nothing in the callback allocates, throws or blocks: the sample and the command cross to other
// threads through try-locked snapshots (a busy snapshot is skipped for that tick, never waited
// for).
//
// Joint convention: dentsim's q (q1 base yaw counter-clockwise about z up, q2 upper-arm elevation,
// q3 absolute forearm angle, q4..q6 gimbal; docs/phantom.md) from the vendor's angles q_v as
// q_i = s_i q_v,i + o_i; torques then map by power (tau^T qd = tau_v^T qd_v) as tau_v,i = s_i
// tau_i. Default s = (-1, 1, 1, 1, 1, 1), o = 0: the vendor's base angle is positive clockwise seen
// from above (a ROS driver maps q0 -> -q0), its third angle is already the absolute forearm angle
// (the same driver subtracts q1 to get a relative elbow, which dentsim does not use). The gimbal
// signs and offsets are not published: identity, to be checked on a device (docs/hardware.md).
#pragma once

#include <pthread.h>

#include <array>
#include <atomic>
#include <chrono>
#include <mutex>
#include <string>
#include <thread>

#include "device/device.h"
#include "device/hdapi/hdapi_library.h"
#include "device/velocity_estimator.h"

namespace dentsim {

struct HdJointConvention {
  std::array<double, 6> sign = {-1, 1, 1, 1, 1, 1};
  std::array<double, 6> offset = {0, 0, 0, 0, 0, 0};  // [rad]
};

// q = s .* q_v + o (q sized 6; no allocation).
void hd_vendor_to_dentsim_q(const HdJointConvention& c, const double* q_vendor, VecX& q);
// q_v = (q - o) ./ s.
void hd_dentsim_to_vendor_q(const HdJointConvention& c, const VecX& q, double* q_vendor);
// tau_v [mN m] = 1000 s .* tau [N m].
void hd_dentsim_to_vendor_torque(const HdJointConvention& c, const VecX& tau, double* tau_vendor);
// tau [N m] = s .* tau_v [mN m] / 1000.
void hd_vendor_to_dentsim_torque(const HdJointConvention& c, const double* tau_vendor, VecX& tau);

struct HdapiConfig {
  std::string library;      // "" = DENTSIM_HD_LIBRARY, else the usual sonames
  std::string device_name;  // "" = HD_DEFAULT_DEVICE, then "Default PHANToM"
  HdJointConvention convention;
  int rate_hz = 1000;           // scheduler rate asked for
  double tick_timeout_s = 0.1;  // advance() waits this long for a tick, then scheduler_stopped
  // Start-up waits this long for the scheduler's first callback, then fails: the start of the
  // vendor's real-time thread is not a servo deadline, and on a busy machine it can take longer
  // than a tick's timeout (measured: > 0.1 s with 40 probes started at once on 2 cores).
  double start_timeout_s = 2.0;
  VelocityEstimatorParams velocity;
  VecX tau_max;                 // [N m] (empty: phantom_tau_max(), gimbal capped by the device)
  VecX tau_fault;               // [N m] (empty: 4 tau_max)
  double max_joint_step = 0.1;  // [rad] encoder-jump fault threshold per tick
};

// What the device said about itself at start-up.
struct HdDeviceInfo {
  std::string library;  // the library loaded
  std::string model, serial;
  int input_dof = 0, output_dof = 0, update_rate_hz = 0;
  double max_force_n = 0, max_continuous_force_n = 0, max_stiffness_n_per_mm = 0;
  std::array<double, 3> gimbal_max_continuous_mnm{};  // HD_NOMINAL_MAX_TORQUE_CONTINUOUS_FORCE
  bool reports_motor_temperature = false;
};

class HdapiDevice : public Device {
 public:
  // The servo function run inside the scheduler callback: sample in, torque [N m] out (sized 6).
  // Returns false to stop the servo loop (the callback then returns HD_CALLBACK_DONE). Must not
  // allocate, block or throw.
  using ServoFn = bool (*)(void* context, const DeviceSample& sample, VecX& tau_out);

  // Loads the library and starts the device (sequence above). Throws HdapiError.
  explicit HdapiDevice(HdapiConfig config);
  // Stops the scheduler, zero torque, disables the device.
  ~HdapiDevice() override;
  HdapiDevice(const HdapiDevice&) = delete;
  HdapiDevice& operator=(const HdapiDevice&) = delete;

  // Device interface. read() gives the latest tick's sample; write() sets the command the callback
  // applies from its next tick k on (held until replaced); advance() waits until that tick k has
  // applied it and tick k+1 has published its sample (the sample after the command, as with
  // SimulatedPhantom), at most tick_timeout_s per tick, then latches kFaultSchedulerStopped.
  // A wait that times out (a stalled scheduler, or a callback the scheduler dropped after DONE)
  // also disables force output at once from the waiting thread (hdDisable(HD_FORCE_OUTPUT)):
  // no scheduler tick would apply the zero torque the fault asks for, and the motors would keep
  // the last torque set. Force output stays disabled until the device is destroyed, and
  // applied_torque() is zero once the library reports output disabled (hdIsEnabled).
  const DeviceCapabilities& capabilities() const override { return caps_; }
  const DeviceLimits& limits() const override { return limits_; }
  void read(DeviceSample& out) const override;
  void write(const VecX& tau) override;
  void advance() override;
  const VecX& applied_torque() const override;
  std::uint32_t faults() const override { return faults_.load(); }
  void clear_faults() override { faults_.store(kFaultNone); }

  // Runs `fn(context, ...)` in the scheduler callback from the next tick on, in place of the
  // write() command (nullptr: back to write()). Both must outlive the device or the next call;
  // called from another thread than the scheduler's, it returns only once no callback is inside
  // the previous function (so the caller may then destroy what it used).
  void set_servo_function(ServoFn fn, void* context);
  // Waits until the scheduler has run `ticks` more ticks; false (and kFaultSchedulerStopped)
  // when the wait exceeds ticks x tick_timeout_s (timeout_s > 0: that long instead).
  bool wait_ticks(long ticks, double timeout_s = 0.0);

  const HdDeviceInfo& info() const { return info_; }
  long ticks() const { return ticks_.load(); }
  // Latest motor temperatures, normalised 0..1 (all 0 when the device does not report them).
  std::array<double, 6> motor_temperature() const;
  // True once the callback returned HD_CALLBACK_DONE (servo function returned false).
  bool servo_done() const { return done_.load(); }
  // The vendor's scheduler thread's scheduling policy and priority (pthread_getschedparam of the
  // thread the last tick ran on), for a helper thread that must run just below it (the field
  // edit's worker). False when no tick ran yet or the thread cannot be asked (it ended).
  bool scheduler_policy(int* policy, int* priority) const;

 private:
  static HDCallbackCode servo_callback(void* self);
  HDCallbackCode tick();
  void check(const char* step);  // throws HdapiError on an HD error after `step`
  // The scheduler did not tick in time: latch kFaultSchedulerStopped and disable force output.
  void scheduler_timed_out();
  void shutdown();

  HdapiConfig cfg_;
  const HdLibrary* lib_ = nullptr;
  HHD hhd_ = hd::kInvalidHandle;
  HDSchedulerHandle sched_ = 0;
  bool scheduler_started_ = false;
  HdDeviceInfo info_;
  DeviceCapabilities caps_;
  DeviceLimits limits_;
  std::chrono::steady_clock::time_point t0_;

  // Scheduler-thread state (touched only in the callback once started).
  VelocityEstimator vel_;
  DeviceSample s_;  // this tick's sample
  VecX tau_fn_, tau_cmd_, tau_out_, q_prev_;
  std::array<double, 6> temp_rt_{};
  bool first_tick_ = true;

  // Shared with other threads.
  mutable std::mutex snap_mu_;  // published sample, applied torque, motor temperatures
  DeviceSample snap_;
  VecX tau_applied_snap_;
  std::array<double, 6> temp_snap_{};
  mutable std::mutex cmd_mu_;  // write() command
  VecX tau_written_;
  VecX tau_cmd_write_;             // write()'s conditioned command (caller's thread)
  mutable VecX tau_applied_read_;  // what applied_torque() returns (copied under snap_mu_)
  std::atomic<ServoFn> fn_{nullptr};
  std::atomic<void*> fn_ctx_{nullptr};
  std::atomic<bool> fn_running_{false};               // tick() is inside its read of fn_ and call
  std::atomic<std::thread::id> scheduler_thread_{};  // the thread tick() last ran on
  std::atomic<pthread_t> scheduler_pthread_{};       // the same thread, for its policy
  std::atomic<bool> scheduler_ticked_{false};        // scheduler_pthread_ is set
  std::atomic<std::uint32_t> faults_{kFaultNone};
  std::atomic<long> ticks_{0};
  std::atomic<bool> done_{false};
  std::atomic<bool> timed_out_{false};       // scheduler_timed_out() ran
  std::atomic<bool> force_disabled_{false};  // and the library then reported output disabled
  long cmd_seq_ = 0;                    // write() count (under cmd_mu_)
  long wait_seq_ = 0;                   // the caller's last write()
  long cmd_seq_rt_ = 0;                 // the sequence the callback copied last
  std::atomic<long> applied_seq_{0};    // published at the end of the tick that applied it
  std::atomic<long> applied_tick_{-1};  // index of that tick
};

}  // namespace dentsim
