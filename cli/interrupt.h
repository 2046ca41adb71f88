// Ctrl-C (SIGINT) and SIGTERM stop long work cleanly instead of losing it (issue #33, "work
// lost"). A command that can stop early holds a StopOnSignal while it works: the signal handler
// only sets an atomic flag; the loop owner checks the flag at its own boundaries (a servo tick, a
// job of a sweep), stops there, writes everything it has (marked partial, with the reason) and
// throws Interrupted, which main turns into one line and exit status 128 + the signal (130 for
// Ctrl-C, 143 for SIGTERM). A second signal ends the process at once (the handler is reset after
// the first). Holders: run, zwidth, bench, calibrate-seeds, crosscheck contact, crosscheck fast
// (excite has its own: the run's clean stop, calibration/excitation.h); calibrate holds a
// QuitOnSignal (below). The other commands take seconds, write only at their end and keep the
// default behaviour.
#pragma once

#include <atomic>
#include <functional>
#include <mutex>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

namespace dentsim::cli {

class StopOnSignal {
 public:
  StopOnSignal();   // installs the SIGINT and SIGTERM handlers (one holder at a time)
  ~StopOnSignal();  // restores the previous handlers
  StopOnSignal(const StopOnSignal&) = delete;
  StopOnSignal& operator=(const StopOnSignal&) = delete;

  // The flag the handler sets; loops check it (relaxed loads suffice: it only ever turns on).
  const std::atomic<bool>& flag() const;
  bool requested() const { return flag().load(std::memory_order_relaxed); }
  // The signal that stopped the work (0: none yet).
  int signal() const;
  // "SIGINT (Ctrl-C)", "SIGTERM" or "" when none.
  std::string signal_name() const;
  // The exit status for the signal: 128 + signal.
  int exit_status() const { return 128 + signal(); }
};

// For a command whose work cannot stop part way (a Ceres fit: `calibrate`) and has nothing
// partial to keep: while held, SIGINT / SIGTERM print "dentsim: interrupted: MESSAGE" and end the
// process at once with 128 + the signal (only write(2) and _exit(2) in the handler). Outputs are
// written atomically at the end, so an interrupted command leaves them as they were.
class QuitOnSignal {
 public:
  explicit QuitOnSignal(const std::string& message);  // one holder at a time
  ~QuitOnSignal();                                     // restores the previous handlers
  QuitOnSignal(const QuitOnSignal&) = delete;
  QuitOnSignal& operator=(const QuitOnSignal&) = delete;
};

// Thrown once the partial outputs are written; main prints "dentsim: interrupted: WHAT" and exits
// with `status`.
class Interrupted : public std::runtime_error {
 public:
  Interrupted(const std::string& what, int status) : std::runtime_error(what), status_(status) {}
  int status() const { return status_; }

 private:
  int status_;
};

// The jobs of a sweep (zwidth, bench; cli/mpi_sweep.h) that a signal may stop: wrap() makes a job
// refuse to start once the signal came and keeps each finished result; stopped() writes what this
// rank finished to `json` ({"partial": true, "partial_reason", "completed_jobs": [{"stage",
// "index", "result"}], plus `extra`) and returns the Interrupted to throw.
class StoppableJobs {
 public:
  explicit StoppableJobs(const StopOnSignal& stop) : stop_(stop) {}
  std::function<nlohmann::json(int)> wrap(const std::string& stage,
                                          const std::function<nlohmann::json(int)>& job);
  // `write`: this rank writes the outputs (rank 0).
  Interrupted stopped(const std::string& command, const std::string& json, bool write,
                      nlohmann::json extra = nlohmann::json::object());

 private:
  const StopOnSignal& stop_;
  std::mutex mu_;
  nlohmann::json done_ = nlohmann::json::array();
};

}  // namespace dentsim::cli
