// The servo pacer of loops without a device clock (device/servo_pacer.h, `dentsim run --realtime`,
// issue #15) on a fake clock: it sleeps to absolute deadlines (no drift), counts an overrun and
// skips the deadlines already passed instead of replaying them, and its statistics are exact.
#include "device/servo_pacer.h"

#include <sched.h>

#include <gtest/gtest.h>

#include <vector>

namespace dentsim {
namespace {

// A clock that advances only when the pacer sleeps or the test says work took time.
struct FakeTime {
  double now = 100.0;
  std::vector<double> sleeps;  // the absolute times slept to
  ServoPacer pacer(double T) {
    return ServoPacer(
        T, [this] { return now; },
        [this](double t) {
          sleeps.push_back(t);
          if (t > now) now = t;
        });
  }
};

constexpr double T = 1.0 / 1024;  // exact in binary

TEST(ServoPacer, SleepsToAbsoluteDeadlinesWithoutDrift) {
  FakeTime clock;
  ServoPacer p = clock.pacer(T);
  p.start();
  for (int k = 0; k < 100; ++k) {
    p.wait_next();
    clock.now += T / 4;  // the tick's work
    p.tick_done();
  }
  // 99 sleeps, each to exactly t_0 + k T (absolute: work time does not accumulate).
  ASSERT_EQ(clock.sleeps.size(), 99u);
  for (int k = 1; k < 100; ++k) EXPECT_EQ(clock.sleeps[k - 1], 100.0 + k * T) << k;
  const ServoTimingStats s = p.stats();
  EXPECT_EQ(s.ticks, 100);
  EXPECT_EQ(s.overruns, 0);
  EXPECT_EQ(s.skipped_deadlines, 0);
  // 1/1024 s = 976.5625 us: its 1 us bin's centre; the maximum exactly.
  EXPECT_DOUBLE_EQ(s.period_median_us, 976.5);
  EXPECT_DOUBLE_EQ(s.period_max_us, 976.5625);
  EXPECT_DOUBLE_EQ(s.exec_median_us, 244.5);  // T/4 = 244.140625 us
  EXPECT_DOUBLE_EQ(s.exec_max_us, 244.140625);
  EXPECT_DOUBLE_EQ(s.exec_mean_us, 244.140625);
}

TEST(ServoPacer, OverrunsAreCountedAndMissedDeadlinesSkippedNotReplayed) {
  FakeTime clock;
  ServoPacer p = clock.pacer(T);
  p.start();
  p.wait_next();  // tick 0 at t_0
  clock.now += T / 2;
  p.tick_done();
  p.wait_next();         // tick 1 at t_0 + T
  clock.now += 3.5 * T;  // a long tick: deadlines t_0 + 2T, 3T, 4T pass
  p.tick_done();
  const double late_start = clock.now;  // t_0 + 4.5 T
  p.wait_next();                        // tick 2 starts at once, late
  clock.now += T / 4;
  p.tick_done();
  p.wait_next();  // back on the grid: the next deadline after t_0 + 4T is t_0 + 5T
  const ServoTimingStats s = p.stats();
  EXPECT_EQ(s.ticks, 4);
  EXPECT_EQ(s.overruns, 1);
  // Tick 2 should have started at t_0 + 2T; t_0 + 3T and 4T passed too and are skipped.
  EXPECT_EQ(s.skipped_deadlines, 2);
  ASSERT_FALSE(clock.sleeps.empty());
  EXPECT_EQ(clock.sleeps.back(), 100.0 + 5 * T);
  EXPECT_EQ(clock.now, 100.0 + 5 * T);
  EXPECT_DOUBLE_EQ(s.period_max_us, 1e6 * (late_start - (100.0 + T)));  // 3.5 T
  EXPECT_DOUBLE_EQ(s.exec_max_us, 1e6 * 3.5 * T);
}

TEST(TimingHistogram, QuantilesFromBinsAndExactMaximum) {
  TimingHistogram h;
  EXPECT_EQ(h.quantile_us(0.5), 0.0);
  for (int i = 0; i < 100; ++i) h.add(i);  // 0 .. 99 us
  h.add(1e9);                              // beyond the last bin
  EXPECT_EQ(h.count(), 101);
  EXPECT_DOUBLE_EQ(h.quantile_us(0.5), 50.5);
  EXPECT_DOUBLE_EQ(h.quantile_us(0.99), 99.5);
  EXPECT_DOUBLE_EQ(h.quantile_us(1.0), TimingHistogram::kBins - 0.5);
  EXPECT_DOUBLE_EQ(h.max_us(), 1e9);
}

// A helper thread (the field edit's worker) goes one below a real-time servo thread, never above
// or beside a time-shared one, and never to a priority that is not real-time.
TEST(HelperPriority, OneBelowARealTimeServoThreadOnly) {
  const int lowest = sched_get_priority_min(SCHED_FIFO);  // 1 on Linux
  EXPECT_EQ(helper_priority_below(SCHED_FIFO, kRealtimePriority), kRealtimePriority - 1);
  EXPECT_EQ(helper_priority_below(SCHED_RR, 50), 49);
  EXPECT_EQ(helper_priority_below(SCHED_FIFO, lowest + 1), lowest);
  EXPECT_EQ(helper_priority_below(SCHED_FIFO, lowest), 0);
  EXPECT_EQ(helper_priority_below(SCHED_OTHER, 0), 0);
  EXPECT_EQ(helper_priority_below(SCHED_BATCH, 0), 0);
  EXPECT_EQ(helper_priority_below(SCHED_IDLE, 0), 0);
}

}  // namespace
}  // namespace dentsim
