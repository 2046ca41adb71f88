// Running the dentsim binary from end-to-end tests. DENTSIM_BINARY is the build's binary, in
// every test file (tests/support/build_paths.h, given by tests/CMakeLists.txt).
#pragma once

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

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

struct Signalled {
  int status = -1;     // exit status (-1: killed by a signal)
  std::string output;  // stdout and stderr
};

// Runs `dentsim ARGS` (no shell), sends `sig` once a line of stderr contains `marker`, and collects the rest.
inline Signalled run_and_signal(const std::vector<std::string>& args, const std::string& marker, int sig) {
  int fds[2];
  if (pipe(fds) != 0) return {};
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(fds[1], 1);
    dup2(fds[1], 2);
    close(fds[0]);
    close(fds[1]);
    std::vector<char*> argv;
    std::string bin = DENTSIM_BINARY;
    argv.push_back(bin.data());
    std::vector<std::string> copy = args;
    for (std::string& a : copy) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(bin.c_str(), argv.data());
    _exit(127);
  }
  close(fds[1]);
  Signalled out;
  FILE* f = fdopen(fds[0], "r");
  char buf[4096];
  bool sent = false;
  while (std::fgets(buf, sizeof buf, f) != nullptr) {
    out.output += buf;
    if (!sent && std::string(buf).find(marker) != std::string::npos) {
      kill(pid, sig);
      sent = true;
    }
  }
  fclose(f);
  int st = 0;
  waitpid(pid, &st, 0);
  out.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  if (!sent) out.output += "\n(test: the marker '" + marker + "' never came)";
  return out;
}

}  // namespace dentsim::testing
