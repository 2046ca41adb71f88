// Randomised whole-loop stress (validation/stress.h, issue #18): the full simulator over random
// gains beyond the Z-width grid, methods, pipelines, rates, jitter, hand scripts and drilling,
// with the invariants checked every tick. Short form in CI (10^5 ticks in Release, 2 x 10^4 under
// the sanitizers); DENTSIM_STRESS=full runs 10^7, DENTSIM_STRESS_TICKS=N any number
// (docs/results/reliability.md).
#include "validation/stress.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>

#include "tests/support/stress.h"

namespace dentsim {
namespace {

#if defined(__SANITIZE_ADDRESS__)
constexpr long kShortTicks = 20000;
#else
constexpr long kShortTicks = 100000;
#endif

TEST(LoopStress, EveryTickKeepsTheInvariants) {
  StressConfig c;
  c.ticks = testing::stress_count(kShortTicks, 10000000);
  // DENTSIM_STRESS_TICKS=N: a run of N ticks (a long run that fits the time at hand).
  if (const char* n = std::getenv("DENTSIM_STRESS_TICKS")) c.ticks = std::max(1L, std::atol(n));
  // DENTSIM_STRESS_ONLY=METHOD/SCENE (e.g. pmi/drill): only those runs of the same draw
  // (StressConfig::only_method, only_scene); the invariants and the tick budget as above.
  if (const char* only = std::getenv("DENTSIM_STRESS_ONLY")) {
    const std::string s(only);
    const std::size_t slash = s.find('/');
    c.only_method = s.substr(0, slash);
    if (slash != std::string::npos) c.only_scene = s.substr(slash + 1);
  }
  // DENTSIM_STRESS_VARIANT=JSON: a merge patch applied to every drawn configuration (the same
  // draw under a variant, e.g. {"method":{"saturation_passive":false}}; StressConfig).
  if (const char* v = std::getenv("DENTSIM_STRESS_VARIANT")) c.variant_patch = v;
  // DENTSIM_STRESS_FROM_RUN=N: runs before N drawn and skipped (StressConfig::first_run).
  if (const char* n = std::getenv("DENTSIM_STRESS_FROM_RUN")) c.first_run = std::atol(n);
  c.seed = 1 + static_cast<std::uint64_t>(::testing::UnitTest::GetInstance()->random_seed());
  // A line every 5 % of the ticks on stderr (how far a long form got, if it must be stopped):
  // the run index, the ticks done, the faults so far.
  // Long forms also list each faulted run there as it happens.
  long next_report = c.ticks / 20;
  std::size_t listed = 0;
  const StressResult r = run_stress(c, [&next_report, &listed, &c](const StressResult& so_far,
                                                                   long total) {
    if (c.ticks < 1000000) return;
    for (; listed < so_far.faulted_runs.size(); ++listed) {
      std::fprintf(stderr, "stress: faulted %s\n",
                   describe_faulted_run(so_far.faulted_runs[listed]).c_str());
    }
    if (so_far.ticks < next_report) return;
    long faults = 0;
    for (const auto& [name, n] : so_far.faults) faults += n;
    std::fprintf(stderr, "stress: run %ld, %ld of %ld ticks (%.0f %%), %ld runs ended in a fault\n",
                 so_far.runs, so_far.ticks, total,
                 100.0 * static_cast<double>(so_far.ticks) / static_cast<double>(total), faults);
    while (next_report <= so_far.ticks) next_report += c.ticks / 20;
  });
  std::printf(
      "stress: %ld runs, %ld ticks (seed %llu; %ld configurations refused by the scene "
      "checks), worst |tau|/tau_max %.3f, worst contact force %.2f N, worst depth %.2f rho\n",
      r.runs, r.ticks, static_cast<unsigned long long>(c.seed), r.rejected_configs,
      r.worst_torque_ratio, r.worst_contact_force_n, r.worst_depth_over_radius);
  if (r.skipped_runs > 0) {
    std::printf("  only %s/%s: %ld of the draw's runs simulated, %ld skipped\n",
                c.only_method.c_str(), c.only_scene.c_str(), r.runs - r.skipped_runs,
                r.skipped_runs);
  }
  for (const auto& [name, n] : r.faults) std::printf("  runs ending in %s: %ld\n", name.c_str(), n);
  std::map<std::string, std::map<std::string, long>> by_method;  // method -> fault -> runs
  for (const StressFaultedRun& f : r.faulted_runs) ++by_method[f.method][f.fault];
  for (const auto& [method, faults] : by_method) {
    for (const auto& [name, n] : faults) {
      std::printf("  %s: %ld runs ending in %s\n", method.c_str(), n, name.c_str());
    }
  }
  // Every faulted run, to judge and replay it (validation/stress.h StressFaultedRun).
  for (const StressFaultedRun& f : r.faulted_runs) {
    std::printf("  faulted %s\n    patch %s\n", describe_faulted_run(f).c_str(), f.patch.c_str());
  }
  for (const auto& [method, n] : r.runs_by_method) {
    const auto e = r.exploded.find(method);
    std::printf("  %s: %ld runs, %ld with the proxy exploded\n", method.c_str(), n,
                e == r.exploded.end() ? 0L : e->second);
  }
  std::printf(
      "  rendered tip outside the tooth: %ld ticks checked, min clearance (phi(g) - rho) / "
      "rho = %.4f\n",
      r.surface_checks, r.min_clearance_over_radius);
  for (const auto& [method, depth] : r.worst_depth_by_method) {
    std::printf("  deepest contact under %s: %.2f rho in %s\n", method.c_str(), depth,
                r.worst_depth_run.at(method).c_str());
  }
  EXPECT_EQ(r.violations, 0) << r.first_violation << "\n(re-run: --gtest_random_seed=" << c.seed - 1
                             << ")";
  EXPECT_EQ(r.ticks, c.ticks);
  // The stress reaches what it is for: many configurations, contact, saturation.
  EXPECT_GE(r.runs, c.ticks / 2000);
  EXPECT_GT(r.worst_contact_force_n, 1.0);
  EXPECT_GT(r.worst_torque_ratio, 0.5);
  if (c.only_scene.empty() || c.only_scene == "probe") {
    EXPECT_GT(r.surface_checks, c.ticks / 100 / (c.only_method.empty() ? 1 : 3));  // probe contact
  }
}

}  // namespace
}  // namespace dentsim
