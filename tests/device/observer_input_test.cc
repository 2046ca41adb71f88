// The momentum observer's input matched to the driver's velocity estimate (reference/observer.h
// "Input matched to the velocity estimate", device/device.h matched_observer_input).
//
// Plant: a 1-DoF point mass m (model exact, constant M, no Coulomb friction), torque held over each
// 1 ms tick (zero-order hold), integrated exactly; the driver reports the backward difference of
// the angle low-passed at 200 Hz (device/velocity_estimator.h). Predictions:
//   - matched input: f_hat = L / (s + L) H f, H the velocity estimate's filter, so a torque
//     sequence with f = 0 leaves f_hat at round-off and a constant f is estimated exactly;
//   - the thesis's input: f_hat = L / (s + L) (H f + (H - 1) tau), the torque leaks into the
//     estimate through (H - 1);
//   - in the decomposition's cancellation loop tau = -f_hat + (m / m_d) (f_hat - d_d v) (4.7)
//     the leak closes a loop through tau: the matched locked system follows
//     m_d dv/dt + d_d v = f, the unmatched one rings.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <vector>

#include "device/device.h"
#include "device/velocity_estimator.h"
#include "reference/observer.h"

namespace dentsim {
namespace {

// m qdd + b qd = tau + f.
class PointMass : public DeviceModel {
 public:
  PointMass(double m, double b) : m_(m), b_(b) {}
  int dof() const override { return 1; }
  MatX mass_matrix(const VecX&) const override { return MatX::Constant(1, 1, m_); }
  MatX coriolis_matrix(const VecX&, const VecX&) const override { return MatX::Zero(1, 1); }
  VecX gravity(const VecX&) const override { return VecX::Zero(1); }
  VecX friction_torque(const VecX&, const VecX& qd) const override { return b_ * qd; }

 private:
  double m_, b_;
};

constexpr double kT = 1e-3;
constexpr double kMass = 0.1;  // [kg]

ObserverInput matched() {
  DeviceCapabilities caps;
  caps.measures_velocity = false;
  caps.velocity_lowpass_hz = 200.0;
  return matched_observer_input(caps);
}

// Exact step of m qdd + b qd = u over T (u constant).
void exact_step(double m, double b, double u, double T, double& q, double& v) {
  if (b == 0.0) {
    q += v * T + 0.5 * u / m * T * T;
    v += u / m * T;
    return;
  }
  const double a = b / m, v_inf = u / b, e = std::exp(-a * T);
  q += v_inf * T + (v - v_inf) * (1.0 - e) / a;
  v = v_inf + (v - v_inf) * e;
}

// One run: `tau_of(k, f_hat, qd_est)` gives the torque of tick k; f(k) the human force. Returns
// the largest |f_hat - f_ref| over the run, f_ref = 0 or the estimate's steady value; fills the
// final state.
struct LoopRun {
  double max_abs_fhat = 0.0;
  double final_fhat = 0.0;
  double final_v = 0.0;
  double max_abs_v = 0.0;
};

template <class TauFn, class ForceFn>
LoopRun simulate(double b, double L, const ObserverInput& in, int ticks, TauFn tau_of, ForceFn f_of) {
  const PointMass model(kMass, b);
  MomentumObserver obs(model, VecX::Constant(1, L), in);
  VelocityEstimator est(1, VelocityEstimatorParams{VelocityFilter::kFirstOrderLowPass, 200.0});
  double q = 0.0, v = 0.0, t = 0.0;
  VecX qv = VecX::Zero(1);
  est.reset(qv, t, VecX::Zero(1));
  obs.reset(qv, VecX::Zero(1));
  VecX tau = VecX::Zero(1);
  double f_hat = 0.0, qd_est = 0.0;
  LoopRun r;
  for (int k = 0; k < ticks; ++k) {
    tau(0) = tau_of(k, f_hat, qd_est);
    exact_step(kMass, b, tau(0) + f_of(k), kT, q, v);
    t += kT;
    qv(0) = q;
    qd_est = est.update(qv, t)(0);
    f_hat = obs.update(qv, VecX::Constant(1, qd_est), tau, kT)(0);
    r.max_abs_fhat = std::max(r.max_abs_fhat, std::abs(f_hat));
    r.max_abs_v = std::max(r.max_abs_v, std::abs(v));
  }
  r.final_fhat = f_hat;
  r.final_v = v;
  return r;
}

TEST(ObserverInput, MatchedToTheDeviceVelocityEstimate) {
  DeviceCapabilities caps;
  caps.measures_velocity = false;
  caps.velocity_lowpass_hz = 200.0;
  EXPECT_TRUE(matched_observer_input(caps).match_backward_difference);
  EXPECT_EQ(matched_observer_input(caps).lowpass_hz, 200.0);
  caps.measures_velocity = true;  // a tachometer: nothing to match
  EXPECT_FALSE(matched_observer_input(caps).match_backward_difference);
  EXPECT_EQ(matched_observer_input(caps).lowpass_hz, 0.0);
}

TEST(ObserverInput, MatchedInputKeepsTheTorqueOutOfTheEstimate) {
  // f = 0, random torques held over each tick, no damping: the matched estimate is round-off.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  std::vector<double> taus(2000);
  for (double& x : taus) x = u(rng);
  auto tau_of = [&](int k, double, double) { return taus[k]; };
  auto no_force = [](int) { return 0.0; };
  const LoopRun m = simulate(0.0, 500.0, matched(), 2000, tau_of, no_force);
  const LoopRun t = simulate(0.0, 500.0, ObserverInput{}, 2000, tau_of, no_force);
  std::printf("max |f_hat| with f = 0, |tau| <= 0.5 N: matched %.3g N, thesis input %.3g N\n",
              m.max_abs_fhat, t.max_abs_fhat);
  EXPECT_LT(m.max_abs_fhat, 1e-9);
  EXPECT_GT(t.max_abs_fhat, 0.1);  // the leak (H - 1) tau is of the order of tau itself
}

TEST(ObserverInput, MatchedInputEstimatesAConstantForceExactly) {
  // f = 0.8 N from tick 0, tau a slow sinusoid, damping b in the (exact) model.
  auto tau_of = [](int k, double, double) { return 0.3 * std::sin(2.0 * std::numbers::pi * 2.0 * k * kT); };
  auto force = [](int) { return 0.8; };
  const LoopRun m = simulate(0.05, 200.0, matched(), 3000, tau_of, force);
  std::printf("f = 0.8 N: matched estimate after 3 s %.9f N\n", m.final_fhat);
  // The damping term is evaluated at the estimated velocity, which lags the true one: the
  // estimate is exact only for beta = 0 (previous test); here the residual is 7e-5 N.
  EXPECT_NEAR(m.final_fhat, 0.8, 2e-4);
}

TEST(ObserverInput, MatchedInputDoesNotRingInTheCancellationLoop) {
  // The locked-system feed-forward of (4.7) on the device alone: tau = -f_hat + (m/m_d)(f_hat -
  // d_d v_est). With f_hat = f the device follows m_d dv/dt + d_d v = f. A desired inertia far
  // above the device's (m/m_d = 0.01, as for the Phantom's gimbal against the tool's inertia)
  // makes tau ~ -f_hat: the loop through (H - 1) has gain ~1, and its phase lag (the estimate's
  // delay plus the 200 Hz low-pass) leaves little margin at L ~ 900/s.
  const double m_d = 100.0 * kMass, d_d = 10.0, f = 0.5;
  auto force = [&](int) { return f; };
  auto tau_of = [&](int, double f_hat, double v_est) {
    return -f_hat + kMass / m_d * (f_hat - d_d * v_est);
  };
  // v(10 s) of the locked system (time constant m_d / d_d = 1 s); the estimate's lag adds an
  // impulse f (1/L + lag) whose velocity has decayed by e^-10 by then.
  const double target = f / d_d * (1.0 - std::exp(-10.0 * d_d / m_d));
  for (double L : {200.0, 500.0, 900.0}) {
    const LoopRun m = simulate(0.0, L, matched(), 10000, tau_of, force);
    const LoopRun t = simulate(0.0, L, ObserverInput{}, 10000, tau_of, force);
    std::printf("L = %.0f/s: v(10 s) matched %.6f, thesis input %.6g m/s (target %.6f); "
                "max |f_hat| matched %.4g, thesis input %.4g N (f = %.1f N)\n",
                L, m.final_v, t.final_v, target, m.max_abs_fhat, t.max_abs_fhat, f);
    EXPECT_NEAR(m.final_v, target, 1e-3 * target) << L;
    EXPECT_LE(m.max_abs_fhat, f * (1.0 + 1e-9)) << L;  // L/(s+L) H: no overshoot
    // The thesis's input rings: its estimate overshoots the step (measured 14 % at 500/s, 38 %
    // at 900/s), and the overshoot grows with L as the loop's phase margin shrinks.
    if (L >= 900.0) {
      EXPECT_GT(t.max_abs_fhat, 1.2 * f) << L;
    }
  }
}

}  // namespace
}  // namespace dentsim
