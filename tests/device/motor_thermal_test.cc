// The motors' thermal torque limit (device/motor_thermal.h; model-file key "torque_limit"):
// the stepped state against the network's exact solution (computed here from Eigen's eigen
// decomposition, not the model's formula), the single-time-constant law, the time the peak lasts,
// derating and the warm-motor fault, through the simulated Phantom, and the file key.
#include "device/motor_thermal.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <string>

#include "device/phantom_device.h"
#include "reference/core/io.h"
#include "reference/phantom/phantom_params.h"
#include "tests/support/alloc_counter.h"

namespace dentsim {
namespace {

// The winding's rise at time t of joint j's network under constant heat P from ambient:
// x(t) = x_ss - V e^{Lambda t} V^-1 x_ss, A and x_ss written from the equations of the header.
double exact_rise(const MotorThermalParams& p, int j, double P, double t) {
  const double r1 = p.r_winding_housing_k_per_w(j), r2 = p.r_housing_ambient_k_per_w(j);
  const double cw = p.tau_winding_s(j) / r1, ch = p.tau_motor_s(j) / r2;
  Eigen::Matrix2d A;
  A << -1.0 / (cw * r1), 1.0 / (cw * r1), 1.0 / (ch * r1), -(1.0 / r1 + 1.0 / r2) / ch;
  const Eigen::Vector2d b(1.0 / cw, 0.0);
  const Eigen::Vector2d xss = -A.inverse() * b * P;
  Eigen::EigenSolver<Eigen::Matrix2d> es(A);
  const Eigen::Matrix2d V = es.eigenvectors().real();
  const Eigen::Vector2d l = es.eigenvalues().real();
  const Eigen::Matrix2d E =
      V * Eigen::Vector2d(std::exp(l(0) * t), std::exp(l(1) * t)).asDiagonal() * V.inverse();
  return (xss - E * xss)(0);
}

double heat(const MotorThermalParams& p, int j, double tau) {
  const double pc = (p.max_winding_c(j) - p.ambient_c) /
                    (p.r_winding_housing_k_per_w(j) + p.r_housing_ambient_k_per_w(j));
  return pc * (tau / p.continuous_n_m(j)) * (tau / p.continuous_n_m(j));
}

// First time [s] the winding reaches Tmax at constant torque tau (bisection on the exact form).
double time_to_limit(const MotorThermalParams& p, int j, double tau) {
  const double P = heat(p, j, tau), rise = p.max_winding_c(j) - p.ambient_c;
  double lo = 0.0, hi = 1.0;
  while (exact_rise(p, j, P, hi) < rise) hi *= 2.0;
  for (int i = 0; i < 200; ++i) {
    const double m = 0.5 * (lo + hi);
    (exact_rise(p, j, P, m) < rise ? lo : hi) = m;
  }
  return hi;
}

TEST(MotorThermal, StepMatchesTheNetworksExactSolution) {
  const MotorThermalParams p = phantom_thermal_torque_limit();
  MotorThermal m(p);
  VecX tau = 0.5 * VecX(p.peak_n_m);  // below the limit for the 2 s below on every joint
  const double T = 1e-3;
  for (int k = 1; k <= 2000; ++k) {
    m.advance(tau, T);
    if (k % 250 == 0) {
      for (int j = 0; j < 6; ++j) {
        const double want = exact_rise(p, j, heat(p, j, tau(j)), k * T);
        EXPECT_NEAR(m.winding_rise(j), want, 1e-9 * std::max(1.0, want)) << "joint " << j;
        EXPECT_NEAR(m.step_response(j, tau(j), k * T), want, 1e-9 * std::max(1.0, want));
      }
    }
  }
  // q2 at half its peak for 2 s: 29.8 W into 4.03 J/K, ~14.6 K (printed for the record).
  std::printf("[thermal] q2 at %.3f N m for 2 s: winding +%.3f K, housing +%.4f K\n", tau(1),
              m.winding_rise(1), m.housing_rise(1));
  EXPECT_GT(m.winding_rise(1), 10.0);
}

TEST(MotorThermal, AFixedHousingIsTheSingleTimeConstantLaw) {
  // A housing of (almost) infinite capacity stays at ambient: the winding alone,
  // rise(t) = P R_wh (1 - exp(-t / tau_w)).
  MotorThermalParams p = phantom_thermal_torque_limit();
  p.tau_motor_s.setConstant(1e12);
  MotorThermal m(p);
  const double tau2 = 1.0;  // N m on q2
  VecX tau = VecX::Zero(6);
  tau(1) = tau2;
  const double P = heat(p, 1, tau2);
  double t = 0.0;
  for (double stop : {1.0, 5.0, 12.5, 30.0}) {
    while (t < stop - 1e-9) {
      m.advance(tau, 0.01);
      t += 0.01;
    }
    const double law = P * p.r_winding_housing_k_per_w(1) * (1.0 - std::exp(-t / p.tau_winding_s(1)));
    EXPECT_NEAR(m.winding_rise(1), law, 1e-6 * law) << "t = " << t;
  }
  // The continuous rating's steady state (the real housing) is the winding at Tmax exactly.
  MotorThermal c(phantom_thermal_torque_limit());
  VecX cont = VecX(p.continuous_n_m);
  for (int k = 0; k < 2000; ++k) c.advance(cont, 10.0);  // 20 000 s, 33 motor time constants
  for (int j = 0; j < 6; ++j) EXPECT_NEAR(c.normalised_temperature(j), 1.0, 1e-9);
}

TEST(MotorThermal, PeakLastsTheExpectedTimeThenDeratesTowardsContinuous) {
  const MotorThermalParams p = phantom_thermal_torque_limit();
  MotorThermal m(p);
  const double T = 1e-3;
  const double t_lim = time_to_limit(p, 1, p.peak_n_m(1));
  VecX cmd = VecX::Zero(6);
  cmd(1) = p.peak_n_m(1);
  long first_clipped = -1;
  double t = 0.0;
  for (long k = 0; t < 60.0; ++k) {
    VecX tau = cmd;
    m.limit(tau, T);
    if (first_clipped < 0 && tau(1) < p.peak_n_m(1)) first_clipped = k;
    if (first_clipped >= 0) {
      EXPECT_GE(tau(1), p.continuous_n_m(1) - 1e-12);
    }
    m.advance(tau, T);
    t += T;
    ASSERT_LE(m.winding_rise(1), p.max_winding_c(1) - p.ambient_c + 1e-9) << "k " << k;
  }
  std::printf("[thermal] q2 at its peak %.3f N m: limit reached after %.4f s (closed form), "
              "first derated tick at %.3f s\n",
              p.peak_n_m(1), t_lim, first_clipped * T);
  // The first tick the limit clips is the one whose end would pass Tmax.
  EXPECT_EQ(first_clipped, static_cast<long>(std::floor(t_lim / T)));
  EXPECT_GT(t_lim, 2.0);  // RE 25: ~3.7 s at the stall torque
  EXPECT_LT(t_lim, 6.0);
  // Held at Tmax, the allowed torque falls as the housing warms, towards the continuous rating.
  const double at60 = m.allowed_torque(1, T);
  EXPECT_NEAR(m.normalised_temperature(1), 1.0, 1e-9);
  EXPECT_LT(at60, p.peak_n_m(1));
  EXPECT_GT(at60, p.continuous_n_m(1));
  for (int k = 0; k < 4000; ++k) {  // 4000 s more, in 1 s ticks
    VecX tau = cmd;
    m.limit(tau, 1.0);
    m.advance(tau, 1.0);
  }
  VecX tau = cmd;
  m.limit(tau, 1.0);
  EXPECT_NEAR(tau(1), p.continuous_n_m(1), 0.01 * p.continuous_n_m(1));
  EXPECT_LT(tau(1), at60);
}

TEST(MotorThermal, FaultModeReportsTheSameTickAndCools) {
  MotorThermalParams p = phantom_thermal_torque_limit();
  p.on_overheat = OnOverheat::kFault;
  MotorThermal m(p);
  const double T = 1e-3;
  const long expect = static_cast<long>(std::floor(time_to_limit(p, 1, p.peak_n_m(1)) / T));
  VecX cmd = VecX::Zero(6);
  cmd(1) = p.peak_n_m(1);
  long k = 0;
  for (;; ++k) {
    VecX tau = cmd;
    if (m.limit(tau, T)) {
      EXPECT_EQ(tau(1), cmd(1));  // not clipped: the caller applies zero
      break;
    }
    m.advance(tau, T);
    ASSERT_LT(k, 100000);
  }
  EXPECT_EQ(k, expect);
  const double hot = m.winding_rise(1);
  m.advance(VecX::Zero(6), 5.0);  // zero torque: it cools
  EXPECT_LT(m.winding_rise(1), 0.8 * hot);
}

// The simulated Phantom with a fast-heating motor (assumed constants, small so that the fault
// comes within 0.2 s): the fault is motor_temperature with zero torque, derating clips.
SimulatedDeviceConfig hot_config(OnOverheat on) {
  PhantomParams prm = default_phantom_params();
  prm.torque_limit = phantom_thermal_torque_limit();
  prm.torque_limit.tau_winding_s.setConstant(0.05);
  prm.torque_limit.on_overheat = on;
  SimulatedDeviceConfig c = phantom_device_config(prm);
  c.gravity = false;
  return c;
}

TEST(MotorThermal, SimulatedPhantomFaultsWithZeroTorqueOrDerates) {
  const PhantomParams prm = default_phantom_params();
  for (OnOverheat on : {OnOverheat::kFault, OnOverheat::kDerate}) {
    SimulatedPhantom dev(phantom_plant(prm), hot_config(on), phantom_home_q(prm));
    EXPECT_EQ(dev.limits().tau_max(1), phantom_thermal_torque_limit().peak_n_m(1));
    VecX tau = VecX::Zero(6);
    tau(1) = 0.2;  // -> 1.2 N m on q2 (peak 1.445): joints 1 and 3 push against each other
    tau(2) = -0.2;
    tau *= 6.0;
    const MotorThermal& th = dev.motor_thermal();
    ASSERT_TRUE(th.active());
    long k = 0;
    for (; k < 400 && dev.faults() == kFaultNone; ++k) {
      dev.write(tau);
      dev.advance();
      if (on == OnOverheat::kDerate && dev.applied_torque()(1) < tau(1)) break;
    }
    if (on == OnOverheat::kFault) {
      EXPECT_EQ(dev.faults(), kFaultMotorTemperature);
      EXPECT_EQ(fault_string(dev.faults()), "motor_temperature");
      EXPECT_EQ(dev.applied_torque().norm(), 0.0);
      EXPECT_LT(k, 400);
    } else {
      EXPECT_EQ(dev.faults(), kFaultNone);
      EXPECT_LT(dev.applied_torque()(1), tau(1));
      EXPECT_GE(dev.applied_torque()(1), 0.320 - 1e-9);  // 11.2 x 28.6 mN m
      EXPECT_LE(th.normalised_temperature(1), 1.0 + 1e-9);
    }
    std::printf("[thermal] simulated Phantom, %s: tick %ld, q2 winding %.1f C\n",
                on == OnOverheat::kFault ? "fault" : "derate", k, th.winding_temperature_c(1));
  }
}

TEST(MotorThermal, ThermalTicksDoNotAllocate) {
  // Through peak, derating and the fault, the tick allocates nothing.
  const PhantomParams prm = default_phantom_params();
  for (OnOverheat on : {OnOverheat::kDerate, OnOverheat::kFault}) {
    SimulatedPhantom dev(phantom_plant(prm), hot_config(on), phantom_home_q(prm));
    DeviceSample s = dev.make_sample();
    VecX tau = VecX::Zero(6);
    tau(1) = 1.2;
    tau(2) = -1.2;
    dev.read(s);
    dev.write(tau);
    dev.advance();
    long allocs = 0;
    {
      dentsim::testing::AllocationScope scope;
      for (int k = 0; k < 60; ++k) {
        dev.read(s);
        dev.write(tau);
        dev.advance();
      }
      allocs = scope.count();
    }
    EXPECT_EQ(allocs, 0);
    EXPECT_LE(dev.motor_thermal().normalised_temperature(1), 1.0 + 1e-9);
  }
}

TEST(MotorThermalFile, DefaultFileAndConfigAreTheClampBitForBit) {
  const PhantomParams d = default_phantom_params();
  EXPECT_EQ(d.torque_limit.model, TorqueLimitModel::kClamp);
  const std::string text = default_phantom_model_file();
  EXPECT_EQ(text.find("torque_limit\":"), std::string::npos);
  EXPECT_EQ(parse_phantom_params(text, "default"), d);
  const SimulatedDeviceConfig c = phantom_device_config(d);
  for (int j = 0; j < 6; ++j) {
    EXPECT_EQ(c.tau_max(j), d.torque_limit_n_m(j));
    EXPECT_EQ(c.tau_fault(j), 4.0 * d.torque_limit_n_m(j));
  }
  EXPECT_EQ(c.torque_limit.model, TorqueLimitModel::kClamp);
  EXPECT_EQ(phantom_torque_clamp(d), d.torque_limit_n_m);
  // {"model": "clamp"} reads as the default.
  std::string clamp = text;
  clamp.insert(clamp.rfind('}'), ", \"torque_limit\": {\"model\": \"clamp\"}\n");
  EXPECT_EQ(parse_phantom_params(clamp, "clamp"), d);
}

TEST(MotorThermalFile, ThermalRoundTripsAndBadValuesNameTheirKey) {
  PhantomParams p = default_phantom_params();
  p.torque_limit = phantom_thermal_torque_limit();
  p.torque_limit.on_overheat = OnOverheat::kFault;
  const std::string text = phantom_params_to_text(p);
  EXPECT_EQ(parse_phantom_params(text, "thermal"), p);
  EXPECT_EQ(phantom_torque_clamp(p), p.torque_limit.peak_n_m);
  const auto expect_bad = [&](const std::string& from, const std::string& to,
                              const std::string& key) {
    std::string bad = text;
    const std::size_t at = bad.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    bad.replace(at, from.size(), to);
    try {
      parse_phantom_params(bad, "bad.json");
      ADD_FAILURE() << "expected InputError for " << key;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  };
  expect_bad("\"model\": \"thermal\"", "\"model\": \"hot\"", "torque_limit.model");
  expect_bad("\"on_overheat\": \"fault\"", "\"on_overheat\": \"melt\"", "torque_limit.on_overheat");
  expect_bad("\"peak_n_m\": [1.7", "\"peak_n_m\": [0.1", "torque_limit.peak_n_m[0]");
  expect_bad("\"thermal_time_constant_winding_s\": [12.5", "\"thermal_time_constant_winding_s\": [-1",
             "torque_limit.thermal_time_constant_winding_s[0]");
  expect_bad("\"max_winding_temperature_c\": [125", "\"max_winding_temperature_c\": [20",
             "torque_limit.max_winding_temperature_c[0]");
  expect_bad("\"ambient_temperature_c\": 25", "\"ambient_temperature_c\": 25, \"x\": 1",
             "torque_limit");
}

}  // namespace
}  // namespace dentsim
