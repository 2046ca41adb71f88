// Seeded random states of the Phantom for property and differential tests: q uniform in the
// joint-limit box of `p` (widened by `pad` rad on each side), qd uniform in [-scale, scale] rad/s.
// The seed is printed (docs/tolerance_policy.md, rule 7).
#pragma once

#include <cstdint>
#include <cstdio>
#include <random>

#include "reference/core/types.h"
#include "reference/phantom/phantom_params.h"

namespace dentsim::testing {

class PhantomStates {
 public:
  PhantomStates(const PhantomParams& p, std::uint64_t seed) : p_(p), rng_(seed) {
    std::printf("seed %llu (fixed)\n", static_cast<unsigned long long>(seed));
  }
  Vec6 q(double pad = 0.0) {
    Vec6 q;
    for (int j = 0; j < 6; ++j) {
      const double lo = p_.q_min_rad(j) - pad, hi = p_.q_max_rad(j) + pad;
      q(j) = lo + u_(rng_) * (hi - lo);
    }
    return q;
  }
  Vec6 qd(double scale = 3.0) {
    Vec6 v;
    for (int j = 0; j < 6; ++j) v(j) = scale * (2.0 * u_(rng_) - 1.0);
    return v;
  }

 private:
  PhantomParams p_;
  std::mt19937_64 rng_;
  std::uniform_real_distribution<double> u_{0.0, 1.0};
};

}  // namespace dentsim::testing
