#include "reference/saturation_passive.h"

#include <algorithm>
#include <cmath>

namespace dentsim {

double deliverable_force(const Mat6& J_t, const Vec6& torque_limit, const Vec6& tau_gravity,
                         const Vec3& u, double headroom) {
  Vec6 w = Vec6::Zero();
  w.head<3>() = u;
  const Vec6 a = J_t.transpose() * w;  // joint torque per newton along u
  double F = INFINITY;
  for (int i = 0; i < 6; ++i) {
    const double L = torque_limit(i) * (1.0 - headroom);
    if (std::abs(tau_gravity(i)) > L) return 0.0;
    if (a(i) == 0.0) continue;
    F = std::min(F, (L - std::copysign(1.0, a(i)) * tau_gravity(i)) / std::abs(a(i)));
  }
  if (!std::isfinite(F)) return 0.0;  // u maps to no joint torque (or not finite): no claim
  return std::max(F, 0.0);
}

double feasible_feedforward_scale(const Vec6& a, const Vec6& b, const Vec6& torque_limit,
                                  double headroom) {
  double sigma = 1.0;
  for (int i = 0; i < 6; ++i) {
    if (b(i) == 0.0) continue;
    const double L = torque_limit(i) * (1.0 - headroom);
    sigma = std::min(sigma, (L - std::copysign(1.0, b(i)) * a(i)) / std::abs(b(i)));
  }
  if (!(sigma >= 0.0)) return 0.0;  // also NaN
  return sigma;
}

bool cap_coupling_spring(double k_lin, const Vec3& x1, const Vec3& x2, double cap,
                         AffineWrench* proxy_side, Vec6* device_side) {
  const Vec3 e = x2 - x1;
  const double stretch = e.norm();
  const double force = k_lin * stretch;
  if (!(force > cap) || stretch == 0.0) return false;
  // Remove the spring's excess over the cap along e: the proxy is pulled by -k e, the device by
  // +k e; both become cap e / |e|.
  const Vec3 excess = (force - cap) / stretch * e;
  proxy_side->f0.head<3>() += excess;
  device_side->head<3>() -= excess;
  return true;
}

}  // namespace dentsim
