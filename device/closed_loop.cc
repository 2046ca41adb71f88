#include "device/closed_loop.h"

#include <time.h>

#include <utility>

namespace dentsim {

ClosedLoop::ClosedLoop(Device& device, Pipeline& pipeline, ContactProvider& contacts)
    : device_(device), pipeline_(pipeline), contacts_(contacts) {
  sample_ = device_.make_sample();
  next_ = device_.make_sample();
  tau_cmd_ = VecX::Zero(device_.dof());
  tau_gravity_prev_ = VecX::Zero(device_.dof());
  T_ = device_.capabilities().nominal_period;
}

void ClosedLoop::set_safety_chain(SafetyChain* chain) {
  safety_ = chain;
  tau_safe_ = VecX::Zero(device_.dof());
}

const char* ClosedLoop::fault_name() const {
  if (fault_ == TickStatus::kOk && supervisor_fault_ != SupervisorFault::kNone) {
    return supervisor_fault_name(supervisor_fault_);
  }
  if (fault_ != TickStatus::kOk || device_faults_ == kFaultNone) return tick_status_name(fault_);
  return dentsim::fault_name(static_cast<DeviceFault>(device_faults_ & (~device_faults_ + 1u)));
}

void ClosedLoop::start() {
  device_.read(sample_);
  device_faults_ = kFaultNone;
  supervisor_fault_ = SupervisorFault::kNone;
  if (supervisor_ != nullptr) supervisor_->start();
  if (safety_ != nullptr) safety_->start(sample_.t);
  fault_ = pipeline_.reset(sample_);
  fault_t_ = sample_.t;
  T_ = device_.capabilities().nominal_period;
  energy_ = 0.0;
  ticks_ = 0;
  last_exec_s_ = -1.0;
  tau_cmd_.setZero();
}

namespace {
// CPU time of the calling thread [s] (one clock_gettime).
double thread_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}
}  // namespace

const TickResult& ClosedLoop::decide() {
  // The watchdog's input, read only when the chain has a watchdog.
  const bool timed = safety_ != nullptr && safety_->limits().watchdog_s > 0.0;
  const double cpu0 = timed ? thread_cpu_s() : 0.0;
  const TickResult& r = pipeline_.tick(sample_, T_, contacts_);
  const double exec_s = timed ? thread_cpu_s() - cpu0 : -1.0;
  if (!faulted() && r.status != TickStatus::kOk) {
    fault_ = r.status;
    fault_t_ = sample_.t;
  }
  // The device's and the sample's faults first (the safety chain: a jumped encoder, a frozen
  // clock, ...): they are the cause when the tick's figures then run away too.
  if (!faulted() && safety_ != nullptr) {
    const std::uint32_t f = safety_->apply(sample_, r.tau, last_exec_s_, nullptr, tau_safe_);
    if (f != kFaultNone) {
      device_faults_ = f;
      fault_t_ = sample_.t;
    }
  }
  if (!faulted() && supervisor_ != nullptr) {
    supervisor_fault_ = supervisor_->check(r, pipeline_.proxy(), T_);
    if (supervisor_fault_ != SupervisorFault::kNone) fault_t_ = sample_.t;
  }
  last_exec_s_ = exec_s;
  if (faulted()) {
    tau_cmd_.setZero();  // the latch: zero torque from the faulting tick on
  } else {
    tau_cmd_ = safety_ != nullptr ? tau_safe_ : r.tau;
  }
  return r;
}

const TickResult& ClosedLoop::step_in_callback(const DeviceSample& s, VecX& tau_out) {
  if (ticks_ > 0) {
    // The previous tick, held over [sample_.t, s.t]: its torque times the joint motion.
    if (!faulted()) energy_ += (tau_cmd_ - tau_gravity_prev_).dot(s.q - sample_.q);
    const double dt = s.t - sample_.t;
    if (dt > 0.0 && !nominal_) T_ = dt;
  }
  sample_.q = s.q;  // same sizes: no allocation
  sample_.qd = s.qd;
  sample_.t = s.t;
  const std::uint32_t dev = device_.faults();
  if (safety_ != nullptr && !faulted() && dev != kFaultNone) {
    device_faults_ = dev;
    fault_t_ = s.t;
  }
  const TickResult& r = decide();
  tau_gravity_prev_ = r.tau_gravity;
  tau_out = tau_cmd_;
  ++ticks_;
  return r;
}

const TickResult& ClosedLoop::step() {
  const TickResult& r = decide();
  device_.write(tau_cmd_);
  device_.advance();
  device_.read(next_);
  if (safety_ != nullptr && !faulted() && device_.faults() != kFaultNone) {
    // The device reported a fault over this tick (lost, its own command chain): latch it and
    // command zero torque at once.
    device_faults_ = device_.faults();
    fault_t_ = next_.t;
    tau_cmd_.setZero();
    device_.write(tau_cmd_);
  }
  // Passivity observer: the torque held over the tick times the joint displacement.
  if (!faulted()) {
    energy_ += (device_.applied_torque() - r.tau_gravity).dot(next_.q - sample_.q);
  }
  const double dt = next_.t - sample_.t;
  if (dt > 0.0 && !nominal_) T_ = dt;
  std::swap(sample_, next_);
  ++ticks_;
  return r;
}

}  // namespace dentsim
