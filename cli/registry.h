// Subcommand registry of the dentsim CLI. Each cli/cmd_*.cc defines a setup function that adds
// its subcommand to the root app and registers it with DENTSIM_REGISTER_COMMAND, so adding a
// subcommand needs no edit elsewhere.
//
// Conventions for every subcommand:
// - options bind to a std::shared_ptr<Options> captured by the callback;
// - bad input throws dentsim::InputError (reference/core/io.h) with a message naming the file,
//   the field and what was expected: main prints it on one line and exits with status 2;
// - numbers go to `--json FILE` (written atomically with write_json below);
// - progress goes to stderr, only when stderr is a terminal and CI is unset (see progress.h).
#pragma once

#include <CLI/CLI.hpp>
#include <cmath>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace dentsim::cli {

using SetupFn = std::function<void(CLI::App&)>;

std::vector<SetupFn>& command_registry();

struct Registrar {
  explicit Registrar(SetupFn fn) { command_registry().push_back(std::move(fn)); }
};

// The subcommand `name` of `parent`, created (with `description`) when it does not exist yet, so
// that two files can add children to one group (e.g. `crosscheck device`, `crosscheck octree`).
CLI::App* group(CLI::App& parent, const std::string& name, const std::string& description);

// A number flag that must be finite and within [lo, hi]: NaN and inf are refused (CLI::Range lets
// NaN through), and the range shows in --help. A value outside exits with status 2 naming the flag.
inline CLI::Validator finite_range(double lo, double hi) {
  std::ostringstream desc;
  desc << "in [" << lo << ", " << hi << "]";
  return CLI::Validator(
      [lo, hi](std::string& s) -> std::string {
        double v = 0.0;
        std::size_t used = 0;
        try {
          v = std::stod(s, &used);
        } catch (const std::exception&) {
          used = 0;
        }
        if (used != s.size() || !std::isfinite(v) || v < lo || v > hi) {
          std::ostringstream m;
          m << "expected a finite number in [" << lo << ", " << hi << "], got '" << s << "'";
          return m.str();
        }
        return "";
      },
      desc.str(), "FINITE_RANGE");
}

// A failure with its own exit status (neither 1, a runtime failure, nor 2, bad input): main
// prints "dentsim: <what>" on one line and exits with status() (e.g. 3: `excite` stopped by a
// device fault or a guard, its log kept and marked incomplete; 130/143: interrupted).
class ExitStatusError : public std::runtime_error {
 public:
  ExitStatusError(int status, const std::string& what)
      : std::runtime_error(what), status_(status) {}
  int status() const { return status_; }

 private:
  int status_;
};

// Writes `j` (pretty-printed) to `path` atomically; throws naming the path on failure.
void write_json(const std::string& path, const nlohmann::json& j);

}  // namespace dentsim::cli

#define DENTSIM_CONCAT_INNER(a, b) a##b
#define DENTSIM_CONCAT(a, b) DENTSIM_CONCAT_INNER(a, b)
#define DENTSIM_REGISTER_COMMAND(fn) \
  static const ::dentsim::cli::Registrar DENTSIM_CONCAT(dentsim_registrar_, __LINE__)(fn)
