// The fast pipeline as every command's default (issue #14): `dentsim run`, `dentsim zwidth` and
// `dentsim observer-report` run `fast` unless told `--pipeline reference`, name the pipeline in
// their JSON, and agree with the reference within the closed-loop bounds of
// docs/tolerance_policy.md item 10.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/support/cli.h"

namespace {

namespace fs = std::filesystem;
using dentsim::testing::run_dentsim;

fs::path temp_dir(const std::string& name) {
  return dentsim::testing::fresh_temp_dir("dentsim_pipeline_default_" + name);
}

nlohmann::json read_json(const fs::path& p) { return dentsim::testing::read_json_file(p); }

// `dentsim run SCENE ARGS` into a fresh directory; its report.
nlohmann::json run_report(const std::string& scene, const std::string& args,
                          const std::string& tag) {
  const fs::path out = temp_dir(tag);
  const auto r = run_dentsim("run " + scene + " " + args + " --out " + out.string());
  EXPECT_EQ(r.status, 0) << r.output;
  return read_json(out / "report.json");
}

// Every number of `a` equals `b`'s within `rel` relative (absolute 1e-12 near zero); other values
// exactly, except the keys that name the run (pipeline, wall-clock timing).
void expect_close(const nlohmann::json& a, const nlohmann::json& b, double rel,
                  const std::string& path, double* worst) {
  if (a.is_object()) {
    ASSERT_TRUE(b.is_object()) << path;
    for (auto it = a.begin(); it != a.end(); ++it) {
      if (it.key() == "pipeline" || it.key() == "timing_us" || it.key() == "wall_s" ||
          it.key() == "setup_s")
        continue;
      ASSERT_TRUE(b.contains(it.key())) << path << "." << it.key();
      expect_close(it.value(), b[it.key()], rel, path + "." + it.key(), worst);
    }
  } else if (a.is_array()) {
    ASSERT_TRUE(b.is_array()) << path;
    ASSERT_EQ(a.size(), b.size()) << path;
    for (std::size_t i = 0; i < a.size(); ++i) {
      expect_close(a[i], b[i], rel, path + "[" + std::to_string(i) + "]", worst);
    }
  } else if (a.is_number_float()) {
    const double x = a.get<double>(), y = b.get<double>();
    const double d = std::abs(x - y);
    if (d > 1e-12) *worst = std::max(*worst, d / std::max(std::abs(x), 1e-300));
    EXPECT_TRUE(d <= 1e-12 || d <= rel * std::abs(x)) << path << ": " << x << " vs " << y;
  } else {
    EXPECT_EQ(a, b) << path;
  }
}

double rel_diff(const nlohmann::json& a, const nlohmann::json& b) {
  const double x = a.get<double>(), y = b.get<double>();
  return std::abs(x - y) / std::max(std::abs(y), 1e-300);
}

// The main job's scene on both pipelines, whole (5 s of drilling). The two runs agree to
// round-off until the first voxel whose accumulated work ties its threshold to the 16th digit
// (docs/results/fast_crosscheck.md); from then on the tools cut different cavities, so the
// report is compared in the statistics a user reads, with item 10's bounds.
TEST(PipelineDefault, RunDrillRunsFastAndMatchesTheReference) {
  const nlohmann::json f = run_report("drill", "", "drill_default");
  const nlohmann::json r = run_report("drill", "--pipeline reference", "drill_reference");
  ASSERT_FALSE(f.is_null());
  ASSERT_FALSE(r.is_null());
  EXPECT_EQ(f["pipeline"], "fast");
  EXPECT_EQ(r["pipeline"], "reference");
  EXPECT_EQ(f["ticks"], r["ticks"]);
  EXPECT_EQ(f["faults"], r["faults"]);
  EXPECT_EQ(f["passive_at_hand"], r["passive_at_hand"]);
  EXPECT_EQ(f["passive_at_motors"], r["passive_at_motors"]);
  // Signal guard: the run drills and touches (the bounds below are far smaller than the signal).
  ASSERT_GT(r["removed_volume_mm3"]["total"].get<double>(), 1.0);
  ASSERT_GT(r["max_contact_force_n"].get<double>(), 0.5);
  EXPECT_LT(rel_diff(f["removed_volume_mm3"]["total"], r["removed_volume_mm3"]["total"]), 0.10);
  EXPECT_LT(rel_diff(f["removed_volume_mm3"]["enamel"], r["removed_volume_mm3"]["enamel"]), 0.10);
  EXPECT_LT(rel_diff(f["max_contact_force_n"], r["max_contact_force_n"]), 0.10);
  EXPECT_LT(rel_diff(f["rms_contact_force_n"], r["rms_contact_force_n"]), 0.10);
  EXPECT_LT(rel_diff(f["max_penetration_m"], r["max_penetration_m"]), 0.10);
  // The rendered stiffness is the quotient of the two peak figures above, each bounded at 10 %:
  // since the anchored spring's implicit excess (issue #32) a held anchor is one more discrete
  // decision after the cavities part, and the quotient measured 8411 (fast) against 7965 N/m
  // (reference), 5.6 % (8077 against 8112 before). Bounded like its factors.
  EXPECT_LT(rel_diff(f["rendered_stiffness_n_per_m"], r["rendered_stiffness_n_per_m"]), 0.10);
  EXPECT_LT(rel_diff(f["contact_ticks"], r["contact_ticks"]), 0.05);
}

// The probe does not drill: no discrete event, the two pipelines stay at round-off for the whole
// run, so the whole report agrees to 1e-8 relative (item 10).
TEST(PipelineDefault, ProbeReportsAgreeToRoundOff) {
  const nlohmann::json f = run_report("probe", "--duration 2", "probe_default");
  const nlohmann::json r = run_report("probe", "--duration 2 --pipeline reference", "probe_ref");
  ASSERT_FALSE(f.is_null());
  EXPECT_EQ(f["pipeline"], "fast");
  ASSERT_GT(r["max_contact_force_n"].get<double>(), 0.5);
  double worst = 0.0;
  expect_close(r, f, 1e-8, "report", &worst);
  std::printf("probe: largest relative difference fast vs reference %.3g\n", worst);
}

TEST(PipelineDefault, ZwidthNamesItsPipelineAndAgrees) {
  const fs::path d = temp_dir("zwidth");
  const std::string grid =
      "zwidth --methods pmi-pd --operators force grip --k-vc 2400 --b-vc 4 --k-tooth 6000 "
      "--threads 1 --json ";
  const auto a = run_dentsim(grid + (d / "fast.json").string());
  ASSERT_EQ(a.status, 0) << a.output;
  EXPECT_NE(a.output.find("fast pipeline"), std::string::npos) << a.output;
  const auto b = run_dentsim(grid + (d / "ref.json").string() + " --pipeline reference");
  ASSERT_EQ(b.status, 0) << b.output;
  const nlohmann::json f = read_json(d / "fast.json"), r = read_json(d / "ref.json");
  EXPECT_EQ(f["pipeline"], "fast");
  EXPECT_EQ(r["pipeline"], "reference");
  double worst = 0.0;
  expect_close(r, f, 1e-6, "zwidth", &worst);
  std::printf("zwidth: largest relative difference fast vs reference %.3g\n", worst);
  const auto bad = run_dentsim("zwidth --testbed axis --pipeline turbo");
  EXPECT_EQ(bad.status, 2) << bad.output;
  EXPECT_NE(bad.output.find("--pipeline 'turbo'"), std::string::npos) << bad.output;
}

TEST(PipelineDefault, ObserverReportNamesItsPipelineAndAgrees) {
  const fs::path d = temp_dir("observer");
  const auto a = run_dentsim("observer-report --json " + (d / "fast.json").string());
  ASSERT_EQ(a.status, 0) << a.output;
  const auto b =
      run_dentsim("observer-report --pipeline reference --json " + (d / "ref.json").string());
  ASSERT_EQ(b.status, 0) << b.output;
  const nlohmann::json f = read_json(d / "fast.json"), r = read_json(d / "ref.json");
  EXPECT_EQ(f["config"]["pipeline"], "fast");
  EXPECT_EQ(r["config"]["pipeline"], "reference");
  // The estimate integrates the models' torques over 5 s; lags are fitted by least squares, so
  // round-off in the device terms reaches ~1e-7 of a lag (item 10).
  double worst = 0.0;
  expect_close(r, f, 1e-5, "observer", &worst);
  std::printf("observer-report: largest relative difference fast vs reference %.3g\n", worst);
  const auto bad = run_dentsim("observer-report --pipeline turbo");
  EXPECT_EQ(bad.status, 2) << bad.output;
}

TEST(PipelineDefault, TickRateFlagRunsTheSceneAtThatRate) {
  const nlohmann::json j = run_report("drill", "--duration 0.1 --tick-hz 8000", "rate");
  ASSERT_FALSE(j.is_null());
  EXPECT_EQ(j["tick_hz"], 8000.0);
  EXPECT_EQ(j["ticks"], 800);
  const auto bad = run_dentsim("run drill --tick-hz 50 --out " + temp_dir("rate_bad").string());
  EXPECT_EQ(bad.status, 2) << bad.output;
  EXPECT_NE(bad.output.find("--tick-hz"), std::string::npos) << bad.output;
}

}  // namespace
