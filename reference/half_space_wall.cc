#include "reference/half_space_wall.h"

#include <utility>

namespace dentsim {

HalfSpaceWall::HalfSpaceWall(Vec3 point, Vec3 normal, double tip_radius, double stiffness,
                             double damping)
    : p_(std::move(point)), n_(normal.normalized()), rho_(tip_radius), k_(stiffness), b_(damping) {}

double HalfSpaceWall::depth(const Vec3& x) const { return rho_ - n_.dot(x - p_); }

bool HalfSpaceWall::contacts(const Pose& proxy, std::vector<Contact>& out) {
  out.clear();
  const double d = depth(proxy.x);
  if (d <= 0.0) return true;
  if (out.capacity() == 0) return false;
  Contact c;
  const Vec3 x_c = proxy.x - rho_ * n_;         // deepest point of the tip sphere
  c.x_o = x_c + d * n_;                          // its projection on the wall surface
  c.n = n_;
  c.r = proxy.R.transpose() * (x_c - proxy.x);  // body frame
  c.depth = d;
  c.stiffness = k_;
  c.damping = b_;
  c.weight = 1.0;
  out.push_back(c);
  return true;
}

}  // namespace dentsim
