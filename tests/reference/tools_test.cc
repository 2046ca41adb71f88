// Tests for reference/tools.h: the tool presets of the desired locked dynamics (thesis §3.1.2).
#include "reference/tools.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <string>

#include "reference/core/io.h"

namespace dentsim {
namespace {

TEST(Tools, PresetNamesAreExplorerScalerHandpiece) {
  const std::vector<std::string> expected = {"explorer", "scaler", "handpiece"};
  EXPECT_EQ(tool_preset_names(), expected);
}

TEST(Tools, PresetsAreSpdWithPsdDampingAndMeetTheInertiaFloor) {
  const Mat6 floor = tool_inertia_floor();
  for (const std::string& name : tool_preset_names()) {
    const ToolDynamics t = tool_preset(name);
    EXPECT_EQ(t.name, name);
    EXPECT_EQ((t.M_d - t.M_d.transpose()).norm(), 0.0) << name;
    EXPECT_EQ(Eigen::LLT<Mat6>(t.M_d).info(), Eigen::Success) << name;
    const Eigen::SelfAdjointEigenSolver<Mat6> es(t.D_d);
    EXPECT_GT(es.eigenvalues().minCoeff(), 0.0) << name;  // small but strictly dissipative
    EXPECT_TRUE(meets_inertia_floor(t, floor)) << name;
    // M_d = floor + instrument: the translational excess is the instrument mass exactly.
    const ToolInstrument inst = tool_instrument(name);
    EXPECT_NEAR(t.M_d(0, 0) - floor(0, 0), inst.mass, 1e-15) << name;
    EXPECT_NEAR(t.M_d(5, 5) - floor(5, 5), inst.inertia(), 1e-15) << name;
    std::printf(
        "%-9s M_d = diag(%.3f kg, %.3g kg m^2)  D_d = diag(%.2f N s/m, %.1e N m s/rad)"
        "  time constants %.2f s, %.2f s\n",
        name.c_str(), t.M_d(0, 0), t.M_d(3, 3), t.D_d(0, 0), t.D_d(3, 3), t.M_d(0, 0) / t.D_d(0, 0),
        t.M_d(3, 3) / t.D_d(3, 3));
  }
}

TEST(Tools, InstrumentMassesAreThoseOfRealInstruments) {
  // Ranges quoted in tools.h: hand instruments 10-20 g, high-speed handpiece 50-80 g.
  EXPECT_GE(tool_instrument("explorer").mass, 0.010);
  EXPECT_LE(tool_instrument("explorer").mass, 0.015);
  EXPECT_GE(tool_instrument("scaler").mass, 0.010);
  EXPECT_LE(tool_instrument("scaler").mass, 0.020);
  EXPECT_GE(tool_instrument("handpiece").mass, 0.050);
  EXPECT_LE(tool_instrument("handpiece").mass, 0.080);
}

TEST(Tools, HandpieceIsHeavierThanScalerHeavierThanExplorer) {
  const ToolDynamics e = tool_preset("explorer"), s = tool_preset("scaler"),
                     h = tool_preset("handpiece");
  for (int i = 0; i < 6; ++i) {
    EXPECT_GT(h.M_d(i, i), s.M_d(i, i)) << i;
    EXPECT_GT(s.M_d(i, i), e.M_d(i, i)) << i;
    EXPECT_GT(h.D_d(i, i), s.D_d(i, i)) << i;  // and more resistant (thesis §3.1.2)
  }
}

TEST(Tools, PresetOnACalibratedFloorMeetsIt) {
  // A coupled, anisotropic locked inertia M_L (e.g. from a calibrated device): the preset built
  // on it meets it, the nominal one need not, and a lighter M_d fails the check.
  Mat6 M_L =
      block_diag(Vec3(0.21, 0.25, 0.23).asDiagonal(), Vec3(1.5e-4, 1.1e-4, 1.3e-4).asDiagonal());
  M_L(0, 4) = M_L(4, 0) = 1e-3;
  const ToolDynamics t = tool_preset("scaler", M_L);
  EXPECT_TRUE(meets_inertia_floor(t, M_L));
  EXPECT_NEAR(t.M_d(1, 1), 0.25 + 0.015, 1e-15);
  EXPECT_FALSE(meets_inertia_floor(tool_preset("scaler"), M_L));  // nominal floor 0.19 kg
  ToolDynamics light = t;
  light.M_d(2, 2) = 0.5 * M_L(2, 2);
  EXPECT_FALSE(meets_inertia_floor(light, M_L));
  Mat6 bad = M_L;
  bad(3, 3) = -1.0;
  EXPECT_THROW(tool_preset("scaler", bad), std::invalid_argument);
}

TEST(Tools, UnknownNameThrowsInputErrorNamingIt) {
  try {
    tool_preset("drill");
    FAIL() << "no exception";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("'drill'"), std::string::npos) << msg;
    EXPECT_NE(msg.find("explorer, scaler, handpiece"), std::string::npos) << msg;
  }
  EXPECT_THROW(tool_preset(""), InputError);
  EXPECT_THROW(tool_preset("Scaler"), InputError);  // names are case-sensitive
  EXPECT_THROW(tool_instrument("probe"), InputError);
}

}  // namespace
}  // namespace dentsim
