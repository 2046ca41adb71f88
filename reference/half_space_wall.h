// A flat wall as a contact provider: the half-space {y : n^T (y - point) <= 0} touched by the
// tool tip, a sphere of radius `tip_radius` centred at the proxy origin. Used by the Z-width rig,
// the wall loop, the demo, the tick's tests and the benchmarks.
//
// One contact when the sphere penetrates: depth d = rho - n^T (x2 - point) > 0, the deepest point
// of the sphere x_c = x2 - rho n (r = R2^T (x_c - x2) in the body frame), x_o = x_c + d n on the
// wall, stiffness K and damping B as given, weight 1.
#pragma once

#include "reference/core/contact_provider.h"

namespace dentsim {

class HalfSpaceWall : public ContactProvider {
 public:
  HalfSpaceWall(Vec3 point, Vec3 normal, double tip_radius, double stiffness, double damping);
  bool contacts(const Pose& proxy, std::vector<Contact>& out) override;
  // Penetration of a sphere centred at x (>0 inside the wall).
  double depth(const Vec3& x) const;
  const Vec3& normal() const { return n_; }

 private:
  Vec3 p_, n_;
  double rho_, k_, b_;
};

}  // namespace dentsim
