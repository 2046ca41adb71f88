// Velocity from quantised angles (device/velocity_estimator.h): the backward difference is within
// quantum/T_k of the true mean velocity over each tick; the low-pass keeps that bound once settled,
// has unit DC gain, and reduces the quantisation noise.
#include "device/velocity_estimator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include "reference/core/io.h"

namespace dentsim {
namespace {

constexpr double kQuantum = 2.0 * std::numbers::pi / (4.0 * 1024.0 * 11.2);

double quantise(double q) { return kQuantum * std::floor(q / kQuantum); }

struct RampRun {
  double worst_ratio = 0.0;  // max |qd_est - v| / (quantum / T_k) after settling
  double rms_error = 0.0;    // RMS of qd_est - v after settling [rad/s]
};

// Constant velocity v from q0, jittered ticks (uniform 1 ms +- 0.2 ms), seed printed.
RampRun run_ramp(VelocityEstimatorParams p, double v, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> tick(0.8e-3, 1.2e-3);
  VelocityEstimator est(1, p);
  double t = 0.0, q = 0.0123;
  est.reset(VecX::Constant(1, quantise(q)), t, VecX::Constant(1, v));
  RampRun r;
  double acc = 0.0;
  int n = 0;
  for (int k = 0; k < 5000; ++k) {
    const double T = tick(rng);
    t += T;
    q += v * T;
    const double qd = est.update(VecX::Constant(1, quantise(q)), t)[0];
    if (k < 100) continue;  // settling of the filter (100 ms >> 1 / (2 pi 200 Hz))
    r.worst_ratio = std::max(r.worst_ratio, std::abs(qd - v) / (kQuantum / T));
    acc += (qd - v) * (qd - v);
    ++n;
  }
  r.rms_error = std::sqrt(acc / n);
  return r;
}

TEST(VelocityEstimator, BackwardDifferenceErrorBelowQuantumOverT) {
  VelocityEstimatorParams p;
  p.filter = VelocityFilter::kBackwardDifference;
  for (double v : {0.013, 0.37, -1.9}) {
    const RampRun r = run_ramp(p, v, 11);
    std::printf("seed 11, v %+.3f rad/s: max |err| = %.4f quantum/T, RMS %.4e rad/s\n", v,
                r.worst_ratio, r.rms_error);
    EXPECT_LT(r.worst_ratio, 1.0);
    EXPECT_GT(r.worst_ratio, 0.5);  // the bound is approached: the test is not trivially loose
  }
}

TEST(VelocityEstimator, LowPassKeepsTheBoundAndReducesNoise) {
  VelocityEstimatorParams raw;
  raw.filter = VelocityFilter::kBackwardDifference;
  VelocityEstimatorParams lp;
  lp.filter = VelocityFilter::kFirstOrderLowPass;
  lp.cutoff_hz = 50.0;
  for (double v : {0.37, -1.9}) {
    const RampRun a = run_ramp(raw, v, 5), b = run_ramp(lp, v, 5);
    std::printf("seed 5, v %+.2f: RMS raw %.4e, low-pass 50 Hz %.4e rad/s; worst %.3f q/T\n", v,
                a.rms_error, b.rms_error, b.worst_ratio);
    EXPECT_LT(b.worst_ratio, 1.0 * 1.2e-3 / 0.8e-3);  // convex combination: quantum / min T
    EXPECT_LT(b.rms_error, 0.5 * a.rms_error);
  }
}

TEST(VelocityEstimator, LowPassHasUnitDcGainAndTheExactZohStep) {
  VelocityEstimatorParams p;
  p.cutoff_hz = 100.0;
  VelocityEstimator est(2, p);
  est.reset(VecX::Zero(2), 0.0, VecX::Zero(2));
  // A ramp q = v t without quantisation: qd_k = v (1 - exp(-2 pi f_c t_k)) at the sample times.
  const Eigen::Vector2d v(0.5, -2.0);
  double t = 0.0;
  for (int k = 1; k <= 400; ++k) {
    const double T = (k % 2 == 0) ? 0.7e-3 : 1.3e-3;
    t += T;
    const VecX& qd = est.update(v * t, t);
    const Eigen::Vector2d expected = v * (1.0 - std::exp(-2.0 * std::numbers::pi * 100.0 * t));
    ASSERT_LT((qd - expected).cwiseAbs().maxCoeff(), 1e-12) << "tick " << k;
  }
  EXPECT_LT((est.estimate() - v).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(VelocityEstimator, NonPositiveTickKeepsTheEstimate) {
  VelocityEstimatorParams p;
  p.filter = VelocityFilter::kBackwardDifference;
  VelocityEstimator est(1, p);
  est.reset(VecX::Zero(1), 0.0, VecX::Zero(1));
  est.update(VecX::Constant(1, 1e-3), 1e-3);
  EXPECT_DOUBLE_EQ(est.estimate()[0], 1.0);
  est.update(VecX::Constant(1, 5.0), 1e-3);  // same time: ignored
  EXPECT_DOUBLE_EQ(est.estimate()[0], 1.0);
}

TEST(VelocityEstimator, BadParamsThrow) {
  VelocityEstimatorParams p;
  p.cutoff_hz = 0.0;
  EXPECT_THROW(VelocityEstimator(1, p), InputError);
  EXPECT_THROW(VelocityEstimator(0, VelocityEstimatorParams{}), InputError);
}

}  // namespace
}  // namespace dentsim
