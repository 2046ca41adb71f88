// Issue #29's free-space and observer targets on the built-in scenes, as they run by default
// (simulated Phantom with its encoders, fast pipeline, pmi-pd with the grip detector and the
// encoder Kalman filter): the human-force observer's RMS error against the simulated hand's true
// force <= 0.05 N in every steady press or slide and in free space; the force the hand feels
// while moving in free space <= 0.03 N RMS; no pulse while the hand is still; and, over 15 s of
// `drill` (10 s of it still after the retract), the motors' energy input bounded. The same scene
// with the filter off misses the observer target (0.26-0.31 N, the issue's "today"), so the
// figures are the filter's, and these assertions can fail.
// The measures are the run report's (sim/quiet_measures.h, `quiet` in report.json).
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "sim/run_report.h"
#include "sim/scene.h"
#include "sim/simulator.h"

namespace dentsim {
namespace {

constexpr double kObserverTarget = 0.05;  // N RMS
constexpr double kFreeSpaceTarget = 0.03;  // N RMS while moving

// As `dentsim run` runs them: the fast pipeline.
RunOptions product_run(double duration_s = 0.0) {
  RunOptions opt;
  opt.pipeline = "fast";
  opt.duration_override = duration_s;
  return opt;
}

QuietReport quiet_of(const Scene& scene, const RunResult& r) {
  EXPECT_TRUE(r.faults.empty()) << scene.name;
  return run_quiet_report(scene, r);
}

class QuietTargets : public ::testing::TestWithParam<std::string> {};

TEST_P(QuietTargets, ObserverAndFreeSpaceMeetTheIssueTargets) {
  const Scene scene = load_scene(GetParam());
  ASSERT_TRUE(scene.method.encoder_kalman) << "the built-in scenes run the encoder filter";
  const RunResult r = run_scene(scene, product_run());
  const QuietReport q = quiet_of(scene, r);
  ASSERT_FALSE(q.phases.empty());
  for (const QuietPhase& p : q.phases) {
    ASSERT_TRUE(p.observer_rms_error_n.has_value()) << p.phase;
    EXPECT_LE(*p.observer_rms_error_n, kObserverTarget) << GetParam() << " " << p.phase;
    std::printf("%s %s: observer RMS error %.4f N\n", GetParam().c_str(), p.phase.c_str(),
                *p.observer_rms_error_n);
  }
  const QuietFreeSpace& fs = q.free_space;
  ASSERT_GT(fs.moving_ticks, 500);
  ASSERT_TRUE(fs.moving_observer_rms_error_n.has_value());
  EXPECT_LE(*fs.moving_observer_rms_error_n, kObserverTarget) << GetParam();
  EXPECT_LE(fs.moving_force_rms_n, kFreeSpaceTarget) << GetParam();
  EXPECT_EQ(fs.still_pulses, 0) << GetParam();
  std::printf("%s free space: force %.4f N, observer %.4f N RMS while moving\n",
              GetParam().c_str(), fs.moving_force_rms_n, *fs.moving_observer_rms_error_n);
}

TEST_P(QuietTargets, WithoutTheEncoderFilterTheObserverMissesItsTarget) {
  Scene scene = load_scene(GetParam());
  scene.method.encoder_kalman = false;
  const RunResult r = run_scene(scene, product_run());
  const QuietReport q = quiet_of(scene, r);
  double worst = 0.0;
  for (const QuietPhase& p : q.phases) worst = std::max(worst, p.observer_rms_error_n.value_or(0));
  worst = std::max(worst, q.free_space.moving_observer_rms_error_n.value_or(0.0));
  EXPECT_GT(worst, 4 * kObserverTarget) << GetParam();
}

INSTANTIATE_TEST_SUITE_P(BuiltIn, QuietTargets,
                         ::testing::Values("probe", "probe-groove", "drill"));

TEST(QuietTargets, DrillHeldStillFor10sHasNoPulsesAndBoundedMotorEnergy) {
  const Scene scene = load_scene("drill");
  const RunResult r = run_scene(scene, product_run(15.0));
  const QuietReport q = quiet_of(scene, r);
  const QuietFreeSpace& fs = q.free_space;
  ASSERT_GT(fs.still_s, 9.0);
  EXPECT_EQ(fs.still_pulses, 0);
  EXPECT_LE(fs.still_force_rms_n, kFreeSpaceTarget);
  ASSERT_TRUE(fs.still_observer_rms_error_n.has_value());
  EXPECT_LE(*fs.still_observer_rms_error_n, kObserverTarget);
  // The motors' energy while the hand is still: the issue measured ~1.2 mJ/s of climb with the
  // filter off. The motors' true work (the applied torque times the true joint motion) is
  // bounded here by 10 uW on average (0.1 mJ over 10 s) and flat within 0.1 mJ over the last 8 s;
  // E_v, computed from the encoders, over the whole run by the 1 mJ that the encoders' error alone
  // can put in a quiet run (quiet_stiffness.md §4). E_v's own rise while still is that error: the
  // filter's velocity estimate of a joint resting inside one count is not exactly zero, and which
  // count the device rests in decides its sign and size (0.1-0.2 mJ over 10 s measured where the
  // true work falls by 0.05 mJ), so it is reported, not bounded.
  ASSERT_TRUE(fs.still_true_motor_energy_j.has_value());
  EXPECT_LE(*fs.still_true_motor_energy_j, 1e-5 * fs.still_s);
  EXPECT_LE(r.virtual_energy_generated_j, 1e-3);
  const std::vector<double>& e = r.quiet_series.true_energy_j;
  ASSERT_GT(e.size(), 14000u);
  const auto [lo, hi] = std::minmax_element(e.end() - 8000, e.end());
  EXPECT_LE(*hi - *lo, 1e-4);
  std::printf("drill 15 s: still %.1f s, pulses %ld, still force %.4f N, E_v %.3g J, still: true "
              "motor work %.3g J (range over the last 8 s %.3g J), E_v rise %.3g J\n",
              fs.still_s, fs.still_pulses, fs.still_force_rms_n, r.virtual_energy_generated_j,
              *fs.still_true_motor_energy_j, *hi - *lo, fs.still_motor_energy_j);
}

}  // namespace
}  // namespace dentsim
