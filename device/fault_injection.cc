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
    case InjectedFault::kNone:
      break;
  }
  return "none";
}

}  // namespace

InjectedFault parse_injected_fault(const std::string& text, const std::string& what) {
  const auto fail = [&](const std::string& why) {
    std::ostringstream m;
    m << what << " '" << text << "': " << why
      << "expected KIND@T with KIND nan-sample or inf-sample and T >= 0 [s]";
    throw InputError(m.str());
  };
  const auto at = text.find('@');
  if (at == std::string::npos) fail("");
  const std::string kind = text.substr(0, at), time = text.substr(at + 1);
  InjectedFault f;
  if (kind == "nan-sample") {
    f.kind = InjectedFault::kNanSample;
  } else if (kind == "inf-sample") {
    f.kind = InjectedFault::kInfSample;
  } else {
    fail("unknown kind '" + kind + "'; ");
  }
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
  inner_.read(out);
  if (out.t < fault_.at_s) return;
  switch (fault_.kind) {
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
