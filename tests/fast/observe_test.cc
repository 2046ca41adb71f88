// Tests for the fast observe stage's grip filter step (fast/tick.h grip_filter_update_kept): its
// three gains kept by tick length (reference/core/pipeline.h GripGainMemo) give the reference's
// grip_filter_update (reference/grip_detector.h) bitwise, every field of the filter's state and
// its decision, over tick lengths as a clock measures them (t_k - t_k-1 of t_k = k T0, a few
// values apart by round-off), more distinct lengths than the memo keeps (each evicted and met
// again), a zero's sign and NaN. Seeds fixed.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <utility>
#include <vector>

#include "fast/tick.h"
#include "reference/grip_detector.h"
#include "tests/fast/bitwise.h"
#include "tests/support/random.h"

namespace dentsim {
namespace {

using Rng = std::mt19937_64;

int unequal_states(const GripFilterState& a, const GripFilterState& b) {
  int n = testing::unequal_entries(a.h0, b.h0) + testing::unequal_entries(a.h1, b.h1) +
          testing::unequal_entries(a.b0, b.b0) + testing::unequal_entries(a.b1, b.b1) +
          testing::unequal_entries(a.lp0, b.lp0) + testing::unequal_entries(a.lp1, b.lp1);
  for (const auto& [x, y] : {std::pair{a.p0, b.p0}, std::pair{a.p1, b.p1},
                             std::pair{a.g_release, b.g_release}, std::pair{a.g_grip, b.g_grip}}) {
    n += testing::same_double(x, y) ? 0 : 1;
  }
  return n + (a.gripped == b.gripped ? 0 : 1);
}

TEST(FastObserve, GripFilterWithKeptGainsIsTheReferencesBitwise) {
  Rng rng(5101);
  GripDetectorParams p;
  p.evidence = 1e-4;  // decisions both ways within the run
  const Vec6 norm = (Vec6() << 2.5, 2.5, 2.5, 0.0, 0.0, 0.0).finished();
  // Tick lengths: a measured 1 kHz and 8 kHz clock (t_k - t_k-1), seven fixed lengths drawn at
  // random (more than the memo's four), +-0 and NaN.
  std::vector<double> Ts;
  for (const double T0 : {1e-3, 1.25e-4}) {
    for (int k = 1; k < 4000; ++k) Ts.push_back(k * T0 - (k - 1) * T0);
  }
  const double fixed[] = {1e-3, 2e-3, 5e-4, 1e-5, 1e-2, 3.3e-4, 7e-4};
  std::uniform_int_distribution<int> pick(0, 6);
  for (int k = 0; k < 4000; ++k) Ts.push_back(fixed[pick(rng)]);
  Ts.push_back(0.0);
  Ts.push_back(-0.0);
  Ts.push_back(1e-3);
  Ts.push_back(std::numeric_limits<double>::quiet_NaN());
  Ts.push_back(1e-3);
  int distinct_before = 0;
  {
    std::vector<double> seen;
    for (double T : Ts) {
      bool found = false;
      for (double s : seen) found = found || s == T;
      if (!found && T == T) seen.push_back(T);
    }
    distinct_before = static_cast<int>(seen.size());
  }
  EXPECT_GT(distinct_before, GripGainMemo::kSize + 2);  // the memo evicts
  for (const bool start : {true, false}) {
    p.start_gripped = start;
    GripFilterState ref, fast;
    grip_filter_reset(p, ref);
    grip_filter_reset(p, fast);
    GripGainMemo memo;
    int unequal = 0, flips = 0;
    bool last = ref.gripped;
    for (std::size_t k = 0; k < Ts.size(); ++k) {
      // Estimates of a few N with a hand-like slow part and a fast part in one hypothesis.
      Vec6 h0, h1;
      for (int i = 0; i < 6; ++i) {
        h0(i) = testing::uniform(rng, -3.0, 3.0);
        h1(i) = h0(i) + (k / 500 % 2 ? 0.5 : 0.01) * testing::uniform(rng, -1.0, 1.0);
      }
      const bool a = grip_filter_update(p, norm, ref, h0, h1, Ts[k]);
      const bool b = fast::grip_filter_update_kept(p, norm, fast, memo, h0, h1, Ts[k]);
      unequal += (a == b ? 0 : 1) + unequal_states(ref, fast);
      flips += a != last ? 1 : 0;
      last = a;
      if (!(Ts[k] == Ts[k])) {  // NaN poisons the state: start again from the reset
        grip_filter_reset(p, ref);
        grip_filter_reset(p, fast);
      }
    }
    EXPECT_EQ(unequal, 0) << "start gripped " << start;
    EXPECT_GT(flips, 2) << "the decision must change within the run";
  }
}

}  // namespace
}  // namespace dentsim
