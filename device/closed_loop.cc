#include "device/closed_loop.h"

#include <utility>

namespace dentsim {

ClosedLoop::ClosedLoop(Device& device, Pipeline& pipeline, ContactProvider& contacts)
    : device_(device), pipeline_(pipeline), contacts_(contacts) {
  sample_ = device_.make_sample();
  next_ = device_.make_sample();
  tau_cmd_ = VecX::Zero(device_.dof());
  T_ = device_.capabilities().nominal_period;
}

void ClosedLoop::start() {
  device_.read(sample_);
  fault_ = pipeline_.reset(sample_);
  fault_t_ = sample_.t;
  T_ = device_.capabilities().nominal_period;
  energy_ = 0.0;
  ticks_ = 0;
  tau_cmd_.setZero();
}

const TickResult& ClosedLoop::step() {
  const TickResult& r = pipeline_.tick(sample_, T_, contacts_);
  if (!faulted() && r.status != TickStatus::kOk) {
    fault_ = r.status;
    fault_t_ = sample_.t;
  }
  if (faulted()) {
    tau_cmd_.setZero();  // the latch: zero torque from the faulting tick on
  } else {
    tau_cmd_ = r.tau;
  }
  device_.write(tau_cmd_);
  device_.advance();
  device_.read(next_);
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
