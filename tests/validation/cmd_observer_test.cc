// End to end: `dentsim observer-report` writes the JSON it promises and rejects bad flags with
// exit status 2 and nothing written.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "reference/core/io.h"

namespace {

int run(const std::string& args) {
  const std::string cmd = std::string(DENTSIM_BINARY) + " " + args + " > /dev/null 2>&1";
  const int st = std::system(cmd.c_str());
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

TEST(CmdObserverReport, WritesBothRunsToJson) {
  const std::string out =
      (std::filesystem::temp_directory_path() / "dentsim_observer_report_test.json").string();
  std::filesystem::remove(out);
  ASSERT_EQ(run("observer-report --no-friction --ideal-sensing --json " + out), 0);
  const nlohmann::json j = nlohmann::json::parse(dentsim::read_file(out));
  ASSERT_EQ(j["runs"].size(), 2u);
  EXPECT_EQ(j["runs"][0]["model"], "true");
  EXPECT_EQ(j["runs"][1]["model"], "perturbed");
  EXPECT_DOUBLE_EQ(j["config"]["model_error"].get<double>(), 0.2);
  // Ideal sensing, true model: the fitted lag is 1/L = 10 ms.
  EXPECT_NEAR(j["runs"][0]["lag_s"].get<double>(), 0.01, 5e-4);
  std::filesystem::remove(out);
}

TEST(CmdObserverReport, BadFlagsExitTwoAndWriteNothing) {
  const std::string out =
      (std::filesystem::temp_directory_path() / "dentsim_observer_report_bad.json").string();
  std::filesystem::remove(out);
  EXPECT_EQ(run("observer-report --model-error -1.5 --json " + out), 2);
  EXPECT_EQ(run("observer-report --gain 0 --json " + out), 2);
  EXPECT_EQ(run("observer-report --model /nonexistent/model.json --json " + out), 2);
  EXPECT_FALSE(std::filesystem::exists(out));
}

}  // namespace
