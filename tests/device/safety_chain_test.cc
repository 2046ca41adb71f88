// The safety chain (device/safety_chain.h): one test per fault (the named flag, zero torque on the
// tick it is found and after), the rate limit, saturation and the ramp-in as exact numbers.
#include "device/safety_chain.h"

#include <gtest/gtest.h>

#include <limits>

#include "reference/core/io.h"

namespace dentsim {
namespace {

// Two joints, round numbers so every expected value is exact in binary.
SafetyLimits two_joint_limits() {
  SafetyLimits l;
  l.tau_max = (VecX(2) << 0.5, 0.25).finished();
  l.tau_fault = (VecX(2) << 2.0, 1.0).finished();
  l.tau_rate = (VecX(2) << 256.0, 256.0).finished();  // 0.25 N m per 1/1024 s tick
  l.qd_max = (VecX(2) << 4.0, 4.0).finished();
  l.q_min = (VecX(2) << -1.0, -1.0).finished();
  l.q_max = (VecX(2) << 1.0, 1.0).finished();
  l.watchdog_s = 1.0 / 1024;
  l.ramp_time_s = 0.0;
  l.nominal_period = 1.0 / 1024;
  return l;
}

DeviceSample sample(double t, double q = 0.0, double qd = 0.0) {
  DeviceSample s;
  s.q = VecX::Constant(2, q);
  s.qd = VecX::Constant(2, qd);
  s.t = t;
  return s;
}

constexpr double T = 1.0 / 1024;

// Runs one tick from a started chain with a command that the chain accepts unchanged.
struct Fixture {
  SafetyChain chain{two_joint_limits()};
  VecX out = VecX::Zero(2);
  VecX ok = (VecX(2) << 0.125, -0.125).finished();
  Fixture() {
    chain.start(0.0);
    EXPECT_EQ(chain.apply(sample(0.0), ok, 0.0, nullptr, out), kFaultNone);
    EXPECT_EQ(out, ok);
  }
  // The fault is named, the output is zero on this tick and stays zero until cleared.
  void expect_fault(std::uint32_t got, std::uint32_t flag, const char* name) {
    EXPECT_EQ(got, flag);
    EXPECT_EQ(fault_string(got), name);
    EXPECT_EQ(out, VecX::Zero(2));
    EXPECT_EQ(chain.apply(sample(10 * T), ok, 0.0, nullptr, out), flag);
    EXPECT_EQ(out, VecX::Zero(2));
  }
};

TEST(SafetyChain, NonFiniteTorqueLatchesZero) {
  Fixture f;
  VecX bad = f.ok;
  bad[1] = std::numeric_limits<double>::quiet_NaN();
  f.expect_fault(f.chain.apply(sample(T), bad, 0.0, nullptr, f.out), kFaultNonFiniteTorque,
                 "non_finite_torque");
}

TEST(SafetyChain, TorqueBeyondFaultThresholdLatchesZero) {
  Fixture f;
  const VecX bad = (VecX(2) << 0.0, 1.0 + 1.0 / 64).finished();
  f.expect_fault(f.chain.apply(sample(T), bad, 0.0, nullptr, f.out), kFaultTorqueBeyondLimit,
                 "torque_beyond_limit");
}

TEST(SafetyChain, VelocityGuardLatchesZero) {
  Fixture f;
  f.expect_fault(f.chain.apply(sample(T, 0.0, 4.0 + 1.0 / 64), f.ok, 0.0, nullptr, f.out),
                 kFaultVelocityLimit, "velocity_limit");
}

TEST(SafetyChain, WorkspaceGuardLatchesZero) {
  Fixture f;
  f.expect_fault(f.chain.apply(sample(T, -1.0 - 1.0 / 64), f.ok, 0.0, nullptr, f.out),
                 kFaultWorkspaceLimit, "workspace_limit");
}

TEST(SafetyChain, WatchdogLatchesZero) {
  Fixture f;
  // A tick that took exactly the budget is fine; one beyond it is not.
  EXPECT_EQ(f.chain.apply(sample(T), f.ok, 1.0 / 1024, nullptr, f.out), kFaultNone);
  f.expect_fault(f.chain.apply(sample(2 * T), f.ok, 1.0 / 1024 + 1e-6, nullptr, f.out),
                 kFaultWatchdog, "watchdog");
}

// Joint 2 commanded at its saturation: allowed for max_saturation_s (here 64 ticks), a fault on
// the first tick beyond; an interruption (one tick below the limit) restarts the count.
TEST(SafetyChain, SustainedSaturationLatchesZero) {
  SafetyLimits l = two_joint_limits();
  l.max_saturation_s = 64 * T;
  l.tau_rate.resize(0);  // the command reaches the limit at once
  SafetyChain chain(l);
  chain.start(0.0);
  VecX out = VecX::Zero(2);
  const VecX at_limit = (VecX(2) << 0.125, -0.25).finished();  // joint 2 exactly at tau_max
  const VecX beyond = (VecX(2) << 0.125, 0.75).finished();     // beyond (clipped to 0.25)
  const VecX below = (VecX(2) << 0.125, 0.25 - 1.0 / 1024).finished();
  int k = 0;
  for (; k <= 40; ++k)
    ASSERT_EQ(chain.apply(sample(k * T), at_limit, 0.0, nullptr, out), kFaultNone);
  ASSERT_EQ(chain.apply(sample(k * T), below, 0.0, nullptr, out), kFaultNone);  // count restarts
  ++k;
  const int start = k;
  for (; k <= start + 64; ++k) {
    ASSERT_EQ(chain.apply(sample(k * T), beyond, 0.0, nullptr, out), kFaultNone) << k - start;
    EXPECT_EQ(out[1], 0.25);
  }
  EXPECT_EQ(chain.apply(sample(k * T), beyond, 0.0, nullptr, out), kFaultSustainedSaturation);
  EXPECT_EQ(fault_string(chain.faults()), "sustained_saturation");
  EXPECT_EQ(out, VecX::Zero(2));
  EXPECT_EQ(chain.apply(sample((k + 1) * T), below, 0.0, nullptr, out), kFaultSustainedSaturation);
  EXPECT_EQ(out, VecX::Zero(2));
}

TEST(SafetyChain, WarmMotorLatchesZero) {
  Fixture f;
  const double cool[2] = {0.5, 0.875};
  EXPECT_EQ(f.chain.apply(sample(T), f.ok, 0.0, cool, f.out), kFaultNone);
  const double warm[2] = {0.5, 0.9};  // at the limit counts as warm
  f.expect_fault(f.chain.apply(sample(2 * T), f.ok, 0.0, warm, f.out), kFaultMotorTemperature,
                 "motor_temperature");
}

TEST(SafetyChain, ExternalFaultLatchesZeroAndClearRampsIn) {
  SafetyLimits l = two_joint_limits();
  l.ramp_time_s = 4 * T;
  l.tau_rate.resize(0);
  SafetyChain chain(l);
  VecX out = VecX::Zero(2);
  const VecX cmd = (VecX(2) << 0.5, 0.25).finished();
  chain.start(0.0);
  // Ramp-in after start: r = t / (4 T).
  for (int k = 0; k <= 5; ++k) {
    EXPECT_EQ(chain.apply(sample(k * T), cmd, 0.0, nullptr, out), kFaultNone);
    EXPECT_EQ(out, VecX(std::min(1.0, k / 4.0) * cmd)) << "tick " << k;
  }
  chain.latch(kFaultHdCommError);
  EXPECT_EQ(chain.apply(sample(6 * T), cmd, 0.0, nullptr, out), kFaultHdCommError);
  EXPECT_EQ(fault_string(chain.faults()), "hd_comm_error");
  EXPECT_EQ(out, VecX::Zero(2));
  // Ramp-in again after the fault is cleared.
  chain.clear_faults(8 * T);
  EXPECT_EQ(chain.apply(sample(9 * T), cmd, 0.0, nullptr, out), kFaultNone);
  EXPECT_EQ(out, VecX(0.25 * cmd));
}

// The sample's own guards (issue #18): a clock that does not advance and an encoder that jumps.
TEST(SafetyChain, ClockNotAdvancingLatchesZero) {
  SafetyLimits l = two_joint_limits();
  l.monotonic_time = true;
  SafetyChain chain(l);
  VecX out = VecX::Zero(2);
  const VecX ok = (VecX(2) << 0.125, -0.125).finished();
  chain.start(0.0);
  EXPECT_EQ(chain.apply(sample(0.0), ok, 0.0, nullptr, out), kFaultNone);  // first: no previous
  EXPECT_EQ(chain.apply(sample(T), ok, 0.0, nullptr, out), kFaultNone);
  EXPECT_EQ(chain.apply(sample(T), ok, 0.0, nullptr, out), kFaultNonMonotonicTime);  // repeated
  EXPECT_EQ(fault_string(chain.faults()), "non_monotonic_time");
  EXPECT_EQ(out, VecX::Zero(2));
  chain.start(0.0);
  EXPECT_EQ(chain.apply(sample(2 * T), ok, 0.0, nullptr, out), kFaultNone);
  EXPECT_EQ(chain.apply(sample(T), ok, 0.0, nullptr, out), kFaultNonMonotonicTime);  // backwards
  EXPECT_EQ(out, VecX::Zero(2));
  // Without the guard the same samples pass.
  Fixture f;
  EXPECT_EQ(f.chain.apply(sample(0.0), f.ok, 0.0, nullptr, f.out), kFaultNone);
}

TEST(SafetyChain, EncoderJumpLatchesZero) {
  SafetyLimits l = two_joint_limits();
  l.max_joint_step = 0.125;
  SafetyChain chain(l);
  VecX out = VecX::Zero(2);
  const VecX ok = (VecX(2) << 0.125, -0.125).finished();
  chain.start(0.0);
  EXPECT_EQ(chain.apply(sample(0.0, 0.0), ok, 0.0, nullptr, out), kFaultNone);
  EXPECT_EQ(chain.apply(sample(T, 0.125), ok, 0.0, nullptr, out), kFaultNone);  // at the limit
  // A late sample (the callback ran 3 periods after the last: a loaded machine, issue #33) may
  // have moved by 3 steps.
  EXPECT_EQ(chain.apply(sample(4 * T, 0.5), ok, 0.0, nullptr, out), kFaultNone);
  EXPECT_EQ(chain.apply(sample(5 * T, 0.625 + 1.0 / 64), ok, 0.0, nullptr, out), kFaultEncoderJump);
  EXPECT_EQ(fault_string(chain.faults()), "encoder_jump");
  EXPECT_EQ(out, VecX::Zero(2));
}

TEST(SafetyChain, RateLimitThenSaturation) {
  SafetyChain chain(two_joint_limits());
  VecX out = VecX::Zero(2);
  chain.start(0.0);
  const VecX step = (VecX(2) << 1.5, -0.75).finished();  // below the fault threshold
  // 256 N m/s x T = 0.25 N m per tick from 0, then saturation at (0.5, 0.25).
  EXPECT_EQ(chain.apply(sample(0.0), step, 0.0, nullptr, out), kFaultNone);
  EXPECT_EQ(out, (VecX(2) << 0.25, -0.25).finished());
  EXPECT_EQ(chain.apply(sample(T), step, 0.0, nullptr, out), kFaultNone);
  EXPECT_EQ(out, (VecX(2) << 0.5, -0.25).finished());
  // A longer tick (2T) allows twice the change: from 0.5 down by 0.5 to 0.
  EXPECT_EQ(chain.apply(sample(3 * T), VecX::Zero(2), 0.0, nullptr, out), kFaultNone);
  EXPECT_EQ(out, VecX::Zero(2));
}

TEST(SafetyChain, RejectsInconsistentLimits) {
  SafetyLimits l = two_joint_limits();
  l.qd_max = VecX::Ones(3);
  EXPECT_THROW(SafetyChain{l}, InputError);
  l = two_joint_limits();
  l.q_max.resize(0);
  EXPECT_THROW(SafetyChain{l}, InputError);
}

}  // namespace
}  // namespace dentsim
