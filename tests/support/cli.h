// Running the dentsim binary from end-to-end tests. DENTSIM_BINARY is a compile definition of
// every test executable (tests/CMakeLists.txt).
#pragma once

#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

namespace dentsim::testing {

struct CliRun {
  int status;          // exit status (-1 if the process did not exit normally)
  std::string output;  // stdout and stderr together
};

// Runs `dentsim ARGS` through the shell and collects its output and exit status.
inline CliRun run_dentsim(const std::string& args) {
  const std::string cmd = std::string(DENTSIM_BINARY) + " " + args + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  std::string out;
  char buf[4096];
  while (p && std::fgets(buf, sizeof buf, p)) out += buf;
  const int st = p ? pclose(p) : -1;
  return {WIFEXITED(st) ? WEXITSTATUS(st) : -1, out};
}

// A fresh, empty directory under the system's temporary directory (removed first if it exists).
inline std::filesystem::path fresh_temp_dir(const std::string& name) {
  const std::filesystem::path d = std::filesystem::temp_directory_path() / name;
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

// A JSON file's document; null when the file cannot be read (the caller's assertions then fail).
inline nlohmann::json read_json_file(const std::filesystem::path& p) {
  std::ifstream f(p);
  return f.good() ? nlohmann::json::parse(f) : nlohmann::json();
}

}  // namespace dentsim::testing
