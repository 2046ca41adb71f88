// Device faults injected for tests and drills (`dentsim run --inject-fault KIND@T`): a Device
// decorator that corrupts what the wrapped device reports from time T on, so the whole chain
// behind it — the tick's status, the loop owner's latch to zero torque, the report — is exercised
// exactly as a faulty driver would exercise it.
//
// Kinds (KIND@T, T [s] on the device clock); what the loop owner with its safety chain
// (device/closed_loop.h) makes of each:
//   nan-sample       q[0] of every sample from T on is NaN   -> tick_bad_sample (the tick's status)
//   inf-sample       qd[0] of every sample from T on is +inf -> tick_bad_sample
//   encoder-jump     q[0] of every sample from T on is 0.5 rad off (one jump) -> encoder_jump
//   frozen           from T on the device repeats the first sample at or after T (time included)
//                    -> non_monotonic_time on the second repeat
//   clock-backwards  from T on the device clock reads two nominal periods early (it steps back
//                    once) -> non_monotonic_time
//   late-tick        from T on the device clock reads four nominal periods late: one sample comes
//                    5 periods after the last (missed ticks). Recovery, not a fault: the loop
//                    hands the pipeline the measured tick length (PMI takes a varying T_k)
//   device-loss      from T on the device reports kFaultSchedulerStopped (its clock no longer
//                    calls the loop: a lost device) and repeats its last sample
//                    -> scheduler_stopped, zero torque written at once
#pragma once

#include <string>

#include "device/device.h"

namespace dentsim {

struct InjectedFault {
  enum Kind {
    kNone,
    kNanSample,
    kInfSample,
    kEncoderJump,
    kFrozen,
    kClockBackwards,
    kLateTick,
    kDeviceLoss
  };
  Kind kind = kNone;
  double at_s = 0.0;  // device time from which the fault is present [s]
};

// Parses "KIND@T" (kinds above, T finite and >= 0). Throws InputError naming `what` (the flag)
// and the accepted forms otherwise.
InjectedFault parse_injected_fault(const std::string& text, const std::string& what);
// "nan-sample@2.5"
std::string injected_fault_string(const InjectedFault& f);

class FaultInjectingDevice : public Device {
 public:
  // `inner` must outlive the decorator.
  FaultInjectingDevice(Device& inner, InjectedFault fault)
      : inner_(inner), fault_(fault), held_(inner.make_sample()) {}

  const DeviceCapabilities& capabilities() const override { return inner_.capabilities(); }
  const DeviceLimits& limits() const override { return inner_.limits(); }
  void read(DeviceSample& out) const override;
  void write(const VecX& tau) override { inner_.write(tau); }
  void advance() override { inner_.advance(); }
  const VecX& applied_torque() const override { return inner_.applied_torque(); }
  std::uint32_t faults() const override {
    return inner_.faults() | (lost_ ? kFaultSchedulerStopped : kFaultNone);
  }
  void clear_faults() override { inner_.clear_faults(); }

 private:
  Device& inner_;
  InjectedFault fault_;
  // frozen / device-loss: the sample the device keeps repeating (preallocated: no allocation in
  // read()), whether it was captured, and whether the device is lost.
  mutable DeviceSample held_;
  mutable bool holding_ = false;
  mutable bool lost_ = false;
};

}  // namespace dentsim
