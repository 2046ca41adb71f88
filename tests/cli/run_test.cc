// End-to-end tests of `dentsim run` (issue #6): both built-in scenes in a short form, asserting on
// the report, plus the CLI's handling of bad input.
#include <gtest/gtest.h>

#include "tests/support/cli.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

namespace {

namespace fs = std::filesystem;

using Cmd = dentsim::testing::CliRun;
inline Cmd run(const std::string& args) { return dentsim::testing::run_dentsim(args); }

fs::path temp_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("dentsim_run_test_" + name);
  fs::remove_all(d);
  return d;
}

bool is_png(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  char sig[8] = {};
  f.read(sig, 8);
  return f.gcount() == 8 && std::string(sig + 1, 3) == "PNG" && fs::file_size(p) > 1000;
}

nlohmann::json run_scene(const std::string& scene, double duration) {
  const fs::path out = temp_dir(scene);
  const Cmd c = run("run " + scene + " --duration " + std::to_string(duration) + " --out " +
                    out.string());
  EXPECT_EQ(c.status, 0) << c.output;
  for (const char* f : {"force_penetration.png", "observer.png", "tooth_before.png",
                        "tooth_after.png"}) {
    EXPECT_TRUE(is_png(out / f)) << f;
  }
  EXPECT_GT(fs::file_size(out / "timeseries.csv"), 1000u);
  {
    // Every row of the time series has the header's columns; one row per tick.
    std::ifstream csv(out / "timeseries.csv");
    std::string line;
    std::getline(csv, line);
    const auto columns = std::count(line.begin(), line.end(), ',') + 1;
    EXPECT_EQ(columns, 27) << line;
    long rows = 0;
    while (std::getline(csv, line)) {
      EXPECT_EQ(std::count(line.begin(), line.end(), ',') + 1, columns);
      ++rows;
    }
    EXPECT_EQ(rows, static_cast<long>(std::llround(duration * 1000.0)));
  }
  std::ifstream in(out / "report.json");
  return nlohmann::json::parse(in);
}

// The Phantom's peak force (docs/device_facts.md §3: 8.5 N) bounds every force the device can feed
// back.
constexpr double kDeviceMaxForceN = 8.5;

void check_common(const nlohmann::json& r) {
  EXPECT_GT(r.at("ticks").get<long>(), 0);
  EXPECT_GT(r.at("contact_ticks").get<long>(), 100) << "the tool never touched the tooth";
  EXPECT_GT(r.at("max_contact_force_n").get<double>(), 0.05);
  EXPECT_LE(r.at("max_contact_force_n").get<double>(), kDeviceMaxForceN);
  EXPECT_GT(r.at("max_penetration_m").get<double>(), 0.0);
  // Passivity toward the hand (the time-domain passivity observer at the handle, docs/scenes.md):
  // the hand never got back more energy than it put in. The motor-port energy must be reported;
  // under pmi-pd it may be positive (the feed-forward supplies the device's own damping losses).
  EXPECT_GE(r.at("hand_work_min_j").get<double>(), -1e-6) << "the rendering was active at the hand";
  EXPECT_TRUE(r.at("passive_at_hand").get<bool>());
  EXPECT_TRUE(std::isfinite(r.at("virtual_energy_generated_j").get<double>()));
  EXPECT_GT(r.at("rendered_stiffness_n_per_m").get<double>(), 0.0);
  EXPECT_EQ(r.at("pipeline").get<std::string>(), "fast");  // the default pipeline (issue #14)
  for (const char* stage :
       {"device_terms", "observe", "collide", "assemble", "solve", "command", "drill", "tick"}) {
    const auto& t = r.at("timing_us").at(stage);
    EXPECT_LE(t.at("median").get<double>(), t.at("p99").get<double>());
    EXPECT_LE(t.at("p99").get<double>(), t.at("max").get<double>());
  }
  EXPECT_TRUE(r.at("faults").empty());
}

TEST(RunCli, ProbeTouchesWithoutRemovingTooth) {
  const nlohmann::json r = run_scene("probe", 2.5);
  check_common(r);
  EXPECT_EQ(r.at("removed_volume_mm3").at("total").get<double>(), 0.0);
  // The headline (issue #16): enamel rendered at >= 3000 N/m, passively (check_common), with an
  // explorer's force (0.5-2 N; measured 9369 N/m, RMS 0.68 N over the full 5 s run,
  // docs/scenes.md).
  EXPECT_GE(r.at("rendered_stiffness_n_per_m").get<double>(), 3000.0);
  EXPECT_LE(r.at("rms_contact_force_n").get<double>(), 2.0);
  EXPECT_GE(r.at("rms_contact_force_n").get<double>(), 0.3);
}

TEST(RunCli, DrillRemovesTooth) {
  const nlohmann::json r = run_scene("drill", 3.0);
  check_common(r);
  const auto& v = r.at("removed_volume_mm3");
  EXPECT_GT(v.at("total").get<double>(), 0.0);
  EXPECT_NEAR(v.at("total").get<double>(),
              v.at("enamel").get<double>() + v.at("dentin").get<double>() +
                  v.at("pulp").get<double>() + v.at("caries").get<double>(),
              1e-9);
  // Drilling starts at the occlusal surface: enamel goes first.
  EXPECT_GT(v.at("enamel").get<double>(), 0.0);
  // The first 3 s cut enamel only and do not open the pulp (the full 5 s reach dentin,
  // docs/scenes.md).
  EXPECT_EQ(v.at("pulp").get<double>(), 0.0);
  ASSERT_TRUE(r.contains("pulp_exposed_at_s"));
  EXPECT_TRUE(r.at("pulp_exposed_at_s").is_null());
}

TEST(RunCli, BadInputExitsTwoWithOneLine) {
  const Cmd unknown = run("run no-such-scene --out " + temp_dir("bad").string());
  EXPECT_EQ(unknown.status, 2) << unknown.output;
  EXPECT_NE(unknown.output.find("neither a built-in scene"), std::string::npos);
  const Cmd flag = run("run probe --no-such-flag");
  EXPECT_EQ(flag.status, 2);
  const fs::path bad = temp_dir("badscene");
  fs::create_directories(bad);
  {
    std::ofstream f(bad / "s.json");
    f << "{\"dentsim_scene\": 1, \"name\": \"x\", \"duration_s\": -1}";
  }
  const Cmd field = run("run " + (bad / "s.json").string() + " --out " + (bad / "o").string());
  EXPECT_EQ(field.status, 2);
  EXPECT_NE(field.output.find("duration_s: must be > 0"), std::string::npos) << field.output;
  EXPECT_FALSE(fs::exists(bad / "o" / "report.json"));
}

TEST(RunCli, ListsBuiltinScenes) {
  const Cmd c = run("run --list");
  EXPECT_EQ(c.status, 0);
  EXPECT_NE(c.output.find("probe"), std::string::npos);
  EXPECT_NE(c.output.find("drill"), std::string::npos);
}

// A fault injected into the tick (a NaN in the device sample from 0.4 s on) ends the run with the
// tick's named fault, zero torque over the faulting tick, and the report and time series written
// up to the fault (exit status non-zero, the fault named on stderr).
TEST(RunCli, InjectedNanSampleEndsInANamedFaultWithZeroTorqueAndTheReportWritten) {
  const fs::path out = temp_dir("fault");
  const Cmd c = run("run drill --duration 1 --inject-fault nan-sample@0.4 --out " + out.string());
  EXPECT_NE(c.status, 0) << c.output;
  EXPECT_NE(c.output.find("tick_bad_sample"), std::string::npos) << c.output;
  std::ifstream f(out / "report.json");
  ASSERT_TRUE(f.good()) << "the report must be written on a fault";
  const nlohmann::json r = nlohmann::json::parse(f);
  ASSERT_EQ(r.at("faults").size(), 1u);
  const std::string fault = r.at("faults")[0].get<std::string>();
  EXPECT_EQ(fault.rfind("tick_bad_sample at t = 0.4", 0), 0u) << fault;
  EXPECT_EQ(r.at("torque_after_fault_n_m").get<double>(), 0.0);
  // The run stopped at the fault: 400 good ticks, then the faulting one is not counted.
  EXPECT_EQ(r.at("ticks").get<long>(), 400);
  EXPECT_TRUE(is_png(out / "force_penetration.png"));
  std::ifstream csv(out / "timeseries.csv");
  long rows = 0;
  for (std::string line; std::getline(csv, line);) ++rows;
  EXPECT_EQ(rows, 401);  // header + one row per tick up to the fault
  // A malformed injection is refused before the run.
  const Cmd bad = run("run drill --inject-fault nan-sample@-1 --out " + out.string());
  EXPECT_EQ(bad.status, 2) << bad.output;
  EXPECT_NE(bad.output.find("--inject-fault"), std::string::npos) << bad.output;
}

}  // namespace

namespace {

// `--realtime` (issue #15): the loop is paced on absolute deadlines and report.json carries the
// servo timing statistics; whether SCHED_FIFO and locked memory were granted depends on the
// machine, and the warning says so exactly when one was refused. (No assertion on the times.)
TEST(RunCli, RealtimeRunReportsServoTimingStatistics) {
  const fs::path out = temp_dir("realtime");
  const Cmd c = run("run probe --duration 0.2 --realtime --out " + out.string());
  ASSERT_EQ(c.status, 0) << c.output;
  std::ifstream f(out / "report.json");
  const nlohmann::json j = nlohmann::json::parse(f);
  ASSERT_TRUE(j.contains("realtime")) << j.dump();
  const nlohmann::json& rt = j["realtime"];
  EXPECT_EQ(rt["ticks"], 200);
  EXPECT_GE(rt["overruns"].get<long>(), 0);
  EXPECT_GE(rt["skipped_deadlines"].get<long>(), 0);
  for (const char* part : {"period_us", "exec_us"}) {
    EXPECT_LE(rt[part]["median"].get<double>(), rt[part]["p99"].get<double>() + 1.0) << part;
    EXPECT_GT(rt[part]["max"].get<double>(), 0.0) << part;
  }
  const bool granted = rt["sched_fifo"].get<bool>() && rt["memory_locked"].get<bool>();
  EXPECT_EQ(granted, rt["warning"].get<std::string>().empty()) << rt["warning"];
  EXPECT_EQ(granted, c.output.find("warning:") == std::string::npos) << c.output;
}

// --tick-times FILE: one row per tick with the header's columns; a path that cannot be written is
// refused before the run (exit 2, no report).
TEST(RunCli, TickTimesWritesOneRowPerTickAndRefusesAnUnwritablePath) {
  const fs::path out = temp_dir("tick_times");
  fs::create_directories(out);  // the file's directory must exist before the run (--out's is made)
  const Cmd c = run("run probe --duration 0.1 --out " + out.string() + " --tick-times " +
                    (out / "ticks.csv").string());
  ASSERT_EQ(c.status, 0) << c.output;
  std::ifstream csv(out / "ticks.csv");
  std::string line;
  ASSERT_TRUE(std::getline(csv, line));
  EXPECT_EQ(line.rfind("k,", 0), 0u) << line;
  EXPECT_NE(line.find(",collide_us,"), std::string::npos) << line;
  EXPECT_NE(line.find(",tick_us,"), std::string::npos) << line;
  EXPECT_NE(line.find(",minor_faults,"), std::string::npos) << line;
  const auto columns = std::count(line.begin(), line.end(), ',') + 1;
  long rows = 0;
  while (std::getline(csv, line)) {
    EXPECT_EQ(std::count(line.begin(), line.end(), ',') + 1, columns);
    EXPECT_EQ(line.rfind(std::to_string(rows) + ",", 0), 0u) << line;
    ++rows;
  }
  EXPECT_EQ(rows, 100);  // 0.1 s at the probe scene's 1 kHz
  const fs::path refused = temp_dir("tick_times_refused");
  const Cmd bad = run("run probe --duration 0.1 --out " + refused.string() + " --tick-times " +
                      (refused / "no_such_dir" / "sub" / "t.csv").string());
  EXPECT_EQ(bad.status, 2) << bad.output;
  EXPECT_NE(bad.output.find("--tick-times"), std::string::npos) << bad.output;
  EXPECT_FALSE(fs::exists(refused / "report.json"));
}

}  // namespace
