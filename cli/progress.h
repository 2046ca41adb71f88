// Progress of long work on stderr.
// The one progress reporter of the CLI (every command uses it; issue #33):
// - ProgressBar: on a terminal (and CI unset) a redrawn bar; otherwise (a log, a pipe, CI, a
//   Slurm job's output file) one line "label: 42% detail (30 s elapsed, about 41 s left)" at most
//   every kProgressLineSeconds, so long runs are never silent and short ones print nothing.
//   message() prints a line of its own without colliding with the bar.
// - Heartbeat: for work that reports no fraction (voxelising a 1024^3 grid takes about a minute),
//   a line "label: 10 s elapsed" every kProgressLineSeconds from a background thread while the
//   object lives; nothing for work shorter than that.
#pragma once

#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <string>
#include <thread>

namespace dentsim::cli {

inline constexpr double kProgressLineSeconds = 5.0;

class ProgressBar {
 public:
  explicit ProgressBar(std::string label, bool enabled = true)
      : label_(std::move(label)),
        bar_(enabled && ::isatty(2) != 0 && std::getenv("CI") == nullptr),
        lines_(enabled && !bar_),
        start_(std::chrono::steady_clock::now()),
        last_line_(start_) {}
  ~ProgressBar() { finish(); }
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  // `fraction` done in [0, 1]; `detail` (e.g. "force 12/30") follows the percentage. The lines
  // (not a terminal) carry the time elapsed and, once 2 % is done, the time left at the mean
  // rate so far.
  void update(double fraction, const std::string& detail = {}) {
    if (!bar_ && !lines_) return;
    const int pct = static_cast<int>(fraction * 100.0 + 0.5);
    if (pct == last_ && detail == detail_) return;
    const auto now = std::chrono::steady_clock::now();
    if (lines_) {
      if (std::chrono::duration<double>(now - last_line_).count() < kProgressLineSeconds) return;
      last_line_ = now;
      last_ = pct;
      detail_ = detail;
      const double elapsed = std::chrono::duration<double>(now - start_).count();
      char left[64] = "";
      if (fraction >= 0.02 && fraction < 1.0) {
        std::snprintf(left, sizeof left, ", about %.0f s left",
                      elapsed * (1.0 - fraction) / fraction);
      }
      std::fprintf(stderr, "%s: %d%%%s%s (%.0f s elapsed%s)\n", label_.c_str(), pct,
                   detail.empty() ? "" : " ", detail.c_str(), elapsed, left);
      return;
    }
    last_ = pct;
    detail_ = detail;
    draw();
  }
  // A line of its own (e.g. "run 3/9 ...") that does not collide with the bar: on a terminal the
  // bar is cleared, the line printed and the bar drawn again below it; otherwise just the line.
  void message(const std::string& line) {
    if (bar_ && last_ >= 0) std::fprintf(stderr, "\r\033[K");
    std::fprintf(stderr, "%s\n", line.c_str());
    if (bar_ && last_ >= 0) draw();
  }
  void finish() {
    if (bar_ && last_ >= 0) std::fprintf(stderr, "\n");
    bar_ = lines_ = false;
  }
  // True when progress is shown as lines (stderr is a log, a pipe, or CI is set).
  bool lines() const { return lines_; }

 private:
  void draw() {
    const int width = 40, fill = last_ * width / 100;
    std::fprintf(stderr, "\r%s [%.*s%*s] %3d%%%s%s\033[K", label_.c_str(), fill,
                 "========================================", width - fill, "", last_,
                 detail_.empty() ? "" : " ", detail_.c_str());
    std::fflush(stderr);
  }

  std::string label_;
  bool bar_, lines_;
  int last_ = -1;
  std::string detail_;
  std::chrono::steady_clock::time_point start_, last_line_;
};

class Heartbeat {
 public:
  explicit Heartbeat(std::string label) : label_(std::move(label)), thread_([this] { beat(); }) {}
  ~Heartbeat() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      done_ = true;
    }
    cv_.notify_one();
    thread_.join();
  }
  Heartbeat(const Heartbeat&) = delete;
  Heartbeat& operator=(const Heartbeat&) = delete;

 private:
  void beat() {
    const auto start = std::chrono::steady_clock::now();
    std::unique_lock<std::mutex> lock(mutex_);
    while (!cv_.wait_for(lock, std::chrono::duration<double>(kProgressLineSeconds),
                         [this] { return done_; })) {
      std::fprintf(stderr, "%s: %.0f s elapsed\n", label_.c_str(),
                   std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
  }

  std::string label_;
  std::mutex mutex_;
  std::condition_variable cv_;
  bool done_ = false;
  std::thread thread_;  // last: starts after the members it uses
};

}  // namespace dentsim::cli
