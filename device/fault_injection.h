// Device faults injected for tests and drills (`dentsim run --inject-fault KIND@T`): a Device
// decorator that corrupts what the wrapped device reports from time T on, so the whole chain
// behind it — the tick's status, the loop owner's latch to zero torque, the report — is exercised
// exactly as a faulty driver would exercise it.
//
// Kinds (KIND@T, T [s] on the device clock):
//   nan-sample   q[0] of every sample from T on is NaN   -> the tick returns kBadSample
//   inf-sample   qd[0] of every sample from T on is +inf -> the tick returns kBadSample
#pragma once

#include <string>

#include "device/device.h"

namespace dentsim {

struct InjectedFault {
  enum Kind { kNone, kNanSample, kInfSample };
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
  FaultInjectingDevice(Device& inner, InjectedFault fault) : inner_(inner), fault_(fault) {}

  const DeviceCapabilities& capabilities() const override { return inner_.capabilities(); }
  const DeviceLimits& limits() const override { return inner_.limits(); }
  void read(DeviceSample& out) const override;
  void write(const VecX& tau) override { inner_.write(tau); }
  void advance() override { inner_.advance(); }
  const VecX& applied_torque() const override { return inner_.applied_torque(); }
  std::uint32_t faults() const override { return inner_.faults(); }
  void clear_faults() override { inner_.clear_faults(); }

 private:
  Device& inner_;
  InjectedFault fault_;
};

}  // namespace dentsim
