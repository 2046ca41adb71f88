// Tests for sim/simulator.h's timing of the servo tick: a simulated run's servo stands in for the
// field edit's worker (fast/tooth/field.h FieldEditWorker::publish: it edits a due batch the
// worker has not started, or waits for one the worker is on), and the run reports the servo's own
// tick (timing_us "servo_tick") with exactly that time, as the publish's clock measured it, left
// out of the tick. No wall-clock magnitude is asserted: only identities between the clocks' sums
// and the order of pointwise-smaller series.
#include "sim/simulator.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "fast/tooth/field.h"
#include "sim/run_report.h"

namespace dentsim {
namespace {

std::map<std::string, StageStats> timing_of(const RunResult& r) {
  std::map<std::string, StageStats> t;
  for (const auto& [name, s] : r.timing) t[name] = s;
  return t;
}

// The servo's own tick is the tick without the stand-in, tick by tick (servo_i = tick_i - s_i,
// s_i >= 0), so each order statistic of the servo ticks is at most the tick's; and the stand-in
// ran inside the collide stage (contacts()), so each of its order statistics is at most that
// stage's.
void expect_servo_tick_within_the_tick(const RunResult& r) {
  const std::map<std::string, StageStats> t = timing_of(r);
  ASSERT_EQ(t.count("servo_tick"), 1u);
  ASSERT_EQ(t.count("field_edit_stand_in"), 1u);
  const StageStats& tick = t.at("tick");
  const StageStats& servo = t.at("servo_tick");
  const StageStats& stand_in = t.at("field_edit_stand_in");
  const StageStats& collide = t.at("collide");
  EXPECT_LE(servo.median_us, tick.median_us);
  EXPECT_LE(servo.p99_us, tick.p99_us);
  EXPECT_LE(servo.max_us, tick.max_us);
  EXPECT_LE(servo.mean_us, tick.mean_us);
  EXPECT_GE(stand_in.median_us, 0.0);
  EXPECT_LE(stand_in.max_us, collide.max_us);
  EXPECT_LE(stand_in.p99_us, collide.p99_us);
  // Exactly: the ticks' sum less the servo ticks' sum is what the publish's clock measured.
  EXPECT_EQ(r.tick_ns_total - r.servo_tick_ns_total, r.field_edit_stand_in_ns);
}

// The worker held (it claims no batch): the servo edits every due batch itself.
TEST(RunScene, TheServoTickLeavesOutTheFieldEditsTakeovers) {
  const Scene scene = load_scene_patched("drill", {{"tooth", {{"contact_model", "field"}}}}, "");
  RunOptions o;
  o.pipeline = "fast";
  o.duration_override = 2.0;  // drilling from ~1.5 s: hundreds of batches
  bool held = false;
  o.prepare_rig = [&held](SceneRig& rig) {
    auto* provider = dynamic_cast<fast::FieldContactProvider*>(rig.tooth_provider);
    if (provider == nullptr || provider->worker() == nullptr) return;
    provider->worker()->hold(true);
    held = true;
  };
  const RunResult r = run_scene(scene, o);
  ASSERT_TRUE(held) << "the fast field provider has no worker";
  ASSERT_TRUE(r.faults.empty()) << r.faults.front();
  ASSERT_GT(r.removed_volume_total_mm3, 0.0);
  std::printf("%ld ticks, %ld takeovers, %ld waits, %.3f ms stood in for; tick %.1f ms, servo "
              "tick %.1f ms in all\n",
              r.ticks, r.field_edit_servo_takeovers, r.field_edit_worker_waits,
              1e-6 * r.field_edit_stand_in_ns, 1e-6 * r.tick_ns_total,
              1e-6 * r.servo_tick_ns_total);
  EXPECT_GT(r.field_edit_servo_takeovers, 0);
  EXPECT_EQ(r.field_edit_worker_waits, 0);  // held: the worker is never on a batch
  EXPECT_GT(r.field_edit_stand_in_ns, 0);   // each takeover timed
  EXPECT_LT(r.servo_tick_ns_total, r.tick_ns_total);
  expect_servo_tick_within_the_tick(r);
  // The report's new keys beside the old ones (which keep their meaning).
  const nlohmann::json j = run_report_json(scene, r);
  EXPECT_EQ(j.at("field_edit_servo_takeovers").get<long>(), r.field_edit_servo_takeovers);
  EXPECT_EQ(j.at("field_edit_worker_waits").get<long>(), 0);
  for (const char* key : {"tick", "servo_tick", "field_edit_stand_in"}) {
    ASSERT_TRUE(j.at("timing_us").contains(key)) << key;
  }
  EXPECT_EQ(j["timing_us"]["servo_tick"]["max"].get<double>(), timing_of(r).at("servo_tick").max_us);
}

// Nothing stood in for (the sdf model: no worker): the servo tick is the tick, exactly.
TEST(RunScene, TheServoTickIsTheTickWithoutAWorker) {
  RunOptions o;
  o.pipeline = "fast";
  o.duration_override = 2.0;
  const RunResult r = run_scene(load_scene("drill"), o);
  ASSERT_TRUE(r.faults.empty()) << r.faults.front();
  EXPECT_EQ(r.field_edit_servo_takeovers, 0);
  EXPECT_EQ(r.field_edit_worker_waits, 0);
  EXPECT_EQ(r.field_edit_stand_in_ns, 0);
  EXPECT_EQ(r.servo_tick_ns_total, r.tick_ns_total);
  const std::map<std::string, StageStats> t = timing_of(r);
  EXPECT_EQ(t.at("servo_tick").median_us, t.at("tick").median_us);
  EXPECT_EQ(t.at("servo_tick").p99_us, t.at("tick").p99_us);
  EXPECT_EQ(t.at("servo_tick").max_us, t.at("tick").max_us);
  EXPECT_EQ(t.at("field_edit_stand_in").max_us, 0.0);
  expect_servo_tick_within_the_tick(r);
}

// RunOptions::tick_times_path: one row per measured tick, whose stage times add up to the run's
// tick total, whose contacts are the quiet series', and whose removed voxels are the drill log's.
TEST(RunScene, TickTimesHoldEveryTicksStagesContactsAndRemovals) {
  const std::filesystem::path path = std::filesystem::temp_directory_path() /
                                     ("dentsim_tick_times_" + std::to_string(getpid()) + ".csv");
  RunOptions o;
  o.pipeline = "fast";
  o.duration_override = 2.0;  // contact from ~0.9 s, drilling from ~1.5 s
  o.tick_times_path = path.string();
  const RunResult r = run_scene(load_scene("drill"), o);
  ASSERT_TRUE(r.faults.empty()) << r.faults.front();
  std::ifstream f(path);
  std::string line;
  ASSERT_TRUE(std::getline(f, line));
  std::vector<std::string> header;
  for (std::stringstream ss(line); std::getline(ss, header.emplace_back(), ',');) {
  }
  header.pop_back();
  ASSERT_EQ(header.size(), 1u + kStageCount + 4u + 5u);
  EXPECT_EQ(header[1], std::string(tick_stage_name(0)) + "_us");
  EXPECT_EQ(header[kStageCount + 1], "tick_us");
  EXPECT_EQ(header[kStageCount + 6], "removed_voxels");
  long rows = 0, removed = 0;
  double tick_us = 0.0, stages_us = 0.0;
  while (std::getline(f, line)) {
    std::vector<double> v;
    std::string cell;
    for (std::stringstream ss(line); std::getline(ss, cell, ',');) v.push_back(std::stod(cell));
    ASSERT_EQ(v.size(), header.size());
    EXPECT_EQ(v[0], rows);
    for (int s = 0; s < kStageCount; ++s) stages_us += v[1 + s];
    tick_us += v[kStageCount + 1];
    EXPECT_EQ(v[kStageCount + 5], r.quiet_series.contacts[static_cast<std::size_t>(rows)]);
    removed += static_cast<long>(v[kStageCount + 6]);
    ++rows;
  }
  std::filesystem::remove(path);
  EXPECT_EQ(rows, r.ticks);
  EXPECT_NEAR(tick_us, 1e-3 * static_cast<double>(r.tick_ns_total), 1e-6 * tick_us);
  EXPECT_NEAR(stages_us, tick_us, 1e-6 * tick_us);
  long logged = 0;
  for (const DrillRecord& d : r.drill_log) {
    for (const int n : d.removed) logged += n;
  }
  EXPECT_GT(logged, 0);
  EXPECT_EQ(removed, logged);
}

}  // namespace
}  // namespace dentsim
