// One row of the fast-vs-reference stage-by-stage check (validation/crosscheck_fast.h), printed and
// held to the options' bound: within max_rel_bound, no count mismatch, every tick of the
// configuration compared, and enough of them in contact to mean something. Shared by
// tests/fast/tick_test.cc and the remedies' differential tests (tests/reference/
// lag_compensation_test.cc, saturation_passive_test.cc).
#pragma once

#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "validation/crosscheck_fast.h"

namespace dentsim::testing {

inline void expect_stage_row_agrees(const FastCrosscheckOptions& o, const StageCrosscheck& s) {
  std::printf("%s %-34s %-13s max_rel %.3e (%ld samples, %ld in contact)\n",
              s.implementation.c_str(), s.config.c_str(), s.stage.c_str(), s.max_rel, s.samples,
              s.contact_samples);
  EXPECT_LE(s.max_rel, o.max_rel_bound) << s.config << " " << s.stage;
  EXPECT_EQ(s.count_mismatches, 0) << s.config << " " << s.stage;
  EXPECT_EQ(s.samples, o.stage_ticks) << s.config;
  // A check that barely met contact would prove little.
  EXPECT_GT(s.contact_samples, s.samples / 20) << s.config << " " << s.stage;
}

// The stage-by-stage check alone (no adversarial states, no whole scenes) on `configs`, `ticks`
// ticks each: it passes and every row agrees (expect_stage_row_agrees).
inline void expect_stage_configs_agree(std::vector<StageConfig> configs, long ticks) {
  FastCrosscheckOptions o;
  o.stage_configs = std::move(configs);
  o.stage_ticks = ticks;
  o.adversarial = false;
  o.scenes.clear();
  const FastCrosscheckResult r = crosscheck_fast(o);
  for (const std::string& f : r.failures) ADD_FAILURE() << f;
  EXPECT_TRUE(r.ok);
  ASSERT_FALSE(r.stages.empty());
  for (const StageCrosscheck& s : r.stages) expect_stage_row_agrees(o, s);
}

}  // namespace dentsim::testing
