// Tests for fast/grasp_mass_model.h: the hand's terms M_h = J_t^T diag(Mt) J_t and C_h^T qd =
// dJ_t/dt^T (Mt .* V1) two entries at a time against the reference's grasp_mass_terms
// (reference/grasp_mass_model.h), bitwise (a zero's sign counts): random Jacobians and rates over
// six decades, the model's Mt = (m, m, m, j, j, j) and general diagonals, zeros and non-finite
// entries among them. Seeds fixed.
#include "fast/grasp_mass_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "reference/grasp_mass_model.h"
#include "tests/fast/bitwise.h"
#include "tests/support/random.h"

namespace dentsim {
namespace {

using Rng = std::mt19937_64;

double uni(Rng& rng, double a, double b) { return testing::uniform(rng, a, b); }

TEST(FastGraspMass, TermsAreTheReferencesBitwise) {
  Rng rng(4804);
  int unequal = 0, checked = 0;
  for (int trial = 0; trial < 50000; ++trial) {
    DeviceTerms t;
    for (int i = 0; i < 36; ++i) {
      t.J_t(i) = uni(rng, -1.0, 1.0) * std::pow(10.0, uni(rng, -3.0, 3.0));
      t.J_t_dot(i) = uni(rng, -1.0, 1.0) * std::pow(10.0, uni(rng, -3.0, 3.0));
    }
    if (trial % 10 == 0) t.J_t(trial % 36) = 0.0;
    if (trial % 101 == 0) t.J_t(trial % 36) = std::numeric_limits<double>::quiet_NaN();
    if (trial % 103 == 0) t.J_t_dot(trial % 36) = std::numeric_limits<double>::infinity();
    Vec6 Mt;
    if (trial % 2 == 0) {  // the grasp model's diag(m I, j I)
      const double m = trial % 20 == 0 ? 0.0 : std::pow(10.0, uni(rng, -3.0, 0.0));
      const double j = std::pow(10.0, uni(rng, -7.0, -4.0));
      Mt << m, m, m, j, j, j;
    } else {
      for (int i = 0; i < 6; ++i) Mt(i) = std::pow(10.0, uni(rng, -7.0, 1.0));
    }
    Vec6 V1;
    for (int i = 0; i < 6; ++i) V1(i) = uni(rng, -2.0, 2.0);
    Mat6 M_ref, M_fast;
    Vec6 C_ref, C_fast;
    grasp_mass_terms(Mt, t, V1, &M_ref, &C_ref);
    M_fast.setConstant(-1.0);  // every entry must be written
    C_fast.setConstant(-1.0);
    fast::grasp_mass_terms(Mt, t, V1, &M_fast, &C_fast);
    unequal += testing::unequal_entries(M_fast, M_ref) + testing::unequal_entries(C_fast, C_ref);
    checked += 42;
  }
  EXPECT_EQ(unequal, 0) << "of " << checked << " entries";
}

}  // namespace
}  // namespace dentsim
