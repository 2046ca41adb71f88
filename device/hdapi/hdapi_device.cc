#include "device/hdapi/hdapi_device.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <thread>

#include "device/simulated_phantom.h"
#include "reference/core/io.h"

namespace dentsim {

void hd_vendor_to_dentsim_q(const HdJointConvention& c, const double* q_vendor, VecX& q) {
  for (int i = 0; i < 6; ++i) q[i] = c.sign[i] * q_vendor[i] + c.offset[i];
}

void hd_dentsim_to_vendor_q(const HdJointConvention& c, const VecX& q, double* q_vendor) {
  for (int i = 0; i < 6; ++i) q_vendor[i] = (q[i] - c.offset[i]) / c.sign[i];
}

void hd_dentsim_to_vendor_torque(const HdJointConvention& c, const VecX& tau, double* tau_vendor) {
  for (int i = 0; i < 6; ++i) tau_vendor[i] = 1000.0 * c.sign[i] * tau[i];
}

void hd_vendor_to_dentsim_torque(const HdJointConvention& c, const double* tau_vendor, VecX& tau) {
  for (int i = 0; i < 6; ++i) tau[i] = c.sign[i] * tau_vendor[i] / 1000.0;
}

namespace {

std::string hex(unsigned v) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%04X", v);
  return buf;
}

// Empties the HD error stack (bounded: a library that never reports HD_SUCCESS cannot hang us).
void drain_errors(const HdLibrary& l) {
  for (int i = 0; i < 64 && l.hdGetError().errorCode != hd::kSuccess; ++i) {
  }
}

// The usual causes of an initialisation failure, for the message.
const char* init_hint(HDerror code) {
  switch (code) {
    case hd::kDeviceFault:
      return "the device is not connected or not found: check the cable and power, the driver "
             "(PHANToM Configuration / the vendor's test tool), the device name, and permissions "
             "on "
             "the port (run the vendor's test tool as the same user; root is often needed for EPP "
             "parallel ports)";
    case hd::kDeviceAlreadyInitiated:
      return "another program (or this one) already holds the device";
    case hd::kCommError:
    case hd::kCommConfigError:
      return "communication with the device failed: cable, port configuration (EPP/FireWire), "
             "permissions";
    case hd::kInvalidLicense:
      return "the OpenHaptics licence does not match the driver";
    default:
      return "see the vendor's documentation of this code";
  }
}

}  // namespace

void HdapiDevice::check(const char* step) {
  const HDErrorInfo e = lib_->hdGetError();
  if (e.errorCode == hd::kSuccess) return;
  std::string text = lib_->hdGetErrorString(e.errorCode) ? lib_->hdGetErrorString(e.errorCode) : "";
  throw HdapiError(std::string("HDAPI ") + step + " failed: " + hd::error_name(e.errorCode) + " (" +
                   hex(e.errorCode) + ", internal " + std::to_string(e.internalErrorCode) +
                   (text.empty() ? "" : ", \"" + text + "\"") + ") from " + lib_->path + "; " +
                   init_hint(e.errorCode));
}

HdapiDevice::HdapiDevice(HdapiConfig config) : cfg_(std::move(config)), vel_(6, cfg_.velocity) {
  if (cfg_.rate_hz < 100 || cfg_.rate_hz > 10000) {
    throw InputError("hdapi device: rate_hz = " + std::to_string(cfg_.rate_hz) +
                     ", expected 100..10000");
  }
  for (double s : cfg_.convention.sign) {
    if (s != 1.0 && s != -1.0) throw InputError("hdapi device: joint convention sign must be +-1");
  }
  lib_ = &load_hd_library(cfg_.library);
  info_.library = lib_->path;

  // Init: the default device, then the name some installs need.
  drain_errors(*lib_);
  const char* name = cfg_.device_name.empty() ? hd::kDefaultDevice : cfg_.device_name.c_str();
  hhd_ = lib_->hdInitDevice(name);
  HDErrorInfo err = lib_->hdGetError();
  if ((hhd_ == hd::kInvalidHandle || err.errorCode != hd::kSuccess) && cfg_.device_name.empty() &&
      err.errorCode != hd::kDeviceAlreadyInitiated) {
    drain_errors(*lib_);
    hhd_ = lib_->hdInitDevice("Default PHANToM");
    const HDErrorInfo err2 = lib_->hdGetError();
    if (hhd_ == hd::kInvalidHandle || err2.errorCode != hd::kSuccess) {
      if (err2.errorCode != hd::kSuccess) err = err2;
    } else {
      err = err2;
    }
  }
  if (hhd_ == hd::kInvalidHandle || err.errorCode != hd::kSuccess) {
    const HDerror code = err.errorCode != hd::kSuccess ? err.errorCode : hd::kDeviceFault;
    hhd_ = hd::kInvalidHandle;
    throw HdapiError(std::string("HDAPI hdInitDevice(") +
                     (cfg_.device_name.empty() ? "HD_DEFAULT_DEVICE, then \"Default PHANToM\""
                                               : "\"" + cfg_.device_name + "\"") +
                     ") failed: " + hd::error_name(code) + " (" + hex(code) + ") from " +
                     lib_->path + "; " + init_hint(code));
  }
  try {
    lib_->hdMakeCurrentDevice(hhd_);
    check("hdMakeCurrentDevice");
    // What the device says about itself (optional queries: an error just leaves the default).
    auto get_string = [&](HDenum what) {
      const char* s = lib_->hdGetString(what);
      const bool ok = lib_->hdGetError().errorCode == hd::kSuccess;
      return ok && s != nullptr ? std::string(s) : std::string("unknown");
    };
    auto get_int = [&](HDenum what) {
      HDint v[16] = {};
      lib_->hdGetIntegerv(what, v);
      return lib_->hdGetError().errorCode == hd::kSuccess ? v[0] : 0;
    };
    auto get_doubles = [&](HDenum what, double* out, int n) {
      HDdouble v[16] = {};
      lib_->hdGetDoublev(what, v);
      const bool ok = lib_->hdGetError().errorCode == hd::kSuccess;
      for (int i = 0; i < n; ++i) out[i] = ok ? v[i] : 0.0;
      return ok;
    };
    info_.model = get_string(hd::kDeviceModelType);
    info_.serial = get_string(hd::kDeviceSerialNumber);
    info_.input_dof = get_int(hd::kInputDof);
    info_.output_dof = get_int(hd::kOutputDof);
    info_.update_rate_hz = get_int(hd::kUpdateRate);
    get_doubles(hd::kNominalMaxForce, &info_.max_force_n, 1);
    get_doubles(hd::kNominalMaxContinuousForce, &info_.max_continuous_force_n, 1);
    get_doubles(hd::kNominalMaxStiffness, &info_.max_stiffness_n_per_mm, 1);
    get_doubles(hd::kNominalMaxTorqueContinuousForce, info_.gimbal_max_continuous_mnm.data(), 3);
    double temp[6];
    info_.reports_motor_temperature = get_doubles(hd::kMotorTemperature, temp, 6);
    drain_errors(*lib_);
    if (info_.output_dof != 0 && info_.output_dof != 6) {
      throw HdapiError("HDAPI device \"" + info_.model + "\" reports " +
                       std::to_string(info_.output_dof) +
                       " output DoF; dentsim drives joint and gimbal torques of a 6-DoF "
                       "Phantom (Premium 1.5/6DoF)");
    }

    // Capabilities and limits.
    caps_.dof = 6;
    caps_.measures_velocity = false;
    caps_.simulated = false;
    caps_.nominal_period = 1.0 / cfg_.rate_hz;
    caps_.encoder_quantum = encoder_quantum(1024, 4, phantom_drive_ratios());
    caps_.velocity_lowpass_hz =
        cfg_.velocity.filter == VelocityFilter::kFirstOrderLowPass ? cfg_.velocity.cutoff_hz : 0.0;
    limits_.tau_max = cfg_.tau_max.size() == 6 ? cfg_.tau_max : phantom_tau_max();
    for (int i = 0; i < 3; ++i) {
      const double dev = 1e-3 * info_.gimbal_max_continuous_mnm[i];
      if (cfg_.tau_max.size() != 6 && dev > 0.0) {
        limits_.tau_max[3 + i] = std::min(limits_.tau_max[3 + i], dev);
      }
    }
    limits_.tau_fault = cfg_.tau_fault.size() == 6 ? cfg_.tau_fault : VecX(4.0 * limits_.tau_max);
    limits_.max_joint_step = cfg_.max_joint_step;

    s_.q = VecX::Zero(6);
    s_.qd = VecX::Zero(6);
    snap_ = s_;
    tau_fn_ = VecX::Zero(6);
    tau_cmd_ = VecX::Zero(6);
    tau_out_ = VecX::Zero(6);
    q_prev_ = VecX::Zero(6);
    tau_written_ = VecX::Zero(6);
    tau_applied_snap_ = VecX::Zero(6);
    tau_applied_read_ = VecX::Zero(6);

    lib_->hdEnable(hd::kForceOutput);
    check("hdEnable(HD_FORCE_OUTPUT)");
    t0_ = std::chrono::steady_clock::now();
    sched_ =
        lib_->hdScheduleAsynchronous(&HdapiDevice::servo_callback, this, hd::kMaxSchedulerPriority);
    check("hdScheduleAsynchronous");
    lib_->hdSetSchedulerRate(static_cast<HDulong>(cfg_.rate_hz));
    check("hdSetSchedulerRate");
    lib_->hdStartScheduler();
    scheduler_started_ = true;
    check("hdStartScheduler");
    // The first sample: wait for the first tick so read() is valid before the loop.
    if (!wait_ticks(1, cfg_.start_timeout_s)) {
      throw HdapiError("HDAPI scheduler started but did not call the servo callback within " +
                       std::to_string(cfg_.start_timeout_s) + " s (library " + lib_->path + ")");
    }
  } catch (...) {
    shutdown();
    throw;
  }
}

void HdapiDevice::shutdown() {
  if (lib_ == nullptr || hhd_ == hd::kInvalidHandle) return;
  if (scheduler_started_) lib_->hdStopScheduler();
  scheduler_started_ = false;
  if (sched_ != 0) lib_->hdUnschedule(sched_);
  sched_ = 0;
  lib_->hdDisable(hd::kForceOutput);
  lib_->hdDisableDevice(hhd_);
  drain_errors(*lib_);
  hhd_ = hd::kInvalidHandle;
}

HdapiDevice::~HdapiDevice() { shutdown(); }

bool HdapiDevice::scheduler_policy(int* policy, int* priority) const {
  if (!scheduler_started_ || !scheduler_ticked_.load(std::memory_order_acquire)) return false;
  sched_param param{};
  int p = 0;
  if (pthread_getschedparam(scheduler_pthread_.load(std::memory_order_relaxed), &p, &param) != 0) {
    return false;
  }
  *policy = p;
  *priority = param.sched_priority;
  return true;
}

HDCallbackCode HdapiDevice::servo_callback(void* self) {
  return static_cast<HdapiDevice*>(self)->tick();
}

HDCallbackCode HdapiDevice::tick() {
  const HdLibrary& l = *lib_;
  scheduler_thread_.store(std::this_thread::get_id());
  scheduler_pthread_.store(pthread_self(), std::memory_order_relaxed);
  scheduler_ticked_.store(true, std::memory_order_release);
  const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
  l.hdBeginFrame(hhd_);
  HDdouble qv[6 + 16] = {};  // room for a library that writes more than three values
  HDdouble gv[16] = {};
  l.hdGetDoublev(hd::kCurrentJointAngles, qv);
  l.hdGetDoublev(hd::kCurrentGimbalAngles, gv);
  for (int i = 0; i < 3; ++i) qv[3 + i] = gv[i];
  if (info_.reports_motor_temperature) {
    HDdouble tv[16] = {};
    l.hdGetDoublev(hd::kMotorTemperature, tv);
    for (int i = 0; i < 6; ++i) temp_rt_[i] = tv[i];
  }
  std::uint32_t f = kFaultNone;
  q_prev_ = s_.q;
  hd_vendor_to_dentsim_q(cfg_.convention, qv, s_.q);
  if (first_tick_) {
    vel_.reset(s_.q, t, VecX::Zero(6));
    first_tick_ = false;
  } else {
    f |= check_sample(q_prev_, s_.t, s_.q, t, limits_, caps_.nominal_period);
    s_.qd = vel_.update(s_.q, t);
  }
  s_.t = t;

  // The command: the servo function's, or the last write().
  bool stop = false;
  // fn_running_ is raised before fn_ is read (both seq_cst), so set_servo_function, which clears
  // fn_ before it reads fn_running_, either sees this call in flight and waits for it, or this
  // tick reads the cleared fn_.
  fn_running_.store(true);
  const ServoFn fn = fn_.load();
  if (fn != nullptr) {
    stop = !fn(fn_ctx_.load(), s_, tau_fn_);
    f |= condition_command(tau_fn_, limits_, true, tau_cmd_);
  }
  fn_running_.store(false);
  if (fn == nullptr && cmd_mu_.try_lock()) {
    tau_cmd_ = tau_written_;
    cmd_seq_rt_ = cmd_seq_;
    cmd_mu_.unlock();
  }
  if (f != kFaultNone) faults_.fetch_or(f);
  if (faults_.load() != kFaultNone || stop || force_disabled_.load()) {
    tau_out_.setZero();
  } else {
    tau_out_ = tau_cmd_;
  }
  HDdouble tv[6];
  hd_dentsim_to_vendor_torque(cfg_.convention, tau_out_, tv);
  l.hdSetDoublev(hd::kCurrentJointTorque, tv);
  l.hdSetDoublev(hd::kCurrentGimbalTorque, tv + 3);
  l.hdEndFrame(hhd_);
  // Every error of this frame (the stack is bounded: at most 64 popped per tick).
  std::uint32_t hd_faults = kFaultNone;
  for (int i = 0; i < 64; ++i) {
    const HDErrorInfo e = l.hdGetError();
    if (e.errorCode == hd::kSuccess) break;
    hd_faults |= hd::fault_for_error(e.errorCode);
  }
  if (hd_faults != kFaultNone) {
    faults_.fetch_or(hd_faults);
    tau_out_.setZero();  // what reaches the motors from the next frame on
  }
  if (snap_mu_.try_lock()) {
    snap_.q = s_.q;
    snap_.qd = s_.qd;
    snap_.t = s_.t;
    tau_applied_snap_ = tau_out_;
    temp_snap_ = temp_rt_;
    snap_mu_.unlock();
  }
  if (fn == nullptr && applied_seq_.load() != cmd_seq_rt_) {
    applied_tick_.store(ticks_.load());
    applied_seq_.store(cmd_seq_rt_);
  }
  ticks_.fetch_add(1);
  if (stop) {
    done_.store(true);
    return hd::kCallbackDone;
  }
  return hd::kCallbackContinue;
}

void HdapiDevice::read(DeviceSample& out) const {
  const std::lock_guard<std::mutex> lock(snap_mu_);
  out.q = snap_.q;
  out.qd = snap_.qd;
  out.t = snap_.t;
}

void HdapiDevice::write(const VecX& tau) {
  const std::uint32_t f = condition_command(tau, limits_, true, tau_cmd_write_);
  if (f != kFaultNone) faults_.fetch_or(f);
  const std::lock_guard<std::mutex> lock(cmd_mu_);
  tau_written_ = tau_cmd_write_;
  wait_seq_ = ++cmd_seq_;
}

bool HdapiDevice::wait_ticks(long n, double timeout_s) {
  const long target = ticks_.load() + n;
  const double wait_s = timeout_s > 0.0 ? timeout_s : cfg_.tick_timeout_s * static_cast<double>(n);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(wait_s);
  while (ticks_.load() < target) {
    if (std::chrono::steady_clock::now() > deadline) {
      scheduler_timed_out();
      return false;
    }
    std::this_thread::sleep_for(std::chrono::microseconds(50));
  }
  return true;
}

void HdapiDevice::scheduler_timed_out() {
  faults_.fetch_or(kFaultSchedulerStopped);
  if (timed_out_.exchange(true)) return;
  // From this thread, while the scheduler may still run: an error this pushes is popped (and
  // named) by the callback's next tick, if there is one; the fault is latched either way. The
  // library is asked whether output is off: applied_torque() reports zero only then.
  lib_->hdDisable(hd::kForceOutput);
  force_disabled_.store(lib_->hdIsEnabled(hd::kForceOutput) == 0);
}

void HdapiDevice::advance() {
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(3.0 * cfg_.tick_timeout_s);
  // Tick k applies the command, tick k+1 publishes the sample after it.
  while (applied_seq_.load() < wait_seq_ || ticks_.load() < applied_tick_.load() + 2) {
    if (std::chrono::steady_clock::now() > deadline) {
      scheduler_timed_out();
      return;
    }
    std::this_thread::sleep_for(std::chrono::microseconds(50));
  }
}

const VecX& HdapiDevice::applied_torque() const {
  const std::lock_guard<std::mutex> lock(snap_mu_);
  if (force_disabled_.load()) {
    tau_applied_read_.setZero();  // force output is off: the motors get nothing
  } else {
    tau_applied_read_ = tau_applied_snap_;
  }
  return tau_applied_read_;
}

std::array<double, 6> HdapiDevice::motor_temperature() const {
  const std::lock_guard<std::mutex> lock(snap_mu_);
  return temp_snap_;
}

void HdapiDevice::set_servo_function(ServoFn fn, void* context) {
  fn_.store(nullptr);
  // A callback already inside the old function (on the scheduler thread) finishes before this
  // returns, so the caller may then destroy what the old function used (the servo, the pipeline).
  // Not from inside the callback itself: it would wait for its own call.
  if (std::this_thread::get_id() != scheduler_thread_.load()) {
    while (fn_running_.load()) std::this_thread::sleep_for(std::chrono::microseconds(20));
  }
  fn_ctx_.store(context);
  fn_.store(fn);
}

}  // namespace dentsim
