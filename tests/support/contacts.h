// Contacts placed on a proxy for contact tests.
#pragma once

#include "reference/core/params.h"
#include "reference/core/types.h"

namespace dentsim::testing {

// A contact at body offset r whose surface point x_o sits `depth` beyond the contact point
// x_c = x + R r along n (depth > 0 penetrates; the wrench recomputes it from the pose).
inline Contact make_contact(const Pose& p, const Vec3& n, const Vec3& r, double depth, double K,
                            double B = 0.0, double weight = 1.0) {
  Contact c;
  c.n = n;
  c.r = r;
  c.x_o = p.x + p.R * r + depth * n;
  c.depth = depth;
  c.stiffness = K;
  c.damping = B;
  c.weight = weight;
  return c;
}

}  // namespace dentsim::testing
