// Bitwise comparison of doubles for the fast twins that do the reference's own operations
// (fast/coupling.h, fast/encoder_kalman.h, fast/grasp_mass_model.h): equal as bit patterns, so a
// zero's sign counts; two NaNs count as equal (their payloads are not compared).
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>

namespace dentsim::testing {

inline bool same_double(double a, double b) {
  if (std::isnan(a) && std::isnan(b)) return true;
  std::uint64_t ua = 0, ub = 0;
  std::memcpy(&ua, &a, sizeof a);
  std::memcpy(&ub, &b, sizeof b);
  return ua == ub;
}

// The entries of a and b (Eigen objects of one size) that are not the same double.
template <class A, class B>
int unequal_entries(const A& a, const B& b) {
  int n = 0;
  for (int i = 0; i < a.size(); ++i) n += same_double(a.data()[i], b.data()[i]) ? 0 : 1;
  return n;
}

}  // namespace dentsim::testing
