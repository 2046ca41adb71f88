// The supervisor through `dentsim run` (issue #32): a harsh scene either stays bounded or ends in a
// named fault with zero torque and its outputs written (exit status non-zero, one line naming the
// fault and its figure); no report holds null or a non-finite number for a measured figure; the
// stress run whose PMI proxy exploded while drilling at 500 Hz ends safely in both pipelines; a
// scene outside its method's stability bound is refused before the run (exit 2,
// naming the field and the bound) and `--force` runs it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "tests/support/cli.h"

namespace {

namespace fs = std::filesystem;
using dentsim::testing::fresh_temp_dir;
using dentsim::testing::read_json_file;
using dentsim::testing::run_dentsim;

const std::string kData = std::string(DENTSIM_SOURCE_DIR) + "/tests/validation/data/";

// The Phantom's peak force (docs/device_facts.md §3) and the supervisor's default bound, 4 x it.
constexpr double kForceBoundN = 4.0 * 8.5;

// Every number in `j` is finite and nothing is null, except the keys a report leaves null by
// design (`pulp_exposed_at_s` when the pulp was never opened).
void expect_no_null(const nlohmann::json& j, const std::string& path) {
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it) {
      if (it.key() == "pulp_exposed_at_s") continue;
      expect_no_null(it.value(), path + "." + it.key());
    }
  } else if (j.is_array()) {
    for (std::size_t i = 0; i < j.size(); ++i) expect_no_null(j[i], path + "[" + std::to_string(i) + "]");
  } else {
    EXPECT_FALSE(j.is_null()) << path;
    if (j.is_number()) {
      EXPECT_TRUE(std::isfinite(j.get<double>())) << path;
    }
  }
}

// Whether `fault` is one of the supervisor's named faults.
bool is_supervisor_fault(const std::string& fault) {
  for (const char* name : {"virtual_non_finite", "contact_force_beyond_bound",
                           "coupling_force_beyond_bound", "proxy_too_deep", "proxy_too_far",
                           "virtual_energy_growth"}) {
    if (fault.rfind(name, 0) == 0) return true;
  }
  return false;
}

// The stress run of docs/results/reliability.md (seed 2026, run 1401: PMI drilling at 500 Hz, a
// 50 g proxy, K_tooth 26694 N/m, b_vc 5.4 N s/m): its contact force reached 2e78 N with `faults:
// none`. The cause: the surface proxy's spring across the normal, held by the drilled hole, was
// explicit inside PMI's step (K T/2 = 26.7 N s/m against b = 5.4 N s/m: energy x2 per tick). With
// the excess over that bound integrated at its midpoint (reference/contact.h
// add_anchored_spring_unchecked) the run stays bounded: no fault, every tick, exit 0, passive at
// the hand, the force that of a 2-5 N push on a stiff tooth (measured 25.4 N reference, 15.4 N
// fast; the supervisor's bound is 34 N).
TEST(SupervisorCli, StressRunThatExplodedWhileDrillingAt500HzStaysBounded) {
  for (const char* pipeline : {"reference", "fast"}) {
    const fs::path out = fresh_temp_dir(std::string("dentsim_sup_stress_") + pipeline);
    const auto r = run_dentsim("run " + kData + "stress_2026_run1401_pmi_drill_500hz.json --pipeline " +
                               pipeline + " --out " + out.string());
    const nlohmann::json j = read_json_file(out / "report.json");
    expect_no_null(j, pipeline);
    EXPECT_EQ(r.status, 0) << r.output;
    EXPECT_TRUE(j.at("faults").empty()) << j.at("faults");
    EXPECT_EQ(j.at("ticks").get<long>(), 2000);
    EXPECT_LE(j.at("max_contact_force_n").get<double>(), kForceBoundN) << pipeline;
    EXPECT_GT(j.at("max_contact_force_n").get<double>(), 1.0) << pipeline;  // it did drill
    EXPECT_TRUE(j.at("passive_at_hand").get<bool>()) << pipeline;
  }
}

// The long form's PMI drilling faults (docs/results/reliability.md "The long form's PMI drilling
// runs"; issue #32) were physical, not numerical: run 2505 of seed 2026 (pmi, 2000 Hz, K_tooth
// 35693 N/m, K_vc 7846 N/m), with method.saturation_passive off as it was then, ended in
// contact_force_beyond_bound with zero torque after the device's command had been saturated for
// ~0.2 s (the command scaled down uniformly, gravity compensation included: the device drifts off,
// the coupling stretches, the tooth holds the proxy). Since drilling carries a removed voxel's
// surplus work on (#30) the hole it drills differs and the same run peaked at 29.5 N, under the
// supervisor's 34 N, and since the push-out's corner step (#30) it crosses it again at 0.26 s
// (36.8 N): whether it crosses the bound depends on the cut. What does not: the same run
// on a device whose motors are ten times as strong (the supervisor's bound unchanged), or with
// saturation_passive on (the default now), stays without a fault at less than half the as-drawn
// run's peak force (11.3 N and 4.0 N): the force comes from the saturated device, not from the
// integration.
TEST(SupervisorCli, StressDrillingFaultCameFromTheSaturatedDeviceNotTheIntegration) {
  const std::string file = kData + "stress_2026_run2505_pmi_drill_2000hz.json";
  const fs::path dir = fresh_temp_dir("dentsim_sup_saturated");
  const auto as_drawn =
      run_dentsim("run " + file + " --pipeline reference --out " + (dir / "as_drawn").string());
  const nlohmann::json j = read_json_file(dir / "as_drawn" / "report.json");
  if (j.at("faults").empty()) {
    EXPECT_EQ(as_drawn.status, 0) << as_drawn.output;
  } else {
    // Past the bound: the named fault, zero torque.
    EXPECT_EQ(as_drawn.status, 1) << as_drawn.output;
    ASSERT_EQ(j.at("faults").size(), 1u) << as_drawn.output;
    EXPECT_EQ(j.at("faults")[0].get<std::string>().rfind("contact_force_beyond_bound", 0), 0u)
        << j.at("faults");
    EXPECT_EQ(j.at("torque_after_fault_n_m").get<double>(), 0.0);
  }
  expect_no_null(j, "as_drawn");
  // The report's peak is over the ticks that ran; the faulting tick's force, beyond the bound, is
  // in the fault's message only. A faulted run peaked at least at the bound.
  const double ran_peak_n = j.at("max_contact_force_n").get<double>();
  const double as_drawn_peak_n =
      j.at("faults").empty() ? ran_peak_n : std::max(ran_peak_n, kForceBoundN);
  EXPECT_GT(as_drawn_peak_n, 0.5 * kForceBoundN) << as_drawn.output;

  // The variants: the scene with saturation_passive on, and the scene on strong motors (the
  // shipped model, `dentsim device show`, with every joint's torque limit x10).
  const auto shown = run_dentsim("device show");
  ASSERT_EQ(shown.status, 0) << shown.output;
  nlohmann::json model = nlohmann::json::parse(shown.output);
  for (auto& tau : model.at("joints").at("torque_limit_n_m")) tau = 10.0 * tau.get<double>();
  const fs::path strong_model = dir / "device_strong_motors.json";
  std::ofstream(strong_model) << model.dump(1);
  const nlohmann::json scene = read_json_file(file);
  const struct {
    const char* name;
    nlohmann::json patch;
  } variants[] = {{"saturation_passive", {{"method", {{"saturation_passive", true}}}}},
                  {"strong_motors", {{"device", {{"model_file", strong_model.string()}}}}}};
  for (const auto& v : variants) {
    nlohmann::json s = scene;
    s.merge_patch(v.patch);
    const fs::path f = dir / (std::string(v.name) + ".json");
    std::ofstream(f) << s.dump(1);
    const auto r =
        run_dentsim("run " + f.string() + " --pipeline reference --out " + (dir / v.name).string());
    EXPECT_EQ(r.status, 0) << v.name << "\n" << r.output;
    const nlohmann::json k = read_json_file(dir / v.name / "report.json");
    EXPECT_TRUE(k.at("faults").empty()) << v.name << ": " << k.at("faults");
    EXPECT_EQ(k.at("ticks").get<long>(), 2000) << v.name;
    EXPECT_LE(k.at("max_contact_force_n").get<double>(), 0.5 * kForceBoundN) << v.name;
    EXPECT_LT(k.at("max_contact_force_n").get<double>(), 0.5 * as_drawn_peak_n) << v.name;
  }
}

// A scene that cannot be stable (explicit Euler at 100 Hz without damping) is refused before the
// run, naming the field and the bound; `--force` runs it, and the supervisor ends it in a named
// fault: zero torque, the report written with finite figures, exit status 1, one line.
TEST(SupervisorCli, UnstableSceneIsRefusedAndForcedItEndsInANamedFault) {
  const std::string scene = kData + "harsh32_explicit_100hz.json";
  const fs::path out = fresh_temp_dir("dentsim_sup_explicit");
  const auto refused = run_dentsim("run " + scene + " --out " + out.string());
  EXPECT_EQ(refused.status, 2) << refused.output;
  EXPECT_NE(refused.output.find("method.k_vc_n_per_m"), std::string::npos) << refused.output;
  EXPECT_NE(refused.output.find("K T < b"), std::string::npos) << refused.output;
  EXPECT_NE(refused.output.find("--force"), std::string::npos) << refused.output;
  EXPECT_FALSE(fs::exists(out / "report.json"));

  const auto forced = run_dentsim("run " + scene + " --force --out " + out.string());
  EXPECT_EQ(forced.status, 1) << forced.output;
  const nlohmann::json j = read_json_file(out / "report.json");
  ASSERT_EQ(j.at("faults").size(), 1u) << forced.output;
  const std::string fault = j.at("faults")[0].get<std::string>();
  EXPECT_TRUE(is_supervisor_fault(fault)) << fault;
  EXPECT_EQ(j.at("torque_after_fault_n_m").get<double>(), 0.0);
  EXPECT_LE(j.at("max_contact_force_n").get<double>(), kForceBoundN);
  expect_no_null(j, "report");
  EXPECT_TRUE(fs::exists(out / "timeseries.csv"));
  // The error is one line naming the fault.
  std::istringstream lines(forced.output);
  int error_lines = 0;
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("dentsim: failed:", 0) == 0) {
      ++error_lines;
      EXPECT_NE(line.find(fault.substr(0, fault.find(' '))), std::string::npos) << line;
    }
  }
  EXPECT_EQ(error_lines, 1) << forced.output;
}

// The built-in scenes pass the load-time check (run with --duration to keep it short: the whole
// scene is checked either way) and the supervisor stays quiet on them.
TEST(SupervisorCli, BuiltinScenesLoadAndRunWithoutAFault) {
  for (const char* scene : {"probe", "probe-groove", "drill"}) {
    const fs::path out = fresh_temp_dir(std::string("dentsim_sup_builtin_") + scene);
    const auto r = run_dentsim(std::string("run ") + scene + " --duration 2 --out " + out.string());
    EXPECT_EQ(r.status, 0) << r.output;
    const nlohmann::json j = read_json_file(out / "report.json");
    EXPECT_TRUE(j.at("faults").empty()) << scene;
    EXPECT_LE(j.at("virtual_contact_work_j").get<double>(), 0.05) << scene;
    expect_no_null(j, scene);
  }
}

}  // namespace
