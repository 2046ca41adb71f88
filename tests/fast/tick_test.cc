// The fast tick against the reference (issue #14 "Differential testing"), driven by the registry
// (fast/registry.h) through validation/crosscheck_fast.h — the same code as `dentsim crosscheck
// fast`: every stage of every implementation on the drill scene's states (with the hand's mass
// and the grip detector on, contact and drilling), and both built-in scenes in closed loop.
// Tolerances: docs/tolerance_policy.md "fast vs reference".
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "fast/registry.h"
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

TEST(FastTick, EveryStageAndTheClosedLoopAgreeWithTheReference) {
  FastCrosscheckOptions o;
  o.stage_ticks = 2500;
  o.scene_duration_s = 2.5;
  const FastCrosscheckResult r = crosscheck_fast(o);
  for (const std::string& f : r.failures) ADD_FAILURE() << f;
  EXPECT_TRUE(r.ok);
  ASSERT_EQ(r.stages.size(), static_cast<std::size_t>(kStageCount) * (stage_tables().size() - 1));
  for (const StageCrosscheck& s : r.stages) {
    std::printf("%s %-13s max_rel %.3e (%ld samples, %ld in contact)\n", s.implementation.c_str(),
                s.stage.c_str(), s.max_rel, s.samples, s.contact_samples);
    EXPECT_LE(s.max_rel, 1e-9) << s.stage;
    EXPECT_EQ(s.count_mismatches, 0) << s.stage;
    EXPECT_EQ(s.samples, o.stage_ticks);
    // A check that barely met contact would prove little (docs/conventions.md "Tests").
    EXPECT_GT(s.contact_samples, s.samples / 10) << s.stage;
  }
  // Adversarial states (validation/crosscheck_fast.h): tick lengths 1e-5 to 1e-2 s, the proxy's
  // rotation near 0 and near pi, saturation, a deeper proxy; every stage but drill.
  ASSERT_EQ(r.adversarial.size(), 7u * (kStageCount - 1) * (stage_tables().size() - 1));
  for (const AdversarialCrosscheck& a : r.adversarial) {
    EXPECT_LE(a.max_rel, 1e-9) << a.perturbation << " " << a.stage;
    EXPECT_EQ(a.count_mismatches, 0) << a.perturbation << " " << a.stage;
    EXPECT_GT(a.samples, o.stage_ticks / 8) << a.perturbation;
    EXPECT_GT(a.contact_samples, a.samples / 2) << a.perturbation;
    if (a.perturbation == "saturation" || a.perturbation == "rotation_near_pi") {
      EXPECT_EQ(a.saturated_samples, a.samples) << a.perturbation;
    }
    if (a.stage == "command") {
      std::printf("%s adversarial %-17s samples %ld (%ld in contact, %ld saturated)\n",
                  a.implementation.c_str(), a.perturbation.c_str(), a.samples, a.contact_samples,
                  a.saturated_samples);
    }
  }
  ASSERT_EQ(r.scenes.size(), o.scenes.size() * (stage_tables().size() - 1));
  for (const SceneCrosscheck& c : r.scenes) {
    std::printf("%s %s: max force diff %.3e N (largest force %.3f N), before contact %.3e N\n",
                c.implementation.c_str(), c.scene.c_str(), c.max_force_diff_n, c.max_force_n,
                c.max_force_diff_before_contact_n);
    EXPECT_GT(c.contact_ticks, 0) << c.scene;
    EXPECT_LE(c.max_force_diff_before_contact_n, 1e-9) << c.scene;
  }
}

}  // namespace
}  // namespace dentsim
