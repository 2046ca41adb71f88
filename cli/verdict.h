// The verdict of a check command (crosscheck device|fast|contact|octree, replay; issue #33,
// "results that say what they mean"): every compared quantity is printed with its bound and
// PASS/FAIL, then one line "NAME: PASS (n checks)" or "NAME: FAIL (k of n checks: ...)". A check
// that compared nothing (no samples, no contact) is a FAIL that says so, never a silent pass.
// finish() throws CheckFailed on FAIL: main prints it and exits with status 1 ("a check failed";
// 2 stays "bad input"), the exit status documented in README's "The command line".
#pragma once

#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

namespace dentsim::cli {

class CheckFailed : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Verdict {
 public:
  explicit Verdict(std::string name) : name_(std::move(name)) {}

  // value <= bound (or value >= bound with at_least) passes; NaN fails. Prints one line.
  bool check(const std::string& what, double value, double bound, const std::string& unit = "",
             bool at_least = false) {
    const bool pass = at_least ? value >= bound : value <= bound;
    std::printf("  %-44s %11.3g %s %-10.3g%-8s %s\n", what.c_str(), value,
                at_least ? ">=" : "<=", bound, unit.c_str(), pass ? "PASS" : "FAIL");
    record(what, pass);
    return pass;
  }
  // A condition that is not a number (e.g. "saw at least one contact"): printed with `detail`.
  bool require(const std::string& what, bool pass, const std::string& detail) {
    std::printf("  %-44s %-31s %s\n", what.c_str(), detail.c_str(), pass ? "PASS" : "FAIL");
    record(what, pass);
    return pass;
  }
  bool ok() const { return failed_.empty(); }
  int checks() const { return checks_; }
  const std::vector<std::string>& failed() const { return failed_; }

  // Prints the verdict line; throws CheckFailed on FAIL (exit status 1).
  void finish() const {
    if (ok()) {
      std::printf("%s: PASS (%d checks within their bounds)\n", name_.c_str(), checks_);
      return;
    }
    std::string list;
    for (const std::string& f : failed_) list += (list.empty() ? "" : ", ") + f;
    std::printf("%s: FAIL (%zu of %d checks: %s)\n", name_.c_str(), failed_.size(), checks_,
                list.c_str());
    std::fflush(stdout);
    throw CheckFailed(name_ + ": FAIL (" + list + ")");
  }

 private:
  void record(const std::string& what, bool pass) {
    ++checks_;
    if (!pass) failed_.push_back(what);
  }
  std::string name_;
  int checks_ = 0;
  std::vector<std::string> failed_;
};

}  // namespace dentsim::cli
