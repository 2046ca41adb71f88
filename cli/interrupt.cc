#include "cli/interrupt.h"

#include <csignal>

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

}  // namespace

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

}  // namespace dentsim::cli
