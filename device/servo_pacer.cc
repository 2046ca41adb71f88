#include "device/servo_pacer.h"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <ctime>

namespace dentsim {

void TimingHistogram::add(double us) {
  if (!std::isfinite(us)) return;
  const double v = std::max(0.0, us);
  const int bin = std::min(kBins - 1, static_cast<int>(v));
  ++bins_[bin];
  ++n_;
  mean_ += (v - mean_) / static_cast<double>(n_);
  max_ = std::max(max_, v);
}

double TimingHistogram::quantile_us(double q) const {
  if (n_ == 0) return 0.0;
  const long rank = std::min(n_ - 1, static_cast<long>(q * static_cast<double>(n_)));
  long seen = 0;
  for (int b = 0; b < kBins; ++b) {
    seen += bins_[b];
    if (seen > rank) return b + 0.5;
  }
  return kBins - 0.5;
}

namespace {

double steady_now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// clock_nanosleep on CLOCK_MONOTONIC (the clock steady_clock reads on Linux) to an absolute time.
void sleep_until_monotonic(double t) {
  timespec ts;
  ts.tv_sec = static_cast<time_t>(std::floor(t));
  ts.tv_nsec = static_cast<long>((t - std::floor(t)) * 1e9);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

}  // namespace

ServoPacer::ServoPacer(double period_s, Clock now, SleepUntil sleep_until)
    : T_(period_s),
      now_(now ? std::move(now) : Clock(steady_now)),
      sleep_until_(sleep_until ? std::move(sleep_until) : SleepUntil(sleep_until_monotonic)) {}

void ServoPacer::start() {
  deadline_ = now_() - T_;  // the first wait_next() starts at once, on "now"
  started_any_ = false;
  ticks_ = overruns_ = skipped_ = 0;
  period_ = TimingHistogram{};
  exec_ = TimingHistogram{};
}

void ServoPacer::wait_next() {
  const double target = deadline_ + T_;
  double now = now_();
  if (ticks_ == 0 || now <= target) {
    if (ticks_ > 0 && now < target) {
      sleep_until_(target);
      now = now_();
    }
    deadline_ = ticks_ == 0 ? now : target;
  } else {
    ++overruns_;
    const long passed = static_cast<long>(std::floor((now - target) / T_));
    skipped_ += passed;
    deadline_ = target + static_cast<double>(passed) * T_;
  }
  tick_start_ = now;
  if (started_any_) period_.add(1e6 * (tick_start_ - last_start_));
  last_start_ = tick_start_;
  started_any_ = true;
  ++ticks_;
}

void ServoPacer::tick_done() { exec_.add(1e6 * (now_() - tick_start_)); }

void ServoPacer::set_privileges(bool sched_fifo, bool memory_locked, std::string warning) {
  fifo_ = sched_fifo;
  locked_ = memory_locked;
  warning_ = std::move(warning);
}

ServoTimingStats ServoPacer::stats() const {
  ServoTimingStats s;
  s.ticks = ticks_;
  s.overruns = overruns_;
  s.skipped_deadlines = skipped_;
  s.period_median_us = period_.quantile_us(0.5);
  s.period_p99_us = period_.quantile_us(0.99);
  s.period_max_us = period_.max_us();
  s.exec_median_us = exec_.quantile_us(0.5);
  s.exec_p99_us = exec_.quantile_us(0.99);
  s.exec_max_us = exec_.max_us();
  s.exec_mean_us = exec_.mean_us();
  s.sched_fifo = fifo_;
  s.memory_locked = locked_;
  s.warning = warning_;
  return s;
}

void request_realtime(bool* sched_fifo, bool* memory_locked, std::string* warning) {
  std::string w;
  sched_param p{};
  p.sched_priority = kRealtimePriority;
  const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &p);
  *sched_fifo = rc == 0;
  if (rc != 0) {
    w += std::string("SCHED_FIFO refused (") + std::strerror(rc) +
         "; needs CAP_SYS_NICE or an RLIMIT_RTPRIO, e.g. a limits.conf rtprio entry)";
  }
#if defined(__SANITIZE_ADDRESS__)
  // AddressSanitizer reserves terabytes of shadow address space: locking it is not an option.
  *memory_locked = false;
  w += std::string(w.empty() ? "" : "; ") + "mlockall skipped under AddressSanitizer";
#else
  *memory_locked = mlockall(MCL_CURRENT | MCL_FUTURE) == 0;
  if (!*memory_locked) {
    const int e = errno;
    w += std::string(w.empty() ? "" : "; ") + "mlockall refused (" + std::strerror(e) +
         "; needs CAP_IPC_LOCK or a large RLIMIT_MEMLOCK)";
  }
#endif
  if (!w.empty()) w += ": the loop may be preempted or paged";
  *warning = w;
}

int helper_priority_below(int policy, int priority) {
  if (policy != SCHED_FIFO && policy != SCHED_RR) return 0;
  const int lowest = sched_get_priority_min(SCHED_FIFO);
  return priority - 1 >= lowest ? priority - 1 : 0;
}

void release_realtime(bool sched_fifo, bool memory_locked) {
  if (sched_fifo) {
    sched_param p{};
    p.sched_priority = 0;
    pthread_setschedparam(pthread_self(), SCHED_OTHER, &p);
  }
  if (memory_locked) munlockall();
}

}  // namespace dentsim
