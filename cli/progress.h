// A progress bar on stderr, shown only when stderr is a terminal and CI is unset (quiet in CI and
// in logs).
#pragma once

#include <cstdio>
#include <cstdlib>
#include <string>
#include <unistd.h>

namespace dentsim::cli {

class ProgressBar {
 public:
  explicit ProgressBar(std::string label, bool enabled = true)
      : label_(std::move(label)),
        on_(enabled && ::isatty(2) != 0 && std::getenv("CI") == nullptr) {}
  ~ProgressBar() { finish(); }

  void update(double fraction) {
    if (!on_) return;
    const int pct = static_cast<int>(fraction * 100.0 + 0.5);
    if (pct == last_) return;
    last_ = pct;
    const int width = 40, fill = pct * width / 100;
    std::fprintf(stderr, "\r%s [%.*s%*s] %3d%%", label_.c_str(), fill,
                 "========================================", width - fill, "", pct);
    std::fflush(stderr);
  }
  void finish() {
    if (on_ && last_ >= 0) std::fprintf(stderr, "\n");
    on_ = false;
  }

 private:
  std::string label_;
  bool on_;
  int last_ = -1;
};

}  // namespace dentsim::cli
