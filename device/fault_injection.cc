#include "device/fault_injection.h"

#include <cmath>
#include <limits>
#include <sstream>

#include "reference/core/io.h"

namespace dentsim {
namespace {

const char* kind_name(InjectedFault::Kind k) {
  switch (k) {
    case InjectedFault::kNanSample:
      return "nan-sample";
    case InjectedFault::kInfSample:
      return "inf-sample";
    case InjectedFault::kEncoderJump:
      return "encoder-jump";
    case InjectedFault::kFrozen:
      return "frozen";
    case InjectedFault::kClockBackwards:
      return "clock-backwards";
    case InjectedFault::kLateTick:
      return "late-tick";
    case InjectedFault::kDeviceLoss:
      return "device-loss";
    case InjectedFault::kNone:
      break;
  }
  return "none";
}

constexpr InjectedFault::Kind kKinds[] = {InjectedFault::kNanSample,      InjectedFault::kInfSample,
                                          InjectedFault::kEncoderJump,    InjectedFault::kFrozen,
                                          InjectedFault::kClockBackwards, InjectedFault::kLateTick,
                                          InjectedFault::kDeviceLoss};

}  // namespace

InjectedFault parse_injected_fault(const std::string& text, const std::string& what) {
  const auto fail = [&](const std::string& why) {
    std::ostringstream m;
    m << what << " '" << text << "': " << why
      << "expected KIND@T with KIND one of nan-sample, inf-sample, encoder-jump, frozen, "
         "clock-backwards, late-tick, device-loss and T >= 0 [s]";
    throw InputError(m.str());
  };
  const auto at = text.find('@');
  if (at == std::string::npos) fail("");
  const std::string kind = text.substr(0, at), time = text.substr(at + 1);
  InjectedFault f;
  for (InjectedFault::Kind k : kKinds) {
    if (kind == kind_name(k)) f.kind = k;
  }
  if (f.kind == InjectedFault::kNone) fail("unknown kind '" + kind + "'; ");
  std::size_t used = 0;
  double t = 0.0;
  try {
    t = std::stod(time, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != time.size() || !std::isfinite(t) || t < 0.0) {
    fail("bad time '" + time + "'; ");
  }
  f.at_s = t;
  return f;
}

std::string injected_fault_string(const InjectedFault& f) {
  std::ostringstream s;
  s << kind_name(f.kind);
  if (f.kind != InjectedFault::kNone) s << '@' << f.at_s;
  return s.str();
}

void FaultInjectingDevice::read(DeviceSample& out) const {
  if (holding_) {  // frozen or lost: the same sample again
    out.q = held_.q;
    out.qd = held_.qd;
    out.t = held_.t;
    return;
  }
  inner_.read(out);
  if (out.t < fault_.at_s) return;
  const double T = inner_.capabilities().nominal_period;
  switch (fault_.kind) {
    case InjectedFault::kEncoderJump:
      out.q(0) += 0.5;
      break;
    case InjectedFault::kFrozen:
    case InjectedFault::kDeviceLoss:
      held_.q = out.q;
      held_.qd = out.qd;
      held_.t = out.t;
      holding_ = true;
      lost_ = fault_.kind == InjectedFault::kDeviceLoss;
      break;
    case InjectedFault::kClockBackwards:
      out.t -= 2.0 * T;
      break;
    case InjectedFault::kLateTick:
      out.t += 4.0 * T;
      break;
    case InjectedFault::kNanSample:
      out.q(0) = std::numeric_limits<double>::quiet_NaN();
      break;
    case InjectedFault::kInfSample:
      out.qd(0) = std::numeric_limits<double>::infinity();
      break;
    case InjectedFault::kNone:
      break;
  }
}

}  // namespace dentsim
