// Seeded random geometry for property tests.
#pragma once

#include <random>

#include "reference/core/so3.h"
#include "reference/core/types.h"

namespace dentsim::testing {

// A number uniformly distributed in [a, b).
template <class Rng>
double uniform(Rng& rng, double a, double b) {
  return std::uniform_real_distribution<double>(a, b)(rng);
}

// A direction uniformly distributed on the unit sphere.
template <class Rng>
Vec3 random_unit(Rng& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Vec3(n(rng), n(rng), n(rng)).normalized();
}

}  // namespace dentsim::testing
