#include "device/closed_loop.h"

namespace dentsim {

ClosedLoop::ClosedLoop(Device& device, Pipeline& pipeline, ContactProvider& contacts)
    : device_(device), pipeline_(pipeline), contacts_(contacts) {
  sample_ = device_.make_sample();
  next_ = device_.make_sample();
  T_ = device_.capabilities().nominal_period;
}

void ClosedLoop::start() {
  device_.read(sample_);
  pipeline_.reset(sample_);
  T_ = device_.capabilities().nominal_period;
  energy_ = 0.0;
  ticks_ = 0;
}

const TickResult& ClosedLoop::step() {
  const TickResult& r = pipeline_.tick(sample_, T_, contacts_);
  device_.write(r.tau);
  device_.advance();
  device_.read(next_);
  // Passivity observer: the torque held over the tick times the joint displacement.
  energy_ += (device_.applied_torque() - r.tau_gravity).dot(next_.q - sample_.q);
  const double dt = next_.t - sample_.t;
  if (dt > 0.0) T_ = dt;
  std::swap(sample_, next_);
  ++ticks_;
  return r;
}

}  // namespace dentsim
