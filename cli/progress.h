// Progress of long work on stderr.
// - ProgressBar: on a terminal (and CI unset) a redrawn bar; otherwise (a log, a pipe, CI) one
//   line "label: 42%" at most every kProgressLineSeconds, so long runs are never silent and
//   short ones print nothing.
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

  void update(double fraction) {
    if (!bar_ && !lines_) return;
    const int pct = static_cast<int>(fraction * 100.0 + 0.5);
    if (pct == last_) return;
    if (lines_) {
      const auto now = std::chrono::steady_clock::now();
      if (std::chrono::duration<double>(now - last_line_).count() < kProgressLineSeconds) return;
      last_line_ = now;
      last_ = pct;
      std::fprintf(stderr, "%s: %d%% (%.0f s elapsed)\n", label_.c_str(), pct,
                   std::chrono::duration<double>(now - start_).count());
      return;
    }
    last_ = pct;
    const int width = 40, fill = pct * width / 100;
    std::fprintf(stderr, "\r%s [%.*s%*s] %3d%%", label_.c_str(), fill,
                 "========================================", width - fill, "", pct);
    std::fflush(stderr);
  }
  void finish() {
    if (bar_ && last_ >= 0) std::fprintf(stderr, "\n");
    bar_ = lines_ = false;
  }

 private:
  std::string label_;
  bool bar_, lines_;
  int last_ = -1;
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
