// The quiet measures (sim/quiet_measures.h) on synthetic signals with known answers: a sine of
// known amplitude gives a known ripple and oscillation amplitude, a square contact signal a known
// number of losses, constant force over constant depth a known stiffness; and a scripted run cut
// into its phases with every measure exact.
#include "sim/quiet_measures.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

namespace dentsim {
namespace {

// m + a sin(2 pi k / period), k = 0 .. n-1.
std::vector<double> sine(int n, double m, double a, int period) {
  std::vector<double> v(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) v[k] = m + a * std::sin(2.0 * std::numbers::pi * k / period);
  return v;
}

TEST(QuietMeasures, MovingAverageIsTheWindowMeanWhereTheWindowFits) {
  const std::vector<double> x = {1, 2, 3, 4, 5};
  EXPECT_EQ(centred_moving_average(x, 1), (std::vector<double>{2, 3, 4}));
  EXPECT_EQ(centred_moving_average(x, 2), (std::vector<double>{3}));
  EXPECT_TRUE(centred_moving_average(x, 3).empty());
  EXPECT_EQ(centred_moving_average(x, 0), x);
}

TEST(QuietMeasures, ConstantForceHasNoRipple) {
  const std::vector<double> f(200, 1.5);
  ASSERT_TRUE(force_ripple(f, 50).has_value());
  EXPECT_EQ(*force_ripple(f, 50), 0.0);
}

TEST(QuietMeasures, SineRippleIsAmplitudeOverRootTwoMean) {
  // Window 5 ticks = one period: the average is the mean; 50 valid samples = 10 periods.
  const double m = 2.0, a = 0.5;
  const std::vector<double> f = sine(54, m, a, 5);
  ASSERT_TRUE(force_ripple(f, 2).has_value());
  EXPECT_NEAR(*force_ripple(f, 2), a / (std::numbers::sqrt2 * m), 1e-14);
  EXPECT_NEAR(residual_rms(f, 2), a / std::numbers::sqrt2, 1e-14);
}

TEST(QuietMeasures, RippleIsUndefinedWithoutMeanForceOrWindow) {
  EXPECT_FALSE(force_ripple(std::vector<double>(20, 0.0), 2).has_value());
  EXPECT_FALSE(force_ripple(std::vector<double>(4, 1.0), 2).has_value());
}

TEST(QuietMeasures, OscillationAmplitudeOfASineIsItsAmplitude) {
  const double a = 3e-5;
  const std::vector<double> x = sine(104, 0.1, a, 5), zero(104, -0.2);
  // (Tolerance: the round-off of the 0.1 m offset.)
  EXPECT_NEAR(oscillation_amplitude(x, zero, zero, 2), a, 1e-9 * a);
  // A circle of radius a: each coordinate a sine of amplitude a, |residual| = a throughout.
  std::vector<double> y(104);
  for (int k = 0; k < 104; ++k) y[k] = a * std::cos(2.0 * std::numbers::pi * k / 5);
  EXPECT_NEAR(oscillation_amplitude(x, y, zero, 2), std::numbers::sqrt2 * a, 1e-9 * a);
}

TEST(QuietMeasures, SquareContactSignalCountsItsLosses) {
  const std::vector<int> square = {1, 1, 0, 0, 1, 1, 0, 0, 1};
  EXPECT_EQ(contact_losses(square), 2);
  EXPECT_DOUBLE_EQ(contact_fraction(square), 5.0 / 9.0);
  EXPECT_EQ(contact_losses(std::vector<int>{0, 2, 0}), 1);  // starts out: no loss counted there
  EXPECT_EQ(contact_losses(std::vector<int>{3, 0}), 1);     // ends out: the loss counts
  EXPECT_EQ(contact_losses(std::vector<int>{1, 1, 1}), 0);
  EXPECT_EQ(contact_fraction(std::vector<int>{1, 1, 1}), 1.0);
  EXPECT_EQ(contact_fraction(std::vector<int>{}), 0.0);
}

TEST(QuietMeasures, StaticStiffnessIsMeanForceOverMeanDepth) {
  const std::vector<double> f = {1, 2, 3}, d = {1e-3, 2e-3, 3e-3};
  ASSERT_TRUE(static_stiffness(f, d).has_value());
  EXPECT_NEAR(*static_stiffness(f, d), 1000.0, 1e-9);
  EXPECT_FALSE(static_stiffness(f, std::vector<double>(3, 0.0)).has_value());
}

TEST(QuietMeasures, RmsCountAndRise) {
  const std::vector<double> x = {3, -4, 0, 0.5};
  EXPECT_DOUBLE_EQ(rms(x), std::sqrt((9.0 + 16.0 + 0.25) / 4.0));
  EXPECT_EQ(count_above(x, 0.5), 2);
  EXPECT_EQ(rise(x), -2.5);
  EXPECT_EQ(rise(std::vector<double>{1.0}), 0.0);
}

// A scripted run on a dyadic tick (exact times): approach (moving, the push ramps in), a steady
// press [1, 3) with one contact drop-out, a lift [3, 3.5), then the hand stands still.
TEST(QuietMeasures, ReportCutsTheScriptIntoPressAndFreeSpace) {
  QuietBounds b;
  b.window_s = 4.0 / 1024.0;  // h = 2
  b.settle_s = 0.25;
  b.min_steady_s = 0.25;
  b.still_settle_s = 0.5;
  b.pulse_threshold_n = 0.1;
  QuietSeries s;
  s.tick_s = 1.0 / 1024.0;
  const int n = 5 * 1024;
  const std::vector<QuietScriptKey> script = {{0.0, Vec3(0, 0, 1e-3), Vec3::Zero(), "approach"},
                                              {1.0, Vec3::Zero(), Vec3(0, 0, -1), "press"},
                                              {3.0, Vec3::Zero(), Vec3(0, 0, -1), "press"},
                                              {3.5, Vec3(0, 0, 5e-3), Vec3::Zero(), "retract"},
                                              {4.0, Vec3(0, 0, 5e-3), Vec3::Zero(), "retract"}};
  for (int k = 0; k < n; ++k) {
    const double t = k * s.tick_s;
    const bool in = t >= 1.25 && t < 3.25 && k != 2560;  // one drop-out at t = 2.5
    s.t.push_back(t);
    s.contacts.push_back(in ? 1 : 0);
    s.contact_force_n.push_back(t >= 1.25 && t < 3.25 ? 1.0 : 0.0);
    double fd = t >= 1.25 && t < 3.25 ? 2.0 : 0.05;
    if (k == 4608 || k == 4609 || k == 3700) fd = 0.5;  // pulses (3700: before still_settle)
    s.device_force_n.push_back(fd);
    s.device_penetration_m.push_back(in ? 1e-3 : 0.0);
    s.tip_x_m.push_back(0.0);
    s.tip_y_m.push_back(0.0);
    s.tip_z_m.push_back(0.0);
    s.energy_j.push_back(1e-3 * t);
  }
  const QuietReport r = quiet_report(s, script, b, 3e-5);
  ASSERT_EQ(r.phases.size(), 1u);
  const QuietPhase& p = r.phases[0];
  EXPECT_EQ(p.phase, "press");
  EXPECT_EQ(p.kind, "press");
  EXPECT_TRUE(p.touched);
  EXPECT_EQ(p.steady_from_s, 1.5);
  EXPECT_EQ(p.t_end_s, 3.0);
  EXPECT_EQ(p.ticks, 1536);  // t in [1.5, 3.0)
  EXPECT_EQ(p.contact_losses, 1);
  EXPECT_DOUBLE_EQ(p.contact_fraction, 1535.0 / 1536.0);
  ASSERT_TRUE(p.ripple_contact_force && p.ripple_device_force);
  EXPECT_EQ(*p.ripple_contact_force, 0.0);
  EXPECT_EQ(*p.ripple_device_force, 0.0);
  EXPECT_EQ(p.oscillation_amplitude_quanta, 0.0);
  EXPECT_EQ(p.mean_device_force_n, 2.0);
  ASSERT_TRUE(p.static_stiffness_n_per_m.has_value());
  EXPECT_NEAR(*p.static_stiffness_n_per_m, 2.0 / (1e-3 * 1535.0 / 1536.0), 1e-6);
  EXPECT_NEAR(p.motor_energy_j, 1e-3 * 1535.0 / 1024.0, 1e-15);
  EXPECT_FALSE(p.quiet);  // the drop-out
  ASSERT_TRUE(r.quiet.has_value());
  EXPECT_FALSE(*r.quiet);

  // Free space: moving in [0, 1) (1024 ticks) and [3.25 + 2 ticks, 3.5) after the contact;
  // still from 4.0 (3.5 + still_settle) to the end: 1024 ticks, two pulses.
  const QuietFreeSpace& fs = r.free_space;
  EXPECT_EQ(fs.still_ticks, 1024);
  EXPECT_EQ(fs.still_pulses, 2);
  EXPECT_DOUBLE_EQ(fs.still_pulse_rate_per_s, 2.0);
  EXPECT_NEAR(fs.still_force_rms_n, std::sqrt((1022 * 0.05 * 0.05 + 2 * 0.25) / 1024.0), 1e-15);
  EXPECT_NEAR(fs.still_motor_energy_j, 1e-3 * 1023.0 / 1024.0, 1e-15);
  EXPECT_EQ(fs.moving_ticks, 1024 + (3584 - 3328 - 2));
  EXPECT_NEAR(fs.moving_force_rms_n, 0.05, 1e-15);
  // No ground truth (a real device): the observer's error is not measured, so not reported.
  EXPECT_FALSE(p.observer_rms_error_n.has_value());
  EXPECT_FALSE(fs.moving_observer_rms_error_n.has_value());
  EXPECT_FALSE(fs.still_observer_rms_error_n.has_value());

  // The observer's error, measured over the same ticks as the forces: 0.02 N in the press (one
  // 0.5 N tick at t = 2.0), 0.03 N while moving, 0.04 N while still, 9 N elsewhere (the press's
  // settling and the retract's first ticks), which no measure may see.
  {
    QuietSeries o = s;
    for (int k = 0; k < n; ++k) {
      const double t = o.t[k];
      double e = 9.0;
      if (t >= 1.5 && t < 3.0) e = k == 2048 ? 0.5 : 0.02;
      if (t < 1.0 || (t >= 3.25 + 2 * s.tick_s && t < 3.5)) e = 0.03;
      if (t >= 4.0) e = 0.04;
      o.observer_error_n.push_back(e);
    }
    const QuietReport ro = quiet_report(o, script, b, 3e-5);
    ASSERT_TRUE(ro.phases[0].observer_rms_error_n.has_value());
    EXPECT_NEAR(*ro.phases[0].observer_rms_error_n,
                std::sqrt((1535 * 0.02 * 0.02 + 0.25) / 1536.0), 1e-15);
    ASSERT_TRUE(ro.free_space.moving_observer_rms_error_n.has_value());
    EXPECT_NEAR(*ro.free_space.moving_observer_rms_error_n, 0.03, 1e-15);
    ASSERT_TRUE(ro.free_space.still_observer_rms_error_n.has_value());
    EXPECT_NEAR(*ro.free_space.still_observer_rms_error_n, 0.04, 1e-15);
  }

  // Without the drop-out the press is quiet.
  s.contacts[2560] = 1;
  s.device_penetration_m[2560] = 1e-3;
  const QuietReport q = quiet_report(s, script, b, 3e-5);
  ASSERT_EQ(q.phases.size(), 1u);
  EXPECT_EQ(q.phases[0].contact_losses, 0);
  EXPECT_TRUE(q.phases[0].quiet);
  EXPECT_TRUE(q.quiet.value_or(false));
}

TEST(QuietMeasures, PushingIntoTheAirIsNoContactPhase) {
  QuietSeries s;
  const std::vector<QuietScriptKey> script = {{0.0, Vec3::Zero(), Vec3(0, 0, -1), "press"},
                                              {1.0, Vec3::Zero(), Vec3(0, 0, -1), "press"}};
  for (int k = 0; k < 1000; ++k) {
    s.t.push_back(k * 1e-3);
    s.contacts.push_back(0);
    s.contact_force_n.push_back(0.0);
    s.device_force_n.push_back(0.0);
    s.device_penetration_m.push_back(0.0);
    s.tip_x_m.push_back(0.0);
    s.tip_y_m.push_back(0.0);
    s.tip_z_m.push_back(0.0);
    s.energy_j.push_back(0.0);
  }
  const QuietReport r = quiet_report(s, script, QuietBounds{}, 3e-5);
  EXPECT_TRUE(r.phases.empty());
  EXPECT_FALSE(r.quiet.has_value());
}

}  // namespace
}  // namespace dentsim
