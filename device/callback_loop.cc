#include "device/callback_loop.h"

#include <algorithm>

#include "device/hdapi/hdapi_device.h"

namespace dentsim {

void fill_tick_record(long k, const DeviceSample& in, const TickResult& r, const ClosedLoop& loop,
                      const Pipeline& pipeline, double device_depth, TickRecord& out) {
  out.k = k;
  out.t = in.t;
  const Eigen::Index n = std::min<Eigen::Index>(6, in.q.size());
  out.q.setZero();
  out.qd.setZero();
  out.tau.setZero();
  out.tau_pipeline.setZero();
  out.tau_pipeline.head(std::min<Eigen::Index>(6, r.tau.size())) =
      r.tau.head(std::min<Eigen::Index>(6, r.tau.size()));
  out.q.head(n) = in.q.head(n);
  out.qd.head(n) = in.qd.head(std::min<Eigen::Index>(n, in.qd.size()));
  const VecX& tau = loop.commanded_torque();
  out.tau.head(std::min<Eigen::Index>(6, tau.size())) =
      tau.head(std::min<Eigen::Index>(6, tau.size()));
  out.f_contact = r.F_contact.head<3>();
  out.f_device = r.T1.head<3>();
  out.f_observer = r.F1_hat.head<3>();
  out.max_depth = r.max_depth;
  out.device_depth = device_depth;
  out.contacts = static_cast<int>(r.contacts.size());
  out.device = r.device;
  out.proxy = pipeline.proxy().pose;
  out.energy_virtual_j = loop.energy_virtual_j();
  std::copy(std::begin(r.stage_ns), std::end(r.stage_ns), std::begin(out.stage_ns));
  out.faulted = loop.faulted();
  out.fault_name = loop.faulted() ? loop.fault_name() : "";
  out.fault_t = loop.fault_time();
}

CallbackServo::CallbackServo(HdapiDevice& device, ClosedLoop& loop, const Pipeline& pipeline,
                             DepthFn depth, void* depth_context, std::size_t capacity)
    : device_(device),
      loop_(loop),
      pipeline_(pipeline),
      depth_(depth),
      depth_context_(depth_context),
      ring_(capacity) {}

CallbackServo::~CallbackServo() {
  if (attached_.exchange(false)) device_.set_servo_function(nullptr, nullptr);
}

void CallbackServo::start() {
  attached_.store(true);
  device_.set_servo_function(&CallbackServo::servo, this);
}

bool CallbackServo::servo(void* self_ptr, const DeviceSample& s, VecX& tau_out) {
  auto& self = *static_cast<CallbackServo*>(self_ptr);
  if (self.stop_.load()) {
    tau_out.setZero();
    return false;  // HD_CALLBACK_DONE
  }
  const long k = self.ticks_.load(std::memory_order_relaxed);
  const TickResult& r = self.loop_.step_in_callback(s, tau_out);
  const double depth = self.depth_ != nullptr ? self.depth_(self.depth_context_, r.device) : 0.0;
  fill_tick_record(k, s, r, self.loop_, self.pipeline_, depth, self.scratch_);
  if (!self.ring_.push(self.scratch_)) self.dropped_.fetch_add(1, std::memory_order_relaxed);
  self.ticks_.store(k + 1, std::memory_order_release);
  return true;
}

}  // namespace dentsim
