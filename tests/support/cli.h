// Running the dentsim binary from end-to-end tests. DENTSIM_BINARY is a compile definition of
// every test executable (tests/CMakeLists.txt).
#pragma once

#include <sys/wait.h>

#include <cstdio>
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

}  // namespace dentsim::testing
