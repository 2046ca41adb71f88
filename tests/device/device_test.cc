// The command chain and sample checks shared by every device backend (device/device.h).
#include "device/device.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "reference/core/io.h"

namespace dentsim {
namespace {

DeviceLimits limits3() {
  DeviceLimits l;
  l.tau_max = Eigen::Vector3d(0.4, 0.35, 0.2);
  l.tau_fault = 4.0 * l.tau_max;
  l.max_joint_step = 0.1;
  return l;
}

TEST(DeviceCommand, SaturatesEachJointAtItsLimit) {
  VecX out(3);
  const std::uint32_t f = condition_command(Eigen::Vector3d(1.0, -0.1, -0.7), limits3(), true, out);
  EXPECT_EQ(f, kFaultNone);
  EXPECT_EQ(out[0], 0.4);
  EXPECT_EQ(out[1], -0.1);
  EXPECT_EQ(out[2], -0.2);
}

TEST(DeviceCommand, WithoutSaturationPassesTheCommand) {
  VecX out(3);
  condition_command(Eigen::Vector3d(1.0, -0.1, -0.7), limits3(), false, out);
  EXPECT_EQ(out, Eigen::Vector3d(1.0, -0.1, -0.7));
}

TEST(DeviceCommand, NonFiniteOrBeyondFaultGivesZeroAndNamedFlags) {
  VecX out = VecX::Constant(3, 9.0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(condition_command(Eigen::Vector3d(0.1, nan, 0.0), limits3(), true, out),
            kFaultNonFiniteTorque);
  EXPECT_EQ(out, VecX::Zero(3));
  out.setConstant(9.0);
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(condition_command(Eigen::Vector3d(inf, 0.0, 0.81), limits3(), true, out),
            kFaultNonFiniteTorque | kFaultTorqueBeyondLimit);
  EXPECT_EQ(out, VecX::Zero(3));
  // Exactly at the fault threshold is allowed (and saturated).
  EXPECT_EQ(condition_command(Eigen::Vector3d(1.6, -1.4, 0.8), limits3(), true, out), kFaultNone);
  EXPECT_EQ(out, Eigen::Vector3d(0.4, -0.35, 0.2));
}

TEST(DeviceCommand, SizeMismatchThrows) {
  VecX out(2);
  EXPECT_THROW(condition_command(Eigen::Vector2d(0, 0), limits3(), true, out), InputError);
}

TEST(DeviceSampleCheck, TimeMustIncreaseAndEncodersMustNotJump) {
  const DeviceLimits l = limits3();
  const VecX q0 = Eigen::Vector3d(0.0, 0.1, 0.2);
  EXPECT_EQ(check_sample(q0, 1.0, q0, 1.001, l), kFaultNone);
  EXPECT_EQ(check_sample(q0, 1.0, q0, 1.0, l), kFaultNonMonotonicTime);
  EXPECT_EQ(check_sample(q0, 1.0, q0, 0.999, l), kFaultNonMonotonicTime);
  EXPECT_EQ(check_sample(q0, 1.0, q0, std::nan(""), l), kFaultNonMonotonicTime);
  const VecX q1 = q0 + Eigen::Vector3d(0.0, 0.1, 0.0);  // exactly the limit: allowed
  EXPECT_EQ(check_sample(q0, 1.0, q1, 1.001, l), kFaultNone);
  const VecX q2 = q0 + Eigen::Vector3d(0.0, 0.0, -0.1001);
  EXPECT_EQ(check_sample(q0, 1.0, q2, 1.001, l), kFaultEncoderJump);
  EXPECT_EQ(check_sample(q0, 1.0, q2, 1.0, l), kFaultEncoderJump | kFaultNonMonotonicTime);
  // With the nominal period (the HDAPI backend): a sample 3 periods late may move 3 steps.
  const VecX q3 = q0 + Eigen::Vector3d(0.0, 0.0, -0.25);
  EXPECT_EQ(check_sample(q0, 1.0, q3, 1.003, l, 1e-3), kFaultNone);
  EXPECT_EQ(check_sample(q0, 1.0, q3, 1.002, l, 1e-3), kFaultEncoderJump);
  EXPECT_EQ(check_sample(q0, 1.0, q2, 1.0005, l, 1e-3), kFaultEncoderJump);  // at least 1 period
}

TEST(DeviceFaults, NamesAreStable) {
  EXPECT_EQ(fault_string(kFaultNone), "none");
  EXPECT_EQ(fault_string(kFaultNonFiniteTorque), "non_finite_torque");
  EXPECT_EQ(fault_string(kFaultTorqueBeyondLimit | kFaultEncoderJump),
            "torque_beyond_limit,encoder_jump");
  EXPECT_EQ(fault_string(kFaultNonMonotonicTime), "non_monotonic_time");
  EXPECT_EQ(fault_string(kFaultSustainedSaturation), "sustained_saturation");
  EXPECT_STREQ(fault_name(static_cast<DeviceFault>(kFaultSustainedSaturation | kFaultWatchdog)),
               "unknown");  // one flag at a time
}

}  // namespace
}  // namespace dentsim
