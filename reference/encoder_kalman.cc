#include "reference/encoder_kalman.h"

#include <algorithm>
#include <cmath>

namespace dentsim {

void alpha_beta_gains(double lambda, double* alpha, double* beta) {
  const double l = std::max(lambda, 0.0);
  const double r = (4.0 + l - std::sqrt(8.0 * l + l * l)) / 4.0;
  *alpha = 1.0 - r * r;
  *beta = 2.0 * (1.0 - r) * (1.0 - r);
}

void encoder_kalman_reset(const Vec6& q_meas, const Vec6& qd0, const Vec6& quantum,
                          EncoderKalmanState& s) {
  s.q = q_meas + 0.5 * quantum;
  s.qd = qd0;
  s.ready = true;
}

void encoder_kalman_update(const Vec6& q_meas, const Vec6& qd_meas, const Vec6& quantum,
                           const Vec6& accel, const Vec6& sigma_a, double T,
                           EncoderKalmanState& s) {
  for (int i = 0; i < 6; ++i) {
    const double d = quantum(i);
    if (!(d > 0.0)) {
      s.q(i) = q_meas(i);
      s.qd(i) = qd_meas(i);
      continue;
    }
    const double q_pred = s.q(i) + T * s.qd(i) + 0.5 * T * T * accel(i);
    const double qd_pred = s.qd(i) + T * accel(i);
    const double sigma_m = d / std::sqrt(12.0);
    double alpha = 0.0, beta = 0.0;
    alpha_beta_gains(sigma_a(i) * T * T / sigma_m, &alpha, &beta);
    const double r = (q_meas(i) + 0.5 * d) - q_pred;
    s.q(i) = std::clamp(q_pred + alpha * r, q_meas(i), q_meas(i) + d);
    s.qd(i) = qd_pred + (beta / T) * r;
  }
}

}  // namespace dentsim
