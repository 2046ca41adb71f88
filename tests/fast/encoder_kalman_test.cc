// Tests for fast/encoder_kalman.h: the encoder Kalman filter's correction and its acceleration
// noise two joints at a time against the reference (reference/encoder_kalman.h's
// encoder_kalman_update; the noise against reference/tick.cc's loop, written out below as it
// stands there), bitwise (a zero's sign counts): random states, quanta (zero, negative and NaN
// among them: the joint takes the measurement), estimates inside, below and above their cells,
// noise from zero to huge, non-finite inputs. Seeds fixed.
#include "fast/encoder_kalman.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "reference/encoder_kalman.h"
#include "tests/fast/bitwise.h"
#include "tests/support/random.h"

namespace dentsim {
namespace {

using Rng = std::mt19937_64;

double uni(Rng& rng, double a, double b) { return testing::uniform(rng, a, b); }

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(FastEncoderKalman, UpdateIsTheReferencesBitwise) {
  Rng rng(4802);
  int unequal = 0, clamped_low = 0, clamped_high = 0, measured = 0;
  for (int trial = 0; trial < 50000; ++trial) {
    Vec6 quantum, q_meas, qd_meas, accel, sigma_a;
    EncoderKalmanState s;
    for (int i = 0; i < 6; ++i) {
      const int kind = static_cast<int>(uni(rng, 0.0, 20.0));
      quantum(i) = kind == 0 ? 0.0 : kind == 1 ? -1e-4 : kind == 2 ? kNaN : 
                   std::pow(10.0, uni(rng, -6.0, -2.0));
      q_meas(i) = uni(rng, -2.0, 2.0);
      qd_meas(i) = uni(rng, -5.0, 5.0);
      // the estimate near its cell: inside, below or above it after the prediction
      s.q(i) = q_meas(i) + uni(rng, -3.0, 4.0) * std::abs(quantum(i) == quantum(i) ? quantum(i) : 0.0);
      s.qd(i) = uni(rng, -5.0, 5.0);
      accel(i) = uni(rng, -100.0, 100.0);
      const int noise = static_cast<int>(uni(rng, 0.0, 10.0));
      sigma_a(i) = noise == 0 ? 0.0 : noise == 1 ? 1e12 : std::pow(10.0, uni(rng, -3.0, 5.0));
      if (!(quantum(i) > 0.0)) ++measured;
    }
    if (trial % 97 == 0) accel(trial % 6) = kNaN;
    if (trial % 89 == 0) sigma_a(trial % 6) = kInf;
    if (trial % 83 == 0) s.q(trial % 6) = kNaN;
    s.ready = true;
    const double T = std::pow(10.0, uni(rng, -4.5, -2.0));
    EncoderKalmanState ref = s, fast = s;
    encoder_kalman_update(q_meas, qd_meas, quantum, accel, sigma_a, T, ref);
    fast::encoder_kalman_update(q_meas, qd_meas, quantum, accel, sigma_a, T, fast);
    unequal += testing::unequal_entries(fast.q, ref.q) + testing::unequal_entries(fast.qd, ref.qd);
    for (int i = 0; i < 6; ++i) {
      if (quantum(i) > 0.0 && ref.q(i) == q_meas(i)) ++clamped_low;
      if (quantum(i) > 0.0 && ref.q(i) == q_meas(i) + quantum(i)) ++clamped_high;
    }
  }
  EXPECT_EQ(unequal, 0);
  // Guards: the cell's both bounds and the measured joints were exercised.
  EXPECT_GT(clamped_low, 1000);
  EXPECT_GT(clamped_high, 1000);
  EXPECT_GT(measured, 1000);
}

// reference/tick.cc's encoder step: sigma_a,i = sigma_f (|J_v,i| + lever |J_w,i|) / M_ii.
Vec6 reference_noise(const Mat6& J_t, const Mat6& M, const EncoderKalmanParams& p) {
  Vec6 sigma_a = Vec6::Zero();
  for (int i = 0; i < 6; ++i) {
    const double lever =
        J_t.col(i).head<3>().norm() + p.grip_lever_m * J_t.col(i).tail<3>().norm();
    sigma_a(i) = M(i, i) > 0.0 ? p.force_sigma_n * lever / M(i, i) : 0.0;
  }
  return sigma_a;
}

TEST(FastEncoderKalman, AccelerationNoiseIsTheReferenceLoopsBitwise) {
  Rng rng(4803);
  int unequal = 0, zero_inertia = 0;
  for (int trial = 0; trial < 50000; ++trial) {
    Mat6 J_t, M;
    for (int i = 0; i < 36; ++i) {
      J_t(i) = uni(rng, -1.0, 1.0) * std::pow(10.0, uni(rng, -4.0, 2.0));
      M(i) = uni(rng, -1.0, 1.0);
    }
    for (int i = 0; i < 6; ++i) {
      const int kind = static_cast<int>(uni(rng, 0.0, 20.0));
      M(i, i) = kind == 0 ? 0.0 : kind == 1 ? -1e-3 : kind == 2 ? kNaN
                                                      : std::pow(10.0, uni(rng, -5.0, 0.0));
      if (!(M(i, i) > 0.0)) ++zero_inertia;
    }
    if (trial % 101 == 0) J_t(trial % 36) = kNaN;
    EncoderKalmanParams p;
    p.force_sigma_n = std::pow(10.0, uni(rng, -2.0, 1.0));
    p.grip_lever_m = trial % 4 == 0 ? 0.0 : uni(rng, 0.0, 0.05);
    Vec6 fast;
    fast::encoder_acceleration_noise(J_t, M, p, &fast);
    unequal += testing::unequal_entries(fast, reference_noise(J_t, M, p));
  }
  EXPECT_EQ(unequal, 0);
  EXPECT_GT(zero_inertia, 10000);  // guard: the M_ii <= 0 branch ran
}

}  // namespace
}  // namespace dentsim
