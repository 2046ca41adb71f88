#include "cli/interrupt.h"

#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstring>

#include "cli/registry.h"

namespace dentsim::cli {
namespace {

std::atomic<bool> g_stop{false};
std::atomic<int> g_signal{0};
static_assert(std::atomic<bool>::is_always_lock_free && std::atomic<int>::is_always_lock_free,
              "the signal handler needs lock-free atomics");
struct sigaction g_old_int {
}, g_old_term{};

void on_stop_signal(int sig) {
  // Async-signal-safe: lock-free atomic stores only.
  g_signal.store(sig, std::memory_order_relaxed);
  g_stop.store(true, std::memory_order_relaxed);
}

// QuitOnSignal's line, composed before the handler is installed.
char g_quit_line[512];
std::size_t g_quit_len = 0;
struct sigaction g_quit_old_int {
}, g_quit_old_term{};

void on_quit_signal(int sig) {
  // Async-signal-safe: write(2) and _exit(2) only.
  if (::write(STDERR_FILENO, g_quit_line, g_quit_len) < 0) _exit(128 + sig);
  _exit(128 + sig);
}

}  // namespace

QuitOnSignal::QuitOnSignal(const std::string& message) {
  const std::string line = "dentsim: interrupted: " + message + "\n";
  g_quit_len = std::min(line.size(), sizeof g_quit_line);
  std::memcpy(g_quit_line, line.data(), g_quit_len);
  struct sigaction sa {};
  sa.sa_handler = on_quit_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, &g_quit_old_int);
  sigaction(SIGTERM, &sa, &g_quit_old_term);
}

QuitOnSignal::~QuitOnSignal() {
  sigaction(SIGINT, &g_quit_old_int, nullptr);
  sigaction(SIGTERM, &g_quit_old_term, nullptr);
}

StopOnSignal::StopOnSignal() {
  g_stop.store(false);
  g_signal.store(0);
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  // SA_RESETHAND: the second signal gets the default action (the process ends at once).
  sa.sa_flags = SA_RESETHAND;
  sigaction(SIGINT, &sa, &g_old_int);
  sigaction(SIGTERM, &sa, &g_old_term);
}

StopOnSignal::~StopOnSignal() {
  sigaction(SIGINT, &g_old_int, nullptr);
  sigaction(SIGTERM, &g_old_term, nullptr);
}

const std::atomic<bool>& StopOnSignal::flag() const { return g_stop; }

int StopOnSignal::signal() const { return g_signal.load(std::memory_order_relaxed); }

std::string StopOnSignal::signal_name() const {
  switch (signal()) {
    case SIGINT:
      return "SIGINT (Ctrl-C)";
    case SIGTERM:
      return "SIGTERM";
    case 0:
      return "";
    default:
      return "signal " + std::to_string(signal());
  }
}

std::function<nlohmann::json(int)> StoppableJobs::wrap(
    const std::string& stage, const std::function<nlohmann::json(int)>& job) {
  return [this, stage, job](int i) {
    if (stop_.requested()) throw std::runtime_error("interrupted before job " + std::to_string(i));
    nlohmann::json out = job(i);
    const std::lock_guard<std::mutex> lock(mu_);
    done_.push_back({{"stage", stage}, {"index", i}, {"result", out}});
    return out;
  };
}

Interrupted StoppableJobs::stopped(const std::string& command, const std::string& json, bool write,
                                   nlohmann::json extra) {
  const std::lock_guard<std::mutex> lock(mu_);
  const std::string why = "stopped by " + stop_.signal_name() + " after " +
                          std::to_string(done_.size()) + " jobs of this rank";
  if (write && !json.empty()) {
    extra["partial"] = true;
    extra["partial_reason"] = why;
    extra["completed_jobs"] = done_;
    write_json(json, extra);
  }
  return Interrupted(command + " " + why +
                         (json.empty() ? std::string("; no --json given, nothing written")
                                       : "; partial results in " + json +
                                             " (\"partial\": true, \"completed_jobs\")"),
                     stop_.exit_status());
}

}  // namespace dentsim::cli
