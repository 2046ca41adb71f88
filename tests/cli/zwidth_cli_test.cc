// `dentsim zwidth` end to end on the 1-DoF axis testbed (fast): the JSON contract of issue #7 and
// the flags' error messages.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/support/cli.h"

namespace dentsim {
namespace {

namespace fs = std::filesystem;
using testing::run_dentsim;

TEST(ZwidthCli, JsonCarriesTheContractKeys) {
  const fs::path dir = fs::temp_directory_path() / "dentsim_zwidth_cli_test";
  fs::create_directories(dir);
  const fs::path json = dir / "z.json";
  fs::remove(json);
  const auto r = run_dentsim("zwidth --testbed axis --operators force --k-vc 3200 --b-vc 2 "
                             "--k-tooth 3000 --threads 1 --json " + json.string());
  ASSERT_EQ(r.status, 0) << r.output;
  std::ifstream in(json);
  const nlohmann::json j = nlohmann::json::parse(in);
  for (const char* m : {"explicit", "pmi", "pmi-pd"}) {
    ASSERT_TRUE(j["methods"].contains(m)) << m;
    const auto& mj = j["methods"][m];
    EXPECT_TRUE(mj["z_width_n_per_m"].is_number()) << m;
    // The gains of the best point, or null when no point is stable and passive (explicit here).
    EXPECT_TRUE(mj["gains"].is_null() || mj["gains"].contains("k_vc_n_per_m")) << m;
    const auto& pts = mj["operators"]["force"]["points"];
    ASSERT_EQ(pts.size(), 1u) << m;
    EXPECT_TRUE(pts[0]["stable"].is_boolean());
    EXPECT_TRUE(pts[0]["passive"].is_boolean());
  }
  EXPECT_TRUE(j.contains("ratio_pmi_over_explicit"));
  EXPECT_TRUE(j.contains("ratio_pmipd_over_explicit"));
  EXPECT_EQ(j["observer_gain_per_s"].get<double>(), 200.0);
  EXPECT_TRUE(j["observer_input_matched"].get<bool>());
  EXPECT_FALSE(j["grip_detector"].get<bool>());
  EXPECT_FALSE(j["encoder_kalman"].get<bool>());  // the method block's switches, off by default
  EXPECT_FALSE(j["lag_compensation"].get<bool>());
  const auto& run0 = j["methods"]["pmi"]["operators"]["force"]["points"][0]["runs"][0];
  EXPECT_EQ(run0["grip_switches"].get<int>(), 0);
  EXPECT_EQ(run0["release_detected_after_s"].get<double>(), -1.0);  // no detector
  EXPECT_EQ(run0["grip_statistic_max_on"].get<double>(), 0.0);
  EXPECT_EQ(j["tap_speeds_m_s"].size(), 3u);
  // At this point (stiff coupling, thesis wall) PMI + PD renders the wall: its Z-width is above
  // the series value PMI can reach, K_vc K_tooth / (K_vc + K_tooth) = 1548 N/m.
  EXPECT_GT(j["methods"]["pmi-pd"]["z_width_n_per_m"].get<double>(), 1548.0);
  EXPECT_EQ(j["methods"]["pmi-pd"]["gains"]["k_tooth_n_per_m"].get<double>(), 3000.0);
  fs::remove_all(dir);
}

// --encoder-kalman / --lag-compensation (issue #29): the method block's switches on every run,
// recorded in the JSON; they change the run (the filter's sub-count estimate feeds the coupling:
// PMI + PD's static stiffness and ripple differ from the same point without them).
TEST(ZwidthCli, RemedySwitchesReachEveryRunAndAreRecorded) {
  const fs::path dir = testing::fresh_temp_dir("dentsim_zwidth_remedies");
  const std::string grid =
      "zwidth --testbed axis --methods pmi-pd --operators force --k-vc 3200 --b-vc 2 "
      "--k-tooth 3000 --threads 1 --json ";
  const auto off = run_dentsim(grid + (dir / "off.json").string());
  ASSERT_EQ(off.status, 0) << off.output;
  const auto on = run_dentsim(grid + (dir / "on.json").string() +
                              " --encoder-kalman --lag-compensation");
  ASSERT_EQ(on.status, 0) << on.output;
  std::ifstream fo(dir / "off.json"), fn(dir / "on.json");
  const nlohmann::json a = nlohmann::json::parse(fo), b = nlohmann::json::parse(fn);
  EXPECT_FALSE(a["encoder_kalman"].get<bool>());
  EXPECT_TRUE(b["encoder_kalman"].get<bool>());
  EXPECT_TRUE(b["lag_compensation"].get<bool>());
  const auto& ra = a["methods"]["pmi-pd"]["operators"]["force"]["points"][0]["runs"][0];
  const auto& rb = b["methods"]["pmi-pd"]["operators"]["force"]["points"][0]["runs"][0];
  EXPECT_NE(ra["ripple_device_force"].get<double>(), rb["ripple_device_force"].get<double>());
  const auto bad = run_dentsim("zwidth --testbed axis --encoder-kalman=maybe");
  EXPECT_EQ(bad.status, 2) << bad.output;
  EXPECT_NE(bad.output.find("--encoder-kalman"), std::string::npos) << bad.output;
  fs::remove_all(dir);
}

TEST(ZwidthCli, BadFlagsExitTwoWithTheFlagNamed) {
  const auto a = run_dentsim("zwidth --testbed axis --grasp-mass -1");
  EXPECT_EQ(a.status, 2);
  EXPECT_NE(a.output.find("--grasp-mass"), std::string::npos) << a.output;
  const auto b = run_dentsim("zwidth --testbed axis --observer-gain 2000");
  EXPECT_EQ(b.status, 2);
  EXPECT_NE(b.output.find("--observer-gain"), std::string::npos) << b.output;
  const auto c = run_dentsim("zwidth --testbed axis --operators push");
  EXPECT_EQ(c.status, 2);
  EXPECT_NE(c.output.find("operator"), std::string::npos) << c.output;
  const auto e = run_dentsim("zwidth --testbed axis --tap-speeds 0.1 0");
  EXPECT_EQ(e.status, 2);
  EXPECT_NE(e.output.find("--tap-speeds"), std::string::npos) << e.output;
  const auto d = run_dentsim("zwidth --testbed axis --grip-detector");
  EXPECT_EQ(d.status, 2);
  EXPECT_NE(d.output.find("--grip-detector"), std::string::npos) << d.output;
}

// --device and --pipeline-model (issue #17: the Z-width with a calibrated model): the default
// model's file reproduces the built-in run exactly; a perturbed device changes what the loop
// sees (its tip damping, the run); the pipeline believing another model changes the run but not
// the device.
TEST(ZwidthCli, ModelFilesSelectTheDeviceAndWhatThePipelineBelieves) {
  const fs::path d = testing::fresh_temp_dir("dentsim_zwidth_models");
  const std::string base = std::string(DENTSIM_SOURCE_DIR) + "/tests/fuzz/corpus/device_model/";
  const std::string def = base + "premium_1_5a.json";       // == `dentsim device show`
  const std::string pert = base + "perturbed_phantom.json";  // masses, damping, friction scaled
  const std::string args =
      "zwidth --push 1.0 --methods pmi-pd --operators force --k-vc 2400 --b-vc 4 --k-tooth 12000 "
      "--threads 1 ";
  const auto run = [&](const std::string& extra, const std::string& name) {
    const auto r = run_dentsim(args + extra + " --json " + (d / name).string());
    EXPECT_EQ(r.status, 0) << r.output;
    return testing::read_json_file(d / name);
  };
  const nlohmann::json builtin = run("", "builtin.json");
  const nlohmann::json files = run("--device " + def + " --pipeline-model " + def, "files.json");
  const nlohmann::json device = run("--device " + pert, "device.json");
  const nlohmann::json belief = run("--pipeline-model " + pert, "belief.json");
  ASSERT_FALSE(HasFailure());
  EXPECT_EQ(builtin, files) << nlohmann::json::diff(builtin, files).dump(1);
  const auto point = [](const nlohmann::json& j) {
    return j["methods"]["pmi-pd"]["operators"]["force"]["points"][0]["runs"][0];
  };
  // The device's own damping is in the perturbed file (the rig reports it at the tip)...
  EXPECT_NE(device["device_tip_damping_n_s_per_m"], builtin["device_tip_damping_n_s_per_m"]);
  EXPECT_NE(point(device)["energy_final_j"], point(builtin)["energy_final_j"]);
  // ... the pipeline's belief is not: same device, another run.
  EXPECT_EQ(belief["device_tip_damping_n_s_per_m"], builtin["device_tip_damping_n_s_per_m"]);
  EXPECT_NE(point(belief)["energy_final_j"], point(builtin)["energy_final_j"]);

  const auto missing = run_dentsim(args + "--device " + (d / "nope.json").string());
  EXPECT_EQ(missing.status, 2);
  EXPECT_NE(missing.output.find("nope.json"), std::string::npos) << missing.output;
  const auto axis = run_dentsim("zwidth --testbed axis --pipeline-model " + def);
  EXPECT_EQ(axis.status, 2);
  EXPECT_NE(axis.output.find("--testbed phantom"), std::string::npos) << axis.output;
  fs::remove_all(d);
}

}  // namespace
}  // namespace dentsim
