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

}  // namespace
}  // namespace dentsim
