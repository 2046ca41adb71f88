// `dentsim device probe` (cli/cmd_device.cc) with and without a device: through the project's
// emulator of the HDAPI library it prints what the device reports and live readings; without a
// library it fails with exit 1 and says where it looked and the usual causes.
#include <gtest/gtest.h>
#include <stdlib.h>

#include "tests/support/cli.h"

namespace dentsim {
namespace {

using testing::run_dentsim;

TEST(DeviceProbe, ThroughTheEmulatorPrintsTheDevice) {
  const auto r = run_dentsim(std::string("device probe --hd-library ") + DENTSIM_HD_EMULATOR +
                             " --readings 2");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("model: PHANTOM Premium 1.5 6DOF (dentsim emulator)"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("serial: EMU-00001"), std::string::npos);
  EXPECT_NE(r.output.find("DoF: 6 input, 6 output"), std::string::npos);
  EXPECT_NE(r.output.find("nominal max force: 8.5 N"), std::string::npos);
  EXPECT_NE(r.output.find("nominal gimbal continuous torque: 188 188 48 mN m"), std::string::npos);
  EXPECT_NE(r.output.find("torque limits used [N m]: 0.4 0.35 0.2 0.188 0.188 0.048"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("  t = "), std::string::npos);
  EXPECT_NE(r.output.find("ok: device started"), std::string::npos);
}

TEST(DeviceProbe, InitFailureNamesTheHdErrorAndCauses) {
  ::setenv("DENTSIM_HD_EMU_INIT_FAIL", "0x0302", 1);
  const auto r = run_dentsim(std::string("device probe --hd-library ") + DENTSIM_HD_EMULATOR);
  ::unsetenv("DENTSIM_HD_EMU_INIT_FAIL");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("hdInitDevice"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("failed: hd_comm_error (0x0302)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("communication with the device failed"), std::string::npos);
}

TEST(DeviceProbe, WithoutTheOverrideTriesTheUsualSonames) {
  // The library from DENTSIM_HD_LIBRARY when set ...
  ::setenv("DENTSIM_HD_LIBRARY", DENTSIM_HD_EMULATOR, 1);
  const auto env = run_dentsim("device probe --readings 1");
  EXPECT_EQ(env.status, 0) << env.output;
  EXPECT_NE(env.output.find(std::string("library: ") + DENTSIM_HD_EMULATOR), std::string::npos);
  // ... else the sonames (this machine has no OpenHaptics install).
  ::unsetenv("DENTSIM_HD_LIBRARY");
  const auto r = run_dentsim("device probe");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("tried the usual sonames"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("\n  libHD.so: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("\n  libHD.so.3.0: "), std::string::npos) << r.output;
}

TEST(DeviceProbe, WithoutALibrarySaysWhereItLooked) {
  const auto r = run_dentsim("device probe --hd-library /nonexistent/libHD.so");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("OpenHaptics library (HDAPI) not found; tried --hd-library"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("/nonexistent/libHD.so: "), std::string::npos);
  EXPECT_NE(r.output.find("install OpenHaptics"), std::string::npos);
}

}  // namespace
}  // namespace dentsim
