// Seeded random geometry for property tests.
#pragma once

#include <random>

#include "reference/core/so3.h"
#include "reference/core/types.h"

namespace dentsim::testing {

// A direction uniformly distributed on the unit sphere.
inline Vec3 random_unit(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Vec3(n(rng), n(rng), n(rng)).normalized();
}

}  // namespace dentsim::testing
