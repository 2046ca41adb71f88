// The encoder Kalman filter's correction, fast twin of reference/encoder_kalman.h's
// encoder_kalman_update: the same operations in the same order on the same doubles, two joints at
// a time (SSE2, every x86-64): + - * / and sqrt are correctly rounded lane by lane, and the
// reference's std::max(lambda, 0), std::clamp and the zero-quantum branch are written as the
// compares and selects they are (max(0, x) = 0 > x ? 0 : x, min(hi, x) = hi < x ? hi : x, NaN
// kept where the reference keeps it). Bitwise the reference's (tests/fast/encoder_kalman_test.cc);
// without SSE2 it is the reference's own loop. No allocation, no throw.
#pragma once

#include "reference/core/pipeline.h"

namespace dentsim::fast {

// sigma_a,i = sigma_f (|J_v,i| + lever |J_w,i|) / M_ii (0 where M_ii is not > 0): the filter's
// acceleration noise of reference/tick.cc's encoder step (reference/encoder_kalman.h), two columns
// of J_t at a time, each norm summed as Eigen sums a 3-vector's squares, (x^2 + y^2) + z^2: bitwise
// the reference's loop (tests/fast/encoder_kalman_test.cc).
void encoder_acceleration_noise(const Mat6& J_t, const Mat6& M, const EncoderKalmanParams& p,
                                Vec6* sigma_a);

void encoder_kalman_update(const Vec6& q_meas, const Vec6& qd_meas, const Vec6& quantum,
                           const Vec6& accel, const Vec6& sigma_a, double T,
                           EncoderKalmanState& s);

}  // namespace dentsim::fast
