// Pacing a servo loop whose device has no clock of its own (the simulated Phantom with
// `dentsim run --realtime`; issue #15): absolute deadlines on the grid t_0 + k T, overruns counted
// and the missed deadlines skipped rather than replayed, and period and execution-time statistics
// in constant memory (docs/design.md "The real-time loop"; libfranka, ros2_control).
//
//   wait_next():  target = d + T (d: the last deadline the loop started on).
//                 now <= target: sleep until target (absolute: no drift), start on it, d = target.
//                 now >  target: the loop is late: start now (overrun += 1), skip the deadlines
//                 already passed (skipped += floor((now - target) / T)), d = the last one passed.
//   tick_done():  execution time = now - the tick's start.
//   period       = start_k - start_k-1 (what the device sees between two commands).
// Statistics: count, mean (Welford), median and p99 from a histogram of 1 us bins up to 20 ms
// (beyond: the last bin), exact maximum; no allocation after construction.
//
// Real-time privileges (request_realtime): SCHED_FIFO at a high priority and mlockall(); where
// the process may not (no CAP_SYS_NICE / RLIMIT_RTPRIO, containers), a one-line warning says so
// and the loop runs at normal priority.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>

namespace dentsim {

// Quantiles of times in constant memory: 1 us bins up to kBins us, the last bin open-ended.
class TimingHistogram {
 public:
  static constexpr int kBins = 20000;
  void add(double us);
  long count() const { return n_; }
  double mean_us() const { return mean_; }
  double max_us() const { return max_; }
  // The q-quantile (0..1) as the centre of its bin [us]; 0 when empty.
  double quantile_us(double q) const;

 private:
  std::array<std::uint32_t, kBins> bins_{};
  long n_ = 0;
  double mean_ = 0.0, max_ = 0.0;
};

struct ServoTimingStats {
  long ticks = 0;
  long overruns = 0;           // ticks that started after their deadline
  long skipped_deadlines = 0;  // deadlines passed without a tick (never replayed)
  double period_median_us = 0.0, period_p99_us = 0.0, period_max_us = 0.0;
  double exec_median_us = 0.0, exec_p99_us = 0.0, exec_max_us = 0.0, exec_mean_us = 0.0;
  bool sched_fifo = false;     // the loop ran at SCHED_FIFO priority
  bool memory_locked = false;  // mlockall succeeded
  std::string warning;         // why not, when not
};

class ServoPacer {
 public:
  using Clock = std::function<double()>;           // monotonic time [s]
  using SleepUntil = std::function<void(double)>;  // sleep until that time [s]
  // The steady clock and clock_nanosleep(TIMER_ABSTIME) unless given (tests give a fake clock).
  explicit ServoPacer(double period_s, Clock now = {}, SleepUntil sleep_until = {});

  void start();      // the first deadline is now
  void wait_next();  // before a tick
  void tick_done();  // after it
  ServoTimingStats stats() const;
  // Records the outcome of request_realtime() in the statistics.
  void set_privileges(bool sched_fifo, bool memory_locked, std::string warning);

 private:
  double T_;
  Clock now_;
  SleepUntil sleep_until_;
  double deadline_ = 0.0, tick_start_ = 0.0, last_start_ = 0.0;
  bool started_any_ = false;
  long ticks_ = 0, overruns_ = 0, skipped_ = 0;
  TimingHistogram period_, exec_;
  bool fifo_ = false, locked_ = false;
  std::string warning_;
};

// The servo thread's SCHED_FIFO priority (request_realtime); helper threads of the loop run
// below it.
inline constexpr int kRealtimePriority = 80;
// Asks for SCHED_FIFO (priority kRealtimePriority) for the calling thread and locks the
// process's memory.
// Returns what was granted; `warning` says what was not and why (empty when everything was).
void request_realtime(bool* sched_fifo, bool* memory_locked, std::string* warning);
// Back to SCHED_OTHER and unlocked memory (what request_realtime granted).
void release_realtime(bool sched_fifo, bool memory_locked);
// The SCHED_FIFO priority for a helper thread of a servo thread that runs at (`policy`,
// `priority`), e.g. the vendor's scheduler thread (HdapiDevice::scheduler_policy): one below it
// when the servo thread is real-time (SCHED_FIFO or SCHED_RR) and one below is still a real-time
// priority; 0 (leave the helper as it is) otherwise: a helper above a time-shared servo thread
// would preempt it.
int helper_priority_below(int policy, int priority);

}  // namespace dentsim
