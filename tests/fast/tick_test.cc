// The fast tick against the reference (issues #14 "Differential testing" and #31), driven by the
// registry (fast/registry.h) through validation/crosscheck_fast.h — the same code as `dentsim
// crosscheck fast`: every stage of every implementation (and its stages chained) on every method,
// with and without the grip detector, both contact models and the three built-in scenes (contact,
// sliding, drilling), and the default scenes in closed loop. That each row can fail is
// tests/validation/crosscheck_fast_test.cc's.
// Tolerances: docs/tolerance_policy.md "fast vs reference".
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "fast/registry.h"
#include "tests/support/crosscheck_rows.h"
#include "tests/support/stress.h"
#include "validation/crosscheck_fast.h"

namespace dentsim {
namespace {

TEST(FastTick, RegistryHoldsTheReferenceAndTheFastPipeline) {
  ASSERT_GE(stage_tables().size(), 2u);
  EXPECT_STREQ(stage_tables()[0]->implementation, "reference");
  ASSERT_NE(find_stage_table("fast"), nullptr);
  EXPECT_EQ(find_stage_table("float-magic"), nullptr);
  for (const StageTable* t : stage_tables()) {
    for (int i = 0; i < kStageCount; ++i) EXPECT_NE(t->stage[i], nullptr) << t->implementation;
  }
}

// Every row of a run within the bound, with enough contact to mean something.
void expect_rows_agree(const FastCrosscheckOptions& o, const FastCrosscheckResult& r) {
  for (const std::string& f : r.failures) ADD_FAILURE() << f;
  EXPECT_TRUE(r.ok);
  const std::size_t implementations = stage_tables().size() - 1;
  // Per configuration: the stages without the shared ones (observe, command), plus the chain row.
  ASSERT_EQ(r.shared.size(), 2u * implementations);
  const std::size_t rows = static_cast<std::size_t>(kStageCount) - 2 + 1;
  ASSERT_EQ(r.stages.size(), rows * o.stage_configs.size() * implementations);
  for (const StageCrosscheck& s : r.stages) testing::expect_stage_row_agrees(o, s);
  // Adversarial states (validation/crosscheck_fast.h): tick lengths 1e-5 to 1e-2 s, the proxy's
  // rotation near 0 and near pi, saturation, a deeper proxy, no friction; every compared stage but
  // drill.
  ASSERT_EQ(r.adversarial.size(),
            8u * (kStageCount - 3) * o.stage_configs.size() * implementations);
  for (const AdversarialCrosscheck& a : r.adversarial) {
    EXPECT_LE(a.max_rel, o.max_rel_bound) << a.config << " " << a.perturbation << " " << a.stage;
    EXPECT_EQ(a.count_mismatches, 0) << a.config << " " << a.perturbation << " " << a.stage;
    EXPECT_GT(a.samples, o.stage_ticks / 9) << a.perturbation;  // one tick in 8
    if (a.perturbation == "saturation") {
      EXPECT_EQ(a.saturated_samples, a.samples) << a.config;
    }
  }
}

// CI's form: each (method, grip detector, contact model) once, the three built-in scenes in turn
// (validation/crosscheck_fast.h stage_config_cover), 1500 ticks each (contact from 0.9-1.3 s on),
// and the closed loop on the three default scenes for 2.5 s.
TEST(FastTick, EveryMethodAndContactModelAgreeWithTheReference) {
  FastCrosscheckOptions o;
  o.stage_configs = stage_config_cover({"drill", "probe", "probe-groove"});
  ASSERT_EQ(o.stage_configs.size(), 12u);
  o.stage_ticks = 1500;
  o.scene_duration_s = 2.5;
  const FastCrosscheckResult r = crosscheck_fast(o);
  expect_rows_agree(o, r);
  ASSERT_EQ(r.scenes.size(), o.scenes.size() * (stage_tables().size() - 1));
  for (const SceneCrosscheck& c : r.scenes) {
    std::printf("%s %s: max force diff %.3e N (largest force %.3f N), before contact %.3e N\n",
                c.implementation.c_str(), c.scene.c_str(), c.max_force_diff_n, c.max_force_n,
                c.max_force_diff_before_contact_n);
    EXPECT_GT(c.contact_ticks, 0) << c.scene;
    EXPECT_LE(c.max_force_diff_before_contact_n, 1e-9) << c.scene;
  }
}

// The long form (DENTSIM_STRESS=full): the whole matrix, 36 configurations, 2500 ticks each with
// the adversarial states. The short form (CI) only builds the 12 combinations' rigs on the drill
// scene and checks 50 free-space ticks without them (the test above covers the combinations).
TEST(FastTickStress, TheWholeMatrixAgreesWithTheReference) {
  FastCrosscheckOptions o;
  o.stage_ticks = testing::stress_count(50, 2500);
  if (!testing::stress_full()) {
    o.stage_configs = stage_config_matrix({"drill"});
    o.adversarial = false;
  }
  o.scenes.clear();
  const FastCrosscheckResult r = crosscheck_fast(o);
  for (const std::string& f : r.failures) ADD_FAILURE() << f;
  EXPECT_TRUE(r.ok);
  EXPECT_EQ(r.stages.size(), 6u * o.stage_configs.size() * (stage_tables().size() - 1));
  for (const StageCrosscheck& s : r.stages) {
    EXPECT_LE(s.max_rel, o.max_rel_bound) << s.config << " " << s.stage;
    EXPECT_EQ(s.count_mismatches, 0) << s.config << " " << s.stage;
    if (testing::stress_full()) {
      EXPECT_GT(s.contact_samples, s.samples / 10) << s.config;
    }
  }
}

}  // namespace
}  // namespace dentsim
