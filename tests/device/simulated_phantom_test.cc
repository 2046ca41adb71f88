// Tests of the simulated device (device/simulated_phantom.h): each non-ideality is switched on
// alone on a small MuJoCo plant (tests/device/test_plants.h) and its effect is checked against a
// closed form or an exact physical property.
#include "device/simulated_phantom.h"

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <new>
#include <numbers>
#include <set>
#include <vector>

#include "reference/core/io.h"
#include "reference/core/so3.h"
#include "tests/device/test_plants.h"
#include "tests/support/alloc_counter.h"

namespace dentsim {
namespace {

using testing::arm_plant;
using testing::arm_q0;
using testing::kWheelInertia;
using testing::wheel_plant;

// An ideal wheel device: no quantisation, no saturation, no damping, no jitter.
SimulatedDeviceConfig ideal_config() {
  SimulatedDeviceConfig c;
  c.quantize = false;
  c.saturate = false;
  c.damping_on = false;
  c.friction_on = false;
  c.tau_max = VecX::Constant(1, 1.0);
  c.tau_fault = VecX::Constant(1, 10.0);
  return c;
}

TEST(SimulatedPhantom, EncoderQuantumIsTwoPiOverFourTimes1024TimesRatio) {
  const VecX d = encoder_quantum(1024, 4, phantom_drive_ratios());
  for (int i = 0; i < 6; ++i) {
    EXPECT_DOUBLE_EQ(d[i], 2.0 * std::numbers::pi / (4.0 * 1024.0 * phantom_drive_ratios()[i]));
  }
  // docs/device_facts.md §3: "about 1.4e-4 rad per count" for the arm joints.
  EXPECT_NEAR(d[1], 1.37e-4, 0.01e-4);
  std::printf("quantum: q1 %.6e  q2,q3 %.6e  gimbal %.6e rad\n", d[0], d[1], d[3]);
}

TEST(SimulatedPhantom, QuantisationStepIsVisibleInQ) {
  SimulatedDeviceConfig c = ideal_config();
  c.quantize = true;
  c.drive_ratio = VecX::Constant(1, 13.3);
  SimulatedPhantom dev(wheel_plant(), c, VecX::Zero(1));
  const double quantum = 2.0 * std::numbers::pi / (4.0 * 1024.0 * 13.3);
  ASSERT_DOUBLE_EQ(dev.quantum()[0], quantum);
  DeviceSample s = dev.make_sample();
  const VecX tau = VecX::Constant(1, 1e-4);  // 0.5 rad/s^2: slower than one quantum per tick
  std::set<long> counts;
  double q_prev = 0.0;
  int steps = 0;
  for (int k = 0; k < 200; ++k) {
    dev.write(tau);
    dev.advance();
    dev.read(s);
    const double c_real = s.q[0] / quantum;
    EXPECT_NEAR(c_real, std::round(c_real), 1e-9) << "q is not a whole number of quanta";
    EXPECT_LE(s.q[0], dev.true_q()[0]);
    EXPECT_LT(dev.true_q()[0] - s.q[0], quantum);
    if (s.q[0] != q_prev) {
      EXPECT_NEAR(s.q[0] - q_prev, quantum, 1e-15) << "tick " << k;
      ++steps;
    }
    q_prev = s.q[0];
    counts.insert(std::lround(c_real));
  }
  std::printf("quantum %.6e rad, %d single-quantum steps seen, true q %.6e rad\n", quantum, steps,
              dev.true_q()[0]);
  EXPECT_GT(steps, 50);
}

TEST(SimulatedPhantom, SaturationClipsTorqueAtTheLimit) {
  SimulatedDeviceConfig c = ideal_config();
  c.saturate = true;
  c.tau_max = VecX::Constant(1, 0.01);
  c.tau_fault = VecX::Constant(1, 0.1);
  SimulatedPhantom dev(wheel_plant(), c, VecX::Zero(1));
  std::vector<double> applied;
  dev.set_substep_hook(
      [&](double, const mjModel*, const mjData* d) { applied.push_back(d->qfrc_applied[0]); });
  dev.write(VecX::Constant(1, 0.05));
  EXPECT_EQ(dev.applied_torque()[0], 0.01);
  dev.advance();
  for (double a : applied) EXPECT_EQ(a, 0.01);
  // The physics saw the clipped torque: qd = tau_max T / I (RK4 is exact at constant torque).
  EXPECT_NEAR(dev.true_qd()[0], 0.01 * 1e-3 / kWheelInertia, 1e-12);
  dev.write(VecX::Constant(1, -0.05));
  EXPECT_EQ(dev.applied_torque()[0], -0.01);
  dev.write(VecX::Constant(1, 0.004));
  EXPECT_EQ(dev.applied_torque()[0], 0.004);
  EXPECT_EQ(dev.faults(), kFaultNone);
}

TEST(SimulatedPhantom, ZeroOrderHoldKeepsTorqueConstantAcrossSubsteps) {
  SimulatedPhantom dev(wheel_plant(), ideal_config(), VecX::Zero(1));
  std::vector<double> sub_tau;
  dev.set_substep_hook(
      [&](double, const mjModel*, const mjData* d) { sub_tau.push_back(d->qfrc_applied[0]); });
  const double T = 1e-3, I = kWheelInertia;
  double q = 0.0, v = 0.0;          // ZOH closed form
  double q_foh = 0.0, v_foh = 0.0;  // what a first-order hold would give (for contrast)
  double max_err = 0.0, max_foh_gap = 0.0;
  for (int k = 0; k < 50; ++k) {
    const double u = 1e-3 * std::sin(0.3 * k);
    const double u_next = 1e-3 * std::sin(0.3 * (k + 1));
    sub_tau.clear();
    dev.write(VecX::Constant(1, u));
    dev.advance();
    ASSERT_EQ(dev.last_substeps(), 4);
    ASSERT_EQ(sub_tau.size(), 4u);
    for (double a : sub_tau) EXPECT_EQ(a, u) << "tick " << k;
    q += v * T + u * T * T / (2 * I);
    v += u * T / I;
    q_foh += v_foh * T + (2 * u + u_next) * T * T / (6 * I);
    v_foh += (u + u_next) * T / (2 * I);
    max_err = std::max(max_err, std::abs(dev.true_q()[0] - q));
    max_foh_gap = std::max(max_foh_gap, std::abs(q_foh - q));
  }
  std::printf("ZOH: max |q - q_closed_form| = %.3e rad; FOH would differ by %.3e rad\n", max_err,
              max_foh_gap);
  EXPECT_LT(max_err, 1e-12);
  EXPECT_GT(max_foh_gap, 1e3 * 1e-12);  // the check can tell ZOH from FOH
}

struct JitterRun {
  std::vector<double> T;
  bool consistent = true;
};

JitterRun run_jitter(const TickJitter& j, int ticks) {
  SimulatedDeviceConfig c = ideal_config();
  c.jitter = j;
  SimulatedPhantom dev(wheel_plant(), c, VecX::Zero(1));
  DeviceSample s = dev.make_sample();
  JitterRun r;
  double t_prev = 0.0, t_sum = 0.0;
  for (int k = 0; k < ticks; ++k) {
    dev.write(VecX::Zero(1));
    dev.advance();
    dev.read(s);
    const double T = dev.last_tick();
    r.T.push_back(T);
    t_sum += T;
    const int n_expected = static_cast<int>(std::ceil(T / c.max_substep - 1e-9));
    if (std::abs((s.t - t_prev) - T) > 1e-12 * (1.0 + s.t) || dev.last_substeps() != n_expected ||
        std::abs(dev.physics_time() - t_sum) > 1e-9) {
      r.consistent = false;
    }
    t_prev = s.t;
  }
  return r;
}

void stats(const std::vector<double>& x, double& mean, double& var) {
  mean = 0.0;
  for (double v : x) mean += v;
  mean /= x.size();
  var = 0.0;
  for (double v : x) var += (v - mean) * (v - mean);
  var /= (x.size() - 1);
}

TEST(SimulatedPhantom, UniformJitterMatchesItsDistribution) {
  TickJitter j;
  j.kind = TickJitterKind::kUniform;
  j.period = 1e-3;
  j.half_width = 3e-4;
  j.seed = 20261121;
  std::printf("seed %llu\n", static_cast<unsigned long long>(j.seed));
  const int N = 20000;
  const JitterRun r = run_jitter(j, N);
  EXPECT_TRUE(r.consistent) << "sample times / substeps / physics time disagree with T_k";
  double mean, var;
  stats(r.T, mean, var);
  const double var_expected = j.half_width * j.half_width / 3.0;
  std::printf("uniform: mean %.6e (expect %.6e), var %.6e (expect %.6e)\n", mean, j.period, var,
              var_expected);
  EXPECT_NEAR(mean, j.period, 5.0 * std::sqrt(var_expected / N));
  EXPECT_NEAR(var / var_expected, 1.0, 0.03);
  const auto [mn, mx] = std::minmax_element(r.T.begin(), r.T.end());
  EXPECT_GE(*mn, j.period - j.half_width);
  EXPECT_LE(*mx, j.period + j.half_width);
  EXPECT_LT(*mn, j.period - 0.99 * j.half_width);
  EXPECT_GT(*mx, j.period + 0.99 * j.half_width);
}

TEST(SimulatedPhantom, NormalJitterMatchesItsDistribution) {
  TickJitter j;
  j.kind = TickJitterKind::kNormal;
  j.period = 1e-3;
  j.sigma = 1e-4;
  j.seed = 7;
  std::printf("seed %llu\n", static_cast<unsigned long long>(j.seed));
  const int N = 20000;
  const JitterRun r = run_jitter(j, N);
  EXPECT_TRUE(r.consistent);
  double mean, var;
  stats(r.T, mean, var);
  int within = 0;
  for (double T : r.T) within += std::abs(T - j.period) <= j.sigma;
  const double frac = static_cast<double>(within) / N;
  std::printf(
      "normal: mean %.6e, std %.6e (expect %.1e), P(|T-mean|<=sigma) %.4f (expect 0.6827)\n", mean,
      std::sqrt(var), j.sigma, frac);
  EXPECT_NEAR(mean, j.period, 5.0 * j.sigma / std::sqrt(N));
  EXPECT_NEAR(std::sqrt(var) / j.sigma, 1.0, 0.03);
  EXPECT_NEAR(frac, 0.6827, 0.012);
}

TEST(SimulatedPhantom, TraceJitterReplaysTheTrace) {
  TickJitter j;
  j.kind = TickJitterKind::kTrace;
  j.trace = {1e-3, 0.5e-3, 1.5e-3, 0.9e-3};
  const JitterRun r = run_jitter(j, 10);
  EXPECT_TRUE(r.consistent);
  for (int k = 0; k < 10; ++k) EXPECT_EQ(r.T[k], j.trace[k % 4]);
}

TEST(SimulatedPhantom, VelocityErrorIsBoundedByQuantumOverT) {
  SimulatedDeviceConfig c = ideal_config();
  c.quantize = true;
  c.drive_ratio = VecX::Constant(1, 11.2);
  c.velocity.filter = VelocityFilter::kBackwardDifference;
  c.jitter.kind = TickJitterKind::kUniform;
  c.jitter.half_width = 2e-4;
  c.jitter.seed = 3;
  SimulatedPhantom dev(wheel_plant(), c, VecX::Zero(1));
  DeviceSample s = dev.make_sample();
  const double quantum = dev.quantum()[0];
  double worst = 0.0;  // max of |error| / (quantum / T_k)
  for (int k = 0; k < 2000; ++k) {
    const double q_before = dev.true_q()[0];
    dev.write(VecX::Constant(1, 2e-4 * std::cos(0.01 * k)));
    dev.advance();
    dev.read(s);
    const double T = dev.last_tick();
    const double v_mean = (dev.true_q()[0] - q_before) / T;  // true mean velocity over the tick
    worst = std::max(worst, std::abs(s.qd[0] - v_mean) / (quantum / T));
  }
  std::printf("velocity: max |qd_est - v_mean| = %.4f quantum/T_k\n", worst);
  EXPECT_LT(worst, 1.0);
  EXPECT_GT(worst, 0.5);  // the bound is reached, not trivially loose
}

TEST(SimulatedPhantom, FreeDeviceWithoutGravityAndTorqueStaysStill) {
  SimulatedDeviceConfig c;  // everything on: quantisation, damping, friction, velocity filter
  c.gravity = false;
  c.frictionloss = VecX::Constant(6, 0.01);
  c.jitter.kind = TickJitterKind::kUniform;
  c.jitter.half_width = 2e-4;
  SimulatedPhantom dev(arm_plant(), c, arm_q0());
  DeviceSample s0 = dev.make_sample(), s = dev.make_sample();
  dev.read(s0);
  double max_dq_true = 0.0;
  for (int k = 0; k < 2000; ++k) {
    dev.write(VecX::Zero(6));
    dev.advance();
    dev.read(s);
    ASSERT_EQ(s.q, s0.q) << "tick " << k;
    ASSERT_EQ(s.qd, VecX::Zero(6)) << "tick " << k;
    max_dq_true = std::max(max_dq_true, (dev.true_q() - arm_q0()).cwiseAbs().maxCoeff());
  }
  EXPECT_LE(max_dq_true, 1e-15);
  EXPECT_EQ(dev.faults(), kFaultNone);
}

std::vector<double> released_energy(bool damping_on, bool friction_on, int ticks) {
  SimulatedDeviceConfig c;
  c.damping_on = damping_on;
  c.friction_on = friction_on;
  c.frictionloss = VecX::Constant(6, 1e-3);
  c.max_joint_step = 1.0;
  SimulatedPhantom dev(arm_plant(), c, arm_q0());
  std::vector<double> E{dev.energy()};
  for (int k = 0; k < ticks; ++k) {
    dev.write(VecX::Zero(6));
    dev.advance();
    E.push_back(dev.energy());
  }
  EXPECT_EQ(dev.faults(), kFaultNone) << fault_string(dev.faults());
  return E;
}

TEST(SimulatedPhantom, ReleasedDeviceWithDampingLosesEnergyMonotonically) {
  for (bool friction : {false, true}) {
    const std::vector<double> E = released_energy(true, friction, 3000);
    double worst_rise = -1e300;
    for (std::size_t k = 1; k < E.size(); ++k) worst_rise = std::max(worst_rise, E[k] - E[k - 1]);
    std::printf(
        "damping on, friction %s: E0 %.6f J, E_end %.6f J, largest tick-to-tick change "
        "%.3e J\n",
        friction ? "on" : "off", E.front(), E.back(), worst_rise);
    EXPECT_LE(worst_rise, 0.0);
    EXPECT_LT(E.back(), E.front() - 0.01);
  }
  // Contrast: without damping and friction the same integrator conserves energy closely, so the
  // loss above is the damping's.
  const std::vector<double> E = released_energy(false, false, 3000);
  double drift = 0.0;
  for (double e : E) drift = std::max(drift, std::abs(e - E.front()));
  std::printf("no damping: max |E - E0| = %.3e J\n", drift);
  EXPECT_LT(drift, 1e-6);
}

TEST(SimulatedPhantom, HandMassJoinsTheTipBody) {
  // Wheel + a hand of mass m_h at radius r and inertia J_h, no spring or damper: one tick of
  // torque u from rest gives qd = u T / (I + m_h r^2 + J_h) exactly (RK4, constant torque).
  HandImpedance z;
  z.k_lin = z.b_lin = z.k_ang = z.b_ang = 0.0;
  z.mass = 0.2;
  z.inertia = 1e-4;
  SimulatedPhantom dev(wheel_plant(), ideal_config(), VecX::Zero(1));
  const ScriptedHand hand = ScriptedHand::holding(z, dev.tip_pose());
  dev.set_hand(&hand);
  const double u = 1e-3, T = 1e-3, r = 0.05;
  dev.write(VecX::Constant(1, u));
  dev.advance();
  EXPECT_NEAR(dev.true_qd()[0], u * T / (kWheelInertia + z.mass * r * r + z.inertia), 1e-12);
  // The hand-tool contact torque is the hand's inertial reaction -(m_h r^2 + J_h) qdd.
  const double qdd = u / (kWheelInertia + z.mass * r * r + z.inertia);
  std::printf("contact torque %.9e, expected %.9e N m\n", dev.hand_joint_torque()[0],
              -(z.mass * r * r + z.inertia) * qdd);
  EXPECT_NEAR(dev.hand_joint_torque()[0], -(z.mass * r * r + z.inertia) * qdd, 1e-9);
  // Released: back to the bare wheel.
  SimulatedPhantom bare(wheel_plant(), ideal_config(), VecX::Zero(1));
  bare.set_hand(&hand);
  bare.set_hand(nullptr);
  bare.write(VecX::Constant(1, u));
  bare.advance();
  EXPECT_NEAR(bare.true_qd()[0], u * T / kWheelInertia, 1e-12);
}

TEST(SimulatedPhantom, HandSpringForceIsKTimesOffsetAtRest) {
  SimulatedDeviceConfig c;
  c.gravity = false;
  c.friction_on = false;  // stiction would hold the device away from the force balance
  c.quantize = false;
  SimulatedPhantom dev(arm_plant(), c, arm_q0());
  const Pose p0 = dev.tip_pose();
  HandImpedance z;  // literature defaults
  HandKeyframe k;
  k.x_ref = p0.x + Vec3(0.004, -0.003, 0.005);
  const Mat3 R_ref = p0.R * exp_so3(Vec3(0.01, -0.02, 0.015));
  const ScriptedHand hand(z, {k}, R_ref);
  dev.set_hand(&hand);
  VecX tau_c(6);
  tau_c << 0.01, -0.02, 0.01, 0.002, -0.001, 0.0005;
  for (int i = 0; i < 6000; ++i) {
    dev.write(tau_c);
    dev.advance();
  }
  const Pose p = dev.tip_pose();
  const Vec6 V = dev.tip_twist();
  const Vec6 F = dev.hand_wrench();
  const Vec3 f_spring = z.k_lin * (k.x_ref - p.x);
  const Vec3 tau_spring = z.k_ang * so3_spring_vector(p.R.transpose() * R_ref);
  std::printf("at rest: |V| %.2e, f %.6f %.6f %.6f N, K(x_ref - x) %.6f %.6f %.6f N\n", V.norm(),
              F[0], F[1], F[2], f_spring[0], f_spring[1], f_spring[2]);
  EXPECT_LT(V.norm(), 1e-7);
  EXPECT_LT((F.head<3>() - f_spring).norm(), 1e-6 + z.b_lin * V.head<3>().norm());
  EXPECT_LT((F.tail<3>() - tau_spring).norm(), 1e-8 + z.b_ang * V.tail<3>().norm());
  EXPECT_GT(f_spring.norm(), 0.05);  // a real force, not a trivial zero
  // Physics: at rest the hand's joint torques balance the motor torques.
  const VecX residual = dev.hand_joint_torque() + tau_c;
  std::printf("at rest: |tau_hand + tau_motor| = %.3e N m\n", residual.norm());
  EXPECT_LT(residual.norm(), 1e-6);
}

TEST(SimulatedPhantom, NonFiniteTorqueLatchesSafeStop) {
  SimulatedPhantom dev(wheel_plant(), ideal_config(), VecX::Zero(1));
  dev.write(VecX::Constant(1, std::nan("")));
  EXPECT_EQ(dev.faults(), kFaultNonFiniteTorque);
  EXPECT_EQ(fault_string(dev.faults()), "non_finite_torque");
  EXPECT_EQ(dev.applied_torque()[0], 0.0);
  for (int k = 0; k < 100; ++k) {
    dev.write(VecX::Constant(1, 1e-3));  // a valid command does not clear the latch
    EXPECT_EQ(dev.applied_torque()[0], 0.0);
    dev.advance();
  }
  EXPECT_EQ(dev.true_qd()[0], 0.0);
  EXPECT_EQ(dev.true_q()[0], 0.0);
  dev.clear_faults();
  dev.write(VecX::Constant(1, 1e-3));
  EXPECT_EQ(dev.applied_torque()[0], 1e-3);
}

TEST(SimulatedPhantom, TorqueBeyondFaultLimitLatchesSafeStop) {
  SimulatedDeviceConfig c = ideal_config();
  c.saturate = true;
  c.tau_max = VecX::Constant(1, 0.01);
  c.tau_fault = VecX::Constant(1, 0.04);
  SimulatedPhantom dev(wheel_plant(), c, VecX::Zero(1));
  dev.write(VecX::Constant(1, 0.039));
  EXPECT_EQ(dev.faults(), kFaultNone);
  EXPECT_EQ(dev.applied_torque()[0], 0.01);
  dev.write(VecX::Constant(1, -0.041));
  EXPECT_EQ(dev.faults(), kFaultTorqueBeyondLimit);
  EXPECT_EQ(dev.applied_torque()[0], 0.0);
}

TEST(SimulatedPhantom, NonMonotonicTimeLatchesSafeStop) {
  SimulatedDeviceConfig c = ideal_config();
  c.jitter.kind = TickJitterKind::kTrace;
  c.jitter.trace = {1e-3, 1e-3, 0.0, -0.5e-3, 1e-3};
  SimulatedPhantom dev(wheel_plant(), c, VecX::Zero(1));
  DeviceSample s = dev.make_sample();
  const VecX u = VecX::Constant(1, 1e-3);
  dev.write(u);
  dev.advance();
  dev.write(u);
  dev.advance();
  EXPECT_EQ(dev.faults(), kFaultNone);
  const double t_phys = dev.physics_time();
  dev.write(u);
  dev.advance();  // T = 0: the clock does not advance
  dev.read(s);
  EXPECT_EQ(dev.faults(), kFaultNonMonotonicTime);
  EXPECT_EQ(dev.physics_time(), t_phys);
  EXPECT_DOUBLE_EQ(s.t, 2e-3);
  dev.write(u);
  EXPECT_EQ(dev.applied_torque()[0], 0.0);
  dev.advance();  // T < 0: the clock goes back
  dev.read(s);
  EXPECT_DOUBLE_EQ(s.t, 1.5e-3);
  EXPECT_EQ(dev.physics_time(), t_phys);
}

TEST(SimulatedPhantom, EncoderJumpLatchesSafeStop) {
  SimulatedDeviceConfig c = ideal_config();
  c.max_joint_step = 1e-3;  // rad per tick = 1 rad/s
  SimulatedPhantom dev(wheel_plant(), c, VecX::Zero(1));
  int k = 0;
  while (dev.faults() == kFaultNone && k < 1000) {
    dev.write(VecX::Constant(1, 0.01));  // 50 rad/s^2: passes 1 rad/s after 20 ms
    dev.advance();
    ++k;
  }
  EXPECT_EQ(dev.faults(), kFaultEncoderJump);
  EXPECT_GT(dev.true_qd()[0], 1.0);
  EXPECT_LT(dev.true_qd()[0], 1.1);
  EXPECT_EQ(dev.applied_torque()[0], 0.0);
  std::printf("encoder jump latched at tick %d, qd %.4f rad/s\n", k, dev.true_qd()[0]);
}

TEST(SimulatedPhantom, TickDoesNotAllocate) {
  SimulatedDeviceConfig c;
  c.jitter.kind = TickJitterKind::kNormal;
  c.jitter.sigma = 5e-5;
  SimulatedPhantom dev(arm_plant(), c, arm_q0());
  HandKeyframe a, b;
  a.x_ref = dev.tip_pose().x;
  b.t = 0.5;
  b.x_ref = a.x_ref + Vec3(0.01, 0.0, 0.0);
  const ScriptedHand hand(HandImpedance{}, {a, b}, dev.tip_pose().R);
  dev.set_hand(&hand);
  DeviceSample s = dev.make_sample();
  VecX tau = VecX::Zero(6);
  for (int k = 0; k < 10; ++k) {
    dev.read(s);
    dev.write(tau);
    dev.advance();
  }
  long allocs = 0;
  {
    dentsim::testing::AllocationScope scope;
    for (int k = 0; k < 1000; ++k) {
      dev.read(s);
      tau = -0.01 * s.qd;
      dev.write(tau);
      dev.advance();
    }
    allocs = scope.count();
  }
  EXPECT_EQ(allocs, 0);
}

TEST(SimulatedPhantom, BadConfigurationThrowsNamingTheField) {
  auto throws_with = [](const SimulatedDeviceConfig& c, const MujocoPlant& p, const char* what) {
    try {
      SimulatedPhantom dev(p, c, VecX::Zero(static_cast<int>(p.device_dof.size())));
      ADD_FAILURE() << "no throw, expected " << what;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  SimulatedDeviceConfig c = ideal_config();
  c.tau_max = VecX::Constant(2, 1.0);
  throws_with(c, wheel_plant(), "tau_max");
  c = ideal_config();
  c.jitter.kind = TickJitterKind::kUniform;
  c.jitter.half_width = 2e-3;
  throws_with(c, wheel_plant(), "half_width");
  c = ideal_config();
  c.max_substep = 0.0;
  throws_with(c, wheel_plant(), "max_substep");
  c = ideal_config();
  c.jitter.kind = TickJitterKind::kTrace;
  throws_with(c, wheel_plant(), "trace");
  MujocoPlant p = wheel_plant();
  p.tip_body = "nope";
  throws_with(ideal_config(), p, "tip_body 'nope'");
  p = wheel_plant();
  p.G = MatX::Identity(2, 1);
  throws_with(ideal_config(), p, "G is 2x1");
  p = wheel_plant();
  p.mjcf = "<mujoco><worldbody><body></mujoco>";
  throws_with(ideal_config(), p, "does not compile");
  SimulatedPhantom dev(wheel_plant(), ideal_config(), VecX::Zero(1));
  EXPECT_THROW(dev.write(VecX::Zero(2)), InputError);
}

}  // namespace
}  // namespace dentsim
