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
#include <functional>
#include <nlohmann/json.hpp>
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

// Writes `j` (pretty-printed) to `path` atomically; throws naming the path on failure.
void write_json(const std::string& path, const nlohmann::json& j);

}  // namespace dentsim::cli

#define DENTSIM_CONCAT_INNER(a, b) a##b
#define DENTSIM_CONCAT(a, b) DENTSIM_CONCAT_INNER(a, b)
#define DENTSIM_REGISTER_COMMAND(fn) \
  static const ::dentsim::cli::Registrar DENTSIM_CONCAT(dentsim_registrar_, __LINE__)(fn)
