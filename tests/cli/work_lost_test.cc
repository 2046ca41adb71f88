// End-to-end tests of issue #33's "work lost" and "results that say what they mean": outputs are
// checked before the work (exit 2 naming the flag, nothing computed, nothing written); Ctrl-C /
// SIGTERM stop `dentsim run` and `dentsim zwidth` at a boundary with every output of the work done
// so far written and marked partial, exit 128 + signal; the checks print PASS/FAIL against their
// bounds and exit 1 on FAIL (a check that compared nothing fails).
//
// The signal is sent once the command has printed its first line on stderr (printed after the
// handler is installed), so the tests do not depend on timing: whenever the signal lands, the
// command must stop at its next boundary and write what it has.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <signal.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "reference/core/io.h"
#include "tests/support/cli.h"

namespace {

namespace fs = std::filesystem;
using dentsim::testing::fresh_temp_dir;
using dentsim::testing::read_json_file;
using dentsim::testing::run_dentsim;
using dentsim::testing::run_and_signal;
using dentsim::testing::Signalled;
using ::testing::HasSubstr;

// --out that is a file, --json that is a directory, a parent that does not exist: exit 2 before
// any work, the message naming the flag, no other output written.
TEST(WorkLost, OutputsAreCheckedBeforeTheWork) {
  const fs::path d = fresh_temp_dir("dentsim_work_lost_outputs");
  const std::string file = (d / "a_file").string();
  std::ofstream(file) << "keep\n";
  const std::string json = (d / "z.json").string();
  struct Case {
    std::string args, needle;
  };
  const Case cases[] = {
      {"zwidth --quick --out " + file + " --json " + json,
       "--out '" + file + "': exists and is not a directory"},
      {"zwidth --quick --json " + d.string(), "--json '" + d.string() + "': is a directory"},
      {"bench --out " + file + " --json " + json, "--out '" + file + "'"},
      {"run probe --out " + file, "--out '" + file + "'"},
      {"run probe --out " + (d / "o").string() + " --record " + d.string(), "--record"},
      {"crosscheck fast --json " + (d / "no" / "x.json").string(), "--json"},
      {"replay " + file + " --json " + file, "is the input FILE"},
      {"render probe --at 0 --png " + (d / "no" / "x.png").string(), "--png"},
      {"voxelize --procedural --resolution 32 --json " + json + " --write-volume " + file,
       "--write-volume '" + file + "': exists and is not a directory"},
  };
  for (const Case& c : cases) {
    const auto r = run_dentsim(c.args);
    EXPECT_EQ(r.status, 2) << c.args << "\n" << r.output;
    EXPECT_THAT(r.output, HasSubstr(c.needle)) << c.args;
    EXPECT_FALSE(fs::exists(json)) << c.args;
    EXPECT_EQ(dentsim::read_file(file), "keep\n") << c.args;
  }
  EXPECT_FALSE(fs::exists(d / "o"));
}

// Ctrl-C during `dentsim run`: the run stops at a tick boundary, report.json says "partial": true
// with the reason, the time series and the plots are there, one line says so, exit 130.
TEST(WorkLost, InterruptedRunWritesItsPartialOutputs) {
  const fs::path d = fresh_temp_dir("dentsim_work_lost_run");
  const fs::path out = d / "out";
  const Signalled r = run_and_signal({"run", "probe", "--duration", "600", "--out", out.string()},
                                     "dentsim run: scene", SIGINT);
  EXPECT_EQ(r.status, 130) << r.output;
  EXPECT_THAT(r.output, HasSubstr("dentsim: interrupted: run stopped by SIGINT (Ctrl-C) at t = "));
  const nlohmann::json report = read_json_file(out / "report.json");
  ASSERT_TRUE(report.is_object()) << r.output;
  EXPECT_EQ(report["partial"], true);
  EXPECT_THAT(report["partial_reason"].get<std::string>(), HasSubstr("SIGINT"));
  const long ticks = report["ticks"].get<long>();
  EXPECT_LT(ticks, 600000);  // stopped early: 600 s at 1 kHz never ran
  for (const char* f : {"timeseries.csv", "force_penetration.png", "observer.png",
                        "tooth_before.png", "tooth_after.png"}) {
    EXPECT_TRUE(fs::exists(out / f)) << f;
  }
  // One row per tick that ran (plus the header).
  std::ifstream csv(out / "timeseries.csv");
  long lines = 0;
  for (std::string line; std::getline(csv, line);) ++lines;
  EXPECT_EQ(lines, ticks + 1);
}

TEST(WorkLost, TerminatedRunExits143WithPartialOutputs) {
  const fs::path d = fresh_temp_dir("dentsim_work_lost_term");
  const fs::path out = d / "out";
  const Signalled r = run_and_signal({"run", "drill", "--duration", "600", "--out", out.string()},
                                     "dentsim run: scene", SIGTERM);
  EXPECT_EQ(r.status, 143) << r.output;
  EXPECT_EQ(read_json_file(out / "report.json")["partial"], true) << r.output;
}

// The --json of a command stopped by `sig`: exit 128 + sig, the line "dentsim: interrupted:
// COMMAND stopped by SIGNAL", "partial": true with a reason naming the signal (null when the file
// is missing: the caller's ASSERT on is_object() then fails).
nlohmann::json partial_json(const Signalled& r, const std::string& command, int sig,
                            const fs::path& json) {
  const std::string name = sig == SIGINT ? "SIGINT" : "SIGTERM";
  EXPECT_EQ(r.status, 128 + sig) << r.output;
  EXPECT_THAT(r.output, HasSubstr("dentsim: interrupted: " + command + " stopped by " + name));
  const nlohmann::json j = read_json_file(json);
  if (!j.is_object()) return j;
  EXPECT_EQ(j["partial"], true);
  EXPECT_THAT(j["partial_reason"].get<std::string>(), HasSubstr(name));
  return j;
}

// Ctrl-C during `dentsim zwidth`: no new job starts, the jobs done go to --json marked partial.
TEST(WorkLost, InterruptedZwidthWritesPartialJson) {
  const fs::path d = fresh_temp_dir("dentsim_work_lost_zwidth");
  const fs::path json = d / "z.json";
  const Signalled r = run_and_signal({"zwidth", "--quick", "--threads", "1", "--methods",
                                      "explicit", "--operators", "force", "--json", json.string()},
                                     "dentsim zwidth:", SIGINT);
  const nlohmann::json j = partial_json(r, "zwidth", SIGINT, json);
  ASSERT_TRUE(j.is_object()) << r.output;
  EXPECT_LT(j["completed_jobs"].size(), j["grid_runs"].get<std::size_t>());
}

// SIGTERM during `dentsim calibrate-seeds`, as seed 2 starts: its excitation stops, no seed
// after it starts, seed 1 goes to --json (its entry, the summary over it) marked partial, exit
// 143; seed 1's --out files are there, seed 2's not.
TEST(WorkLost, InterruptedCalibrateSeedsWritesPartialJson) {
  const fs::path d = fresh_temp_dir("dentsim_work_lost_seeds");
  const fs::path json = d / "s.json";
  const Signalled r = run_and_signal(
      {"calibrate-seeds", "--count", "3", "--duration", "2", "--design-iterations", "0",
       "--max-samples", "300", "--json", json.string(), "--out", (d / "seeds").string()},
      "calibrate-seeds: seed 2: excite", SIGTERM);
  const nlohmann::json j = partial_json(r, "calibrate-seeds", SIGTERM, json);
  ASSERT_TRUE(j.is_object()) << r.output;
  EXPECT_EQ(j["command"], "calibrate-seeds");
  ASSERT_EQ(j["seeds"].size(), 1u) << j.dump();
  EXPECT_EQ(j["seeds"][0]["seed"], 1);
  EXPECT_EQ(j["completed_jobs"].size(), 1u);
  EXPECT_EQ(j["summary"]["fits"], 1);
  EXPECT_TRUE(fs::exists(d / "seeds" / "seed1" / "fit.json"));
  EXPECT_FALSE(fs::exists(d / "seeds" / "seed2"));
  EXPECT_THAT(r.output, ::testing::Not(HasSubstr("seed 3: excite")));
}

// Ctrl-C during `dentsim crosscheck contact` (a sweep of minutes at 256^3 and 512^3): it stops
// before its next probe, writes the rows so far (the resolution in progress marked partial, its
// sliding ripple not measured: null) to --json marked partial, exit 130.
TEST(WorkLost, InterruptedContactSweepWritesPartialJson) {
  const fs::path d = fresh_temp_dir("dentsim_work_lost_contact");
  const fs::path json = d / "c.json";
  const Signalled r = run_and_signal({"crosscheck", "contact", "--resolutions", "64", "128",
                                      "--models", "sdf", "--probes", "400", "--data-dir", "",
                                      "--json", json.string()},
                                     "crosscheck contact:", SIGINT);
  const nlohmann::json j = partial_json(r, "crosscheck contact", SIGINT, json);
  ASSERT_TRUE(j.is_object()) << r.output;
  ASSERT_FALSE(j["rows"].empty()) << j.dump();
  const nlohmann::json& last = j["rows"].back();
  EXPECT_EQ(last["partial"], true);
  EXPECT_TRUE(last["sliding_ripple_rms"].is_null());
  EXPECT_LT(last["runs"].get<long>(), 400 * 3);
}

// Ctrl-C during `dentsim crosscheck fast`: no configuration starts after it; what ran is written
// to --json marked partial, exit 130.
TEST(WorkLost, InterruptedFastCrosscheckWritesPartialJson) {
  const fs::path d = fresh_temp_dir("dentsim_work_lost_fast");
  const fs::path json = d / "f.json";
  const Signalled r = run_and_signal(
      {"crosscheck", "fast", "--stage-ticks", "3000", "--duration", "1", "--json", json.string()},
      "crosscheck fast:", SIGINT);
  const nlohmann::json j = partial_json(r, "crosscheck fast", SIGINT, json);
  ASSERT_TRUE(j.is_object()) << r.output;
  EXPECT_THAT(j["partial_reason"].get<std::string>(), HasSubstr("before"));
}

// SIGTERM during `dentsim calibrate`'s fit: it ends at once, one line saying nothing was written,
// exit 143, the outputs as they were.
TEST(WorkLost, TerminatedCalibrateSaysNothingWasWritten) {
  const fs::path d = fresh_temp_dir("dentsim_work_lost_calibrate");
  const std::string log = (d / "log.csv").string();
  ASSERT_EQ(run_dentsim("excite -o " + log + " --duration 6 --design-iterations 0").status, 0);
  const std::string model = (d / "m.json").string();
  std::ofstream(model) << "keep\n";
  const Signalled r = run_and_signal(
      {"calibrate", log, "--json", (d / "f.json").string(), "-o", model}, "calibrate: fitting",
      SIGTERM);
  EXPECT_EQ(r.status, 143) << r.output;
  EXPECT_THAT(r.output, HasSubstr("dentsim: interrupted: calibrate: the fit of " + log +
                                  " was not finished; nothing written"));
  EXPECT_FALSE(fs::exists(d / "f.json"));
  EXPECT_EQ(dentsim::read_file(model), "keep\n");
}

// A check that compared nothing fails: `crosscheck octree` with no voxel to find (every query
// empty) — and a check that compared something passes, printing each bound.
TEST(Verdicts, ChecksPrintTheirBoundsAndExitOneOnFail) {
  const fs::path d = fresh_temp_dir("dentsim_verdicts");
  const auto pass =
      run_dentsim("crosscheck octree --n 16 --spheres 200 --json " + (d / "o.json").string());
  EXPECT_EQ(pass.status, 0) << pass.output;
  EXPECT_THAT(pass.output, HasSubstr("crosscheck octree: PASS"));
  EXPECT_THAT(pass.output, HasSubstr("<= 0"));
  EXPECT_EQ(read_json_file(d / "o.json")["verdict"], "PASS");

  const auto device = run_dentsim("crosscheck device --samples 20 --duration 0.001");
  EXPECT_EQ(device.status, 1) << device.output;  // the trajectory did not move: compared nothing
  EXPECT_THAT(device.output, HasSubstr("trajectory range (the device moved)"));
  EXPECT_THAT(device.output, HasSubstr("crosscheck device: FAIL"));
}

// The help says what the parser does: `bench --out` is required unless --list (and bench without
// it is refused, exit 2, naming it); `run --help` names every built-in scene `run --list` lists.
TEST(Help, SaysWhatTheParserRequires) {
  const auto bench_help = run_dentsim("bench --help");
  EXPECT_EQ(bench_help.status, 0);
  EXPECT_THAT(bench_help.output, HasSubstr("REQUIRED unless --list"));
  const auto bench = run_dentsim("bench --duration 0.01");
  EXPECT_EQ(bench.status, 2) << bench.output;
  EXPECT_THAT(bench.output, HasSubstr("--out"));
  EXPECT_EQ(run_dentsim("bench --list").status, 0);

  const auto list = run_dentsim("run --list");
  ASSERT_EQ(list.status, 0);
  const auto run_help = run_dentsim("run --help");
  std::istringstream lines(list.output);
  int scenes = 0;
  for (std::string line; std::getline(lines, line);) {
    const std::string name = line.substr(0, line.find(' '));
    if (name.empty()) continue;
    ++scenes;
    EXPECT_THAT(run_help.output, HasSubstr(name)) << "run --help does not name " << name;
  }
  EXPECT_GE(scenes, 3);
}

}  // namespace
