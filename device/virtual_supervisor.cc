#include "device/virtual_supervisor.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "reference/core/io.h"

namespace dentsim {

const char* supervisor_fault_name(SupervisorFault f) {
  switch (f) {
    case SupervisorFault::kNone: return "none";
    case SupervisorFault::kNonFinite: return "virtual_non_finite";
    case SupervisorFault::kContactForce: return "contact_force_beyond_bound";
    case SupervisorFault::kCouplingForce: return "coupling_force_beyond_bound";
    case SupervisorFault::kProxyTooDeep: return "proxy_too_deep";
    case SupervisorFault::kProxyTooFar: return "proxy_too_far";
    case SupervisorFault::kEnergyGrowth: return "virtual_energy_growth";
    case SupervisorFault::kLateTick: return "tick_too_late";
  }
  return "unknown";
}

void validate_supervisor_limits(const SupervisorLimits& l) {
  const auto need = [](bool ok, const char* field, double v, const char* expected) {
    if (!ok) {
      throw InputError(std::string("supervisor.") + field + " = " + std::to_string(v) +
                       " (expected " + expected + ")");
    }
  };
  need(std::isfinite(l.peak_force_n) && l.peak_force_n > 0.0, "peak_force_n", l.peak_force_n,
       "a finite force > 0 N");
  need(std::isfinite(l.force_bound_multiple) && l.force_bound_multiple > 0.0,
       "force_bound_multiple", l.force_bound_multiple, "a finite multiple > 0");
  need(std::isfinite(l.tool_radius_m), "tool_radius_m", l.tool_radius_m, "finite");
  need(std::isfinite(l.max_separation_m), "max_separation_m", l.max_separation_m, "finite");
  need(std::isfinite(l.energy_tolerance_j), "energy_tolerance_j", l.energy_tolerance_j, "finite");
  need(std::isfinite(l.nominal_period_s) && l.nominal_period_s > 0.0, "nominal_period_s",
       l.nominal_period_s, "a finite period > 0 s");
  need(std::isfinite(l.max_tick_s), "max_tick_s", l.max_tick_s, "finite");
}

VirtualSupervisor::VirtualSupervisor(const SupervisorLimits& limits) : limits_(limits) {
  validate_supervisor_limits(limits_);
}

std::string VirtualSupervisor::describe() const {
  char b[160];
  switch (fault_) {
    case SupervisorFault::kNone: return "";
    case SupervisorFault::kNonFinite: return "a non-finite value in the proxy or the command";
    case SupervisorFault::kContactForce:
    case SupervisorFault::kCouplingForce:
      std::snprintf(b, sizeof b, "|f| = %.4g N > %.4g N = %.4g x the device's peak force", value_,
                    limits_.force_bound_n(), limits_.force_bound_multiple);
      return b;
    case SupervisorFault::kProxyTooDeep:
      std::snprintf(b, sizeof b, "depth %.4g mm > the tool's radius %.4g mm + F_bound / K",
                    value_ * 1e3, limits_.tool_radius_m * 1e3);
      return b;
    case SupervisorFault::kProxyTooFar:
      std::snprintf(b, sizeof b, "proxy %.4g mm from the device > %.4g mm", value_ * 1e3,
                    limits_.max_separation_m * 1e3);
      return b;
    case SupervisorFault::kEnergyGrowth:
      std::snprintf(b, sizeof b, "the contact returned %.4g J > %.4g J", value_,
                    limits_.energy_tolerance_j);
      return b;
    case SupervisorFault::kLateTick:
      std::snprintf(b, sizeof b, "a tick of %.4g ms > %.4g ms", value_ * 1e3,
                    limits_.tick_bound_s() * 1e3);
      return b;
  }
  return "";
}

double VirtualSupervisor::depth_bound(const TickResult& r) const noexcept {
  // The softest member's compression at the force bound: a penalty contact sinks that far to
  // render it.
  double k_min = 0.0;
  for (const Contact& c : r.contacts) {
    if (c.stiffness > 0.0 && (k_min == 0.0 || c.stiffness < k_min)) k_min = c.stiffness;
  }
  return limits_.tool_radius_m + (k_min > 0.0 ? limits_.force_bound_n() / k_min : 0.0);
}

SupervisorFault VirtualSupervisor::check(const TickResult& r, const ProxyState& proxy,
                                         double T) noexcept {
  if (fault_ != SupervisorFault::kNone) return fault_;
  SupervisorFault f = SupervisorFault::kNone;
  double v = 0.0;
  if (T > 1.5 * limits_.nominal_period_s) ++late_ticks_;
  if (T > max_tick_s_) max_tick_s_ = T;
  const double tick_bound = limits_.tick_bound_s();
  if (tick_bound > 0.0 && T > tick_bound) {
    f = SupervisorFault::kLateTick;
    v = T;
  } else if (!proxy.pose.x.allFinite() || !proxy.pose.R.allFinite() || !proxy.V.allFinite() ||
      !r.V_hat.allFinite() || !r.F_contact.allFinite() || !r.F_coupling.allFinite() ||
      !r.T1.allFinite() || !r.tau.allFinite() || !std::isfinite(r.max_depth)) {
    f = SupervisorFault::kNonFinite;
  } else {
    const double bound = limits_.force_bound_n();
    const double fc = r.F_contact.head<3>().norm();
    const double fv = std::max(r.F_coupling.head<3>().norm(), r.T1_vc.head<3>().norm());
    const double sep = (proxy.pose.x - r.device.x).norm();
    contact_work_ += T * r.V_hat.dot(r.F_contact);
    if (fc > bound) {
      f = SupervisorFault::kContactForce;
      v = fc;
    } else if (fv > bound) {
      f = SupervisorFault::kCouplingForce;
      v = fv;
    } else if (limits_.tool_radius_m > 0.0 && r.max_depth > depth_bound(r)) {
      f = SupervisorFault::kProxyTooDeep;
      v = r.max_depth;
    } else if (limits_.max_separation_m > 0.0 && sep > limits_.max_separation_m) {
      f = SupervisorFault::kProxyTooFar;
      v = sep;
    } else if (limits_.energy_tolerance_j > 0.0 && contact_work_ > limits_.energy_tolerance_j) {
      f = SupervisorFault::kEnergyGrowth;
      v = contact_work_;
    }
  }
  fault_ = f;
  value_ = v;
  return f;
}

}  // namespace dentsim
