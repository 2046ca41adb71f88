#include <cstdio>

#include "device/device.h"
#include "reference/tooth/materials.h"
#include "view/view.h"

namespace dentsim::view {

std::vector<std::string> overlay_lines(const std::string& method, const TickSnapshot& s,
                                       double median_us, double p99_us) {
  std::vector<std::string> out;
  char buf[160];
  std::snprintf(buf, sizeof buf, "method %s   t = %.3f s", method.c_str(), s.t);
  out.emplace_back(buf);
  std::snprintf(buf, sizeof buf, "tick time median %.1f us, p99 %.1f us", median_us, p99_us);
  out.emplace_back(buf);
  std::snprintf(buf, sizeof buf, "force: on device %.2f N, on proxy %.2f N, %d contacts",
                s.device_force_n.norm(), s.contact_force_n.norm(), s.contacts);
  out.emplace_back(buf);
  std::snprintf(buf, sizeof buf, "removed mm^3: enamel %.4f  dentin %.4f  pulp %.4f",
                s.removed_volume_mm3[kEnamel], s.removed_volume_mm3[kDentin],
                s.removed_volume_mm3[kPulp]);
  out.emplace_back(buf);
  out.emplace_back("faults: " + (s.faults == 0 ? std::string("none") : fault_string(s.faults)));
  return out;
}

}  // namespace dentsim::view
