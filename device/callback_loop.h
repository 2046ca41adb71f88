// The loop owner inside the vendor's callback (issue #15). With HDAPI the vendor's scheduler
// calls us once per servo tick (1 kHz on a Phantom); the whole tick runs there:
//
//   scheduler callback k (HdapiDevice::tick): sample s_k -> CallbackServo::servo ->
//     ClosedLoop::step_in_callback(s_k, tau_k)   (pipeline tick + safety chain + fault latch)
//     measurements of tick k -> TickRecord -> SpscRing (lock-free, preallocated)
//   -> tau_k through the device's command chain -> the motors over tick k
//
// Nothing in the callback allocates, blocks or throws (the ring is filled in place; a full ring
// drops the record and counts it, the torque is never delayed by it). The caller's thread pops
// the records and does everything else (statistics, time series, the session recorder); it asks
// the servo to stop with request_stop(): the next callback commands zero torque and returns
// HD_CALLBACK_DONE.
//
// TickRecord is also what the direct loop (ClosedLoop::step on the caller's thread) measures, so
// the simulator consumes one kind of record whichever thread ran the tick.
#pragma once

#include <atomic>
#include <cstddef>

#include "device/closed_loop.h"
#include "device/spsc_ring.h"
#include "reference/core/pipeline.h"

namespace dentsim {

class HdapiDevice;

// One tick as the simulator measures it. Fixed size: no allocation to fill or copy.
struct TickRecord {
  long k = 0;                                // tick index since the loop started
  double t = 0.0;                            // the tick's input sample time [s]
  Vec6 q = Vec6::Zero(), qd = Vec6::Zero();  // the input sample (6-DoF devices)
  Vec6 tau = Vec6::Zero();           // the command handed to the device [N m] (zero once faulted)
  Vec6 tau_pipeline = Vec6::Zero();  // the pipeline's torque of the tick (before the chain)
  Vec3 f_contact = Vec3::Zero();     // contact + friction force on the proxy
  Vec3 f_device = Vec3::Zero();      // force of T1 (fed back to the device)
  Vec3 f_observer = Vec3::Zero();    // observer estimate F1_hat (force part)
  double max_depth = 0.0;            // deepest penetration of the proxy [m]
  double device_depth = 0.0;         // deepest penetration of the device's own tip [m]
  int contacts = 0;
  Pose device, proxy;
  double energy_virtual_j = 0.0;  // the loop's E_v after this tick's predecessor
  long stage_ns[kStageCount] = {};
  bool faulted = false;         // the loop had latched a fault after this tick
  const char* fault_name = "";  // ClosedLoop::fault_name() (a static string)
  double fault_t = 0.0;
};

// Fills `out` from tick `k` run on `in` (no allocation). `device_depth` is measured by the caller.
void fill_tick_record(long k, const DeviceSample& in, const TickResult& r, const ClosedLoop& loop,
                      const Pipeline& pipeline, double device_depth, TickRecord& out);

class CallbackServo {
 public:
  // Deepest penetration of the device's own tip at `pose` (the simulator's measurement; run in
  // the callback, must not allocate once warm); null: 0.
  using DepthFn = double (*)(void* context, const Pose& pose);

  // `loop` must already be started (ClosedLoop::start on the caller's thread). References and
  // the context must outlive the servo. `capacity` records are preallocated.
  CallbackServo(HdapiDevice& device, ClosedLoop& loop, const Pipeline& pipeline, DepthFn depth,
                void* depth_context, std::size_t capacity = 1 << 14);
  // Detaches from the device (set_servo_function(nullptr)) if still attached.
  ~CallbackServo();
  CallbackServo(const CallbackServo&) = delete;
  CallbackServo& operator=(const CallbackServo&) = delete;

  // Installs the servo function: the tick runs in the scheduler's callback from its next tick.
  void start();
  // The next callback commands zero torque and returns HD_CALLBACK_DONE.
  void request_stop() { stop_.store(true); }
  // Caller's thread: the oldest record not yet taken; false when none is waiting.
  bool pop(TickRecord& out) { return ring_.pop(out); }
  long dropped() const { return dropped_.load(); }
  long ticks() const { return ticks_.load(); }

 private:
  static bool servo(void* self, const DeviceSample& s, VecX& tau_out);

  HdapiDevice& device_;
  ClosedLoop& loop_;
  const Pipeline& pipeline_;
  DepthFn depth_;
  void* depth_context_;
  SpscRing<TickRecord> ring_;
  TickRecord scratch_;  // filled in the callback, then copied into the ring
  std::atomic<bool> stop_{false};
  std::atomic<bool> attached_{false};
  std::atomic<long> dropped_{0}, ticks_{0};
};

}  // namespace dentsim
