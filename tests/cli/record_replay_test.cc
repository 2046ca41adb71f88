// `dentsim run SCENE --record FILE` and `dentsim replay FILE --pipeline fast|reference` (issue
// #15): the recorded drill session replays bit for bit through the pipeline that recorded it, the
// other pipeline agrees with it to round-off until the first discrete drilling event
// (docs/tolerance_policy.md item 9), and a run that faults keeps every tick up to and including
// the faulting one.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "sim/session_record.h"
#include "tests/support/cli.h"

namespace dentsim {
namespace {

namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& name) {
  return testing::fresh_temp_dir("dentsim_record_replay_" + name);
}

nlohmann::json read_json(const fs::path& p) { return testing::read_json_file(p); }

TEST(RecordReplay, DrillSessionReplaysThroughBothPipelines) {
  const fs::path d = fresh_dir("drill");
  const std::string rec = (d / "drill.rec").string();
  const auto run = testing::run_dentsim("run drill --duration 2.5 --record " + rec + " --out " +
                                        (d / "out").string());
  ASSERT_EQ(run.status, 0) << run.output;
  const nlohmann::json report = read_json(d / "out" / "report.json");
  EXPECT_EQ(report["recorded_ticks"], 2500);
  EXPECT_EQ(report["record_dropped_ticks"], 0);
  const Session s = read_session(rec);
  ASSERT_EQ(s.records.size(), 2500u);
  EXPECT_EQ(s.header.dof, 6);
  long contact_ticks = 0;
  for (const SessionRecord& r : s.records) contact_ticks += r.contacts > 0;
  ASSERT_GT(contact_ticks, 300) << "the session must exercise contact";

  // The recording pipeline (fast, the default) reproduces its own commands bit for bit.
  const auto same = testing::run_dentsim("replay " + rec + " --pipeline fast --json " +
                                         (d / "fast.json").string());
  ASSERT_EQ(same.status, 0) << same.output;
  const nlohmann::json f = read_json(d / "fast.json");
  EXPECT_EQ(f["environment"].get<std::string>().rfind("the recorded scene", 0), 0u);
  EXPECT_EQ(f["ticks"], 2500);
  EXPECT_EQ(f["max_torque_diff_n_m"].get<double>(), 0.0);
  EXPECT_EQ(f["contact_count_mismatches"], 0);
  EXPECT_EQ(f["first_divergent_tick"], -1);

  // The reference on the same samples: round-off until the first tick a voxel is removed one
  // tick apart (or never), and through the first contacts.
  const auto other = testing::run_dentsim("replay " + rec + " --pipeline reference --json " +
                                          (d / "ref.json").string());
  ASSERT_EQ(other.status, 0) << other.output;
  const nlohmann::json r = read_json(d / "ref.json");
  EXPECT_EQ(r["pipeline"], "reference");
  EXPECT_LE(r["max_force_diff_before_divergence_n"].get<double>(), 1e-9);
  const long first = r["first_divergent_tick"].get<long>();
  long contacts_before = 0;
  for (long k = 0; k < (first < 0 ? 2500 : first); ++k)
    contacts_before += s.records[k].contacts > 0;
  EXPECT_GT(contacts_before, 100) << "first divergent tick " << first;
  std::printf("reference replay of the fast drill session: agrees to %.3g N until tick %ld\n",
              r["max_force_diff_before_divergence_n"].get<double>(), first);
}

TEST(RecordReplay, FaultedRunKeepsEveryTickUpToTheFault) {
  const fs::path d = fresh_dir("fault");
  const std::string rec = (d / "fault.rec").string();
  const auto run = testing::run_dentsim(
      "run drill --duration 1 --inject-fault nan-sample@0.4 "
      "--record " +
      rec + " --out " + (d / "out").string());
  EXPECT_EQ(run.status, 1) << run.output;
  const Session s = read_session(rec);
  ASSERT_FALSE(s.records.empty());
  // Ticks 0 .. 400: the last is the faulting tick, whose sample carries the injected NaN.
  EXPECT_EQ(s.records.size(), 401u);
  EXPECT_FALSE(std::isfinite(s.records.back().sample.q[0]));
  EXPECT_TRUE(s.records.back().tau.isZero());
  for (std::size_t k = 0; k + 1 < s.records.size(); ++k) {
    ASSERT_TRUE(s.records[k].sample.q.allFinite()) << k;
  }
  EXPECT_EQ(read_json(d / "out" / "report.json")["recorded_ticks"], 401);
}

TEST(RecordReplay, RecordPathIsCheckedBeforeWork) {
  const fs::path d = fresh_dir("bad");
  const auto a = testing::run_dentsim("run drill --record " + (d / "no" / "x.rec").string() +
                                      " --out " + (d / "out").string());
  EXPECT_EQ(a.status, 2) << a.output;
  EXPECT_NE(a.output.find("--record"), std::string::npos) << a.output;
  EXPECT_FALSE(fs::exists(d / "out" / "report.json"));
  const auto b =
      testing::run_dentsim("replay " + (d / "missing.rec").string() + " --pipeline fast");
  EXPECT_EQ(b.status, 2) << b.output;
  const auto c = testing::run_dentsim("replay " + (d / "missing.rec").string() + " --pipeline x");
  EXPECT_EQ(c.status, 2) << c.output;
}

}  // namespace
}  // namespace dentsim
