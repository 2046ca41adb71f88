// The encoder Kalman filter's correction two joints at a time (why it is bitwise:
// fast/encoder_kalman.h; the filter: reference/encoder_kalman.h).
#include "fast/encoder_kalman.h"

#include <cmath>

#include "reference/encoder_kalman.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace dentsim::fast {

#if defined(__SSE2__)
namespace {

// Rows r0..r0+2 of columns i and i + 1 of a column-major 6x6: |(x, y, z)| per column, as
// sqrt((x^2 + y^2) + z^2).
__m128d column_pair_norm(const double* J, int i, int r0) {
  const double* a = J + 6 * i + r0;
  const __m128d x = _mm_set_pd(a[6], a[0]);
  const __m128d y = _mm_set_pd(a[7], a[1]);
  const __m128d z = _mm_set_pd(a[8], a[2]);
  return _mm_sqrt_pd(
      _mm_add_pd(_mm_add_pd(_mm_mul_pd(x, x), _mm_mul_pd(y, y)), _mm_mul_pd(z, z)));
}

}  // namespace
#endif

void encoder_acceleration_noise(const Mat6& J_t, const Mat6& M, const EncoderKalmanParams& p,
                                Vec6* sigma_a) {
#if defined(__SSE2__)
  const __m128d sigma_f = _mm_set1_pd(p.force_sigma_n);
  const __m128d lever = _mm_set1_pd(p.grip_lever_m);
  for (int i = 0; i < 6; i += 2) {
    const __m128d l = _mm_add_pd(column_pair_norm(J_t.data(), i, 0),
                                 _mm_mul_pd(lever, column_pair_norm(J_t.data(), i, 3)));
    const __m128d m_ii = _mm_set_pd(M(i + 1, i + 1), M(i, i));
    const __m128d s = _mm_div_pd(_mm_mul_pd(sigma_f, l), m_ii);
    _mm_storeu_pd(sigma_a->data() + i, _mm_and_pd(_mm_cmpgt_pd(m_ii, _mm_setzero_pd()), s));
  }
#else
  for (int i = 0; i < 6; ++i) {
    const double lever =
        J_t.col(i).head<3>().norm() + p.grip_lever_m * J_t.col(i).tail<3>().norm();
    (*sigma_a)(i) = M(i, i) > 0.0 ? p.force_sigma_n * lever / M(i, i) : 0.0;
  }
#endif
}

void encoder_kalman_update(const Vec6& q_meas, const Vec6& qd_meas, const Vec6& quantum,
                           const Vec6& accel, const Vec6& sigma_a, double T,
                           EncoderKalmanState& s) {
#if defined(__SSE2__)
  const __m128d zero = _mm_setzero_pd();
  const __m128d one = _mm_set1_pd(1.0);
  const __m128d two = _mm_set1_pd(2.0);
  const __m128d four = _mm_set1_pd(4.0);
  const __m128d eight = _mm_set1_pd(8.0);
  const __m128d half = _mm_set1_pd(0.5);
  const __m128d root12 = _mm_set1_pd(std::sqrt(12.0));
  const __m128d t = _mm_set1_pd(T);
  const __m128d half_tt = _mm_set1_pd(0.5 * T * T);
  for (int i = 0; i < 6; i += 2) {
    const __m128d d = _mm_loadu_pd(quantum.data() + i);
    const __m128d qm = _mm_loadu_pd(q_meas.data() + i);
    const __m128d qdm = _mm_loadu_pd(qd_meas.data() + i);
    const __m128d q = _mm_loadu_pd(s.q.data() + i);
    const __m128d qd = _mm_loadu_pd(s.qd.data() + i);
    const __m128d a = _mm_loadu_pd(accel.data() + i);
    // q- = q + T qd + T^2/2 a,  qd- = qd + T a
    const __m128d q_pred = _mm_add_pd(_mm_add_pd(q, _mm_mul_pd(t, qd)), _mm_mul_pd(half_tt, a));
    const __m128d qd_pred = _mm_add_pd(qd, _mm_mul_pd(t, a));
    // lambda = sigma_a T^2 / (Delta / sqrt 12), l = max(lambda, 0) (alpha_beta_gains)
    const __m128d sigma_m = _mm_div_pd(d, root12);
    const __m128d lambda =
        _mm_div_pd(_mm_mul_pd(_mm_mul_pd(_mm_loadu_pd(sigma_a.data() + i), t), t), sigma_m);
    const __m128d l = _mm_max_pd(zero, lambda);  // 0 > lambda ? 0 : lambda
    const __m128d root = _mm_sqrt_pd(_mm_add_pd(_mm_mul_pd(eight, l), _mm_mul_pd(l, l)));
    const __m128d r = _mm_div_pd(_mm_sub_pd(_mm_add_pd(four, l), root), four);
    const __m128d alpha = _mm_sub_pd(one, _mm_mul_pd(r, r));
    const __m128d one_r = _mm_sub_pd(one, r);
    const __m128d beta = _mm_mul_pd(_mm_mul_pd(two, one_r), one_r);
    // residual to the middle of the cell; q into [q_m, q_m + Delta] (std::clamp's order)
    const __m128d res = _mm_sub_pd(_mm_add_pd(qm, _mm_mul_pd(half, d)), q_pred);
    const __m128d q_new = _mm_add_pd(q_pred, _mm_mul_pd(alpha, res));
    const __m128d below = _mm_cmplt_pd(q_new, qm);
    const __m128d capped = _mm_min_pd(_mm_add_pd(qm, d), q_new);  // hi < x ? hi : x
    const __m128d q_out = _mm_or_pd(_mm_and_pd(below, qm), _mm_andnot_pd(below, capped));
    const __m128d qd_out = _mm_add_pd(qd_pred, _mm_mul_pd(_mm_div_pd(beta, t), res));
    // joints without a quantum (!(Delta > 0)) take the measurement
    const __m128d counted = _mm_cmpgt_pd(d, zero);
    _mm_storeu_pd(s.q.data() + i,
                  _mm_or_pd(_mm_and_pd(counted, q_out), _mm_andnot_pd(counted, qm)));
    _mm_storeu_pd(s.qd.data() + i,
                  _mm_or_pd(_mm_and_pd(counted, qd_out), _mm_andnot_pd(counted, qdm)));
  }
#else
  dentsim::encoder_kalman_update(q_meas, qd_meas, quantum, accel, sigma_a, T, s);
#endif
}

}  // namespace dentsim::fast
