#include "reference/encoder_kalman.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <array>
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

namespace {

// A joint's state in the stick-slip solve: no Coulomb friction, sticking, or sliding with the
// impulse at its lower bound -c (moving forward) or its upper bound +c (moving backward).
enum class Slip { kFree, kStick, kForward, kBackward };

// A sliding (or friction-free) joint's impulse: its bound, -c forward, +c backward, 0 free.
double slip_impulse(Slip s, double c) {
  return s == Slip::kForward ? -c : (s == Slip::kBackward ? c : 0.0);
}

}  // namespace

bool encoder_stick_slip_velocity(const Mat6& M, const Vec6& b, const Vec6& f_c, const Vec6& v,
                                 const Vec6& r, double T, Vec6* v_plus, Vec6* impulse) {
  if (!(T > 0.0) || !std::isfinite(T) || !M.allFinite() || !b.allFinite() || !f_c.allFinite() ||
      !v.allFinite() || !r.allFinite()) {
    return false;
  }
  Mat6 A = M;
  A.diagonal() += T * b.cwiseMax(0.0);  // the viscous part, implicit
  const Eigen::LLT<Mat6> llt(A);
  if (llt.info() != Eigen::Success) return false;
  const Mat6 W = llt.solve(Mat6::Identity());  // the Delassus matrix
  const Vec6 v_free = llt.solve(M * v + T * r);
  const Vec6 c = T * f_c.cwiseMax(0.0);  // the impulse bounds
  if (!W.allFinite() || !v_free.allFinite()) return false;

  // Projected Gauss-Seidel on W: w = v_free + W lambda is the current v+.
  Vec6 lambda = Vec6::Zero();
  Vec6 w = v_free;
  const double v_scale = 1.0 + v_free.cwiseAbs().maxCoeff();
  for (int sweep = 0; sweep < kStickSlipSweeps; ++sweep) {
    double largest = 0.0;
    for (int i = 0; i < 6; ++i) {
      if (!(c(i) > 0.0) || !(W(i, i) > 0.0)) continue;
      const double li = std::clamp(lambda(i) - w(i) / W(i, i), -c(i), c(i));
      const double dl = li - lambda(i);
      if (dl == 0.0) continue;
      w += W.col(i) * dl;
      lambda(i) = li;
      largest = std::max(largest, std::abs(W(i, i) * dl));
    }
    if (largest <= 1e-15 * v_scale) break;
  }

  // The active set Gauss-Seidel found, made exact: K lambda = rhs with the sticking joints' rows
  // W_i lambda = -v_free,i and the others' lambda_i at their bound; corrected while it violates.
  std::array<Slip, 6> state{};
  for (int i = 0; i < 6; ++i) {
    if (!(c(i) > 0.0)) {
      state[i] = Slip::kFree;
    } else if (lambda(i) <= -c(i)) {
      state[i] = Slip::kForward;
    } else if (lambda(i) >= c(i)) {
      state[i] = Slip::kBackward;
    } else {
      state[i] = Slip::kStick;
    }
  }
  const double v_tol = 1e-12 * v_scale;
  for (int pivot = 0; pivot < kStickSlipPivots; ++pivot) {
    Mat6 K = Mat6::Identity();
    Vec6 rhs = Vec6::Zero();
    for (int i = 0; i < 6; ++i) {
      if (state[i] == Slip::kStick) {
        K.row(i) = W.row(i);
        rhs(i) = -v_free(i);
      } else {
        rhs(i) = slip_impulse(state[i], c(i));
      }
    }
    const Eigen::PartialPivLU<Mat6> lu(K);
    const Vec6 l2 = lu.solve(rhs);
    if (!l2.allFinite()) break;
    const Vec6 w2 = v_free + W * l2;
    bool settled = true;
    for (int i = 0; i < 6; ++i) {
      const double slack = 1e-12 * c(i);
      if (state[i] == Slip::kStick && l2(i) > c(i) + slack) {
        state[i] = Slip::kBackward;
      } else if (state[i] == Slip::kStick && l2(i) < -c(i) - slack) {
        state[i] = Slip::kForward;
      } else if ((state[i] == Slip::kForward && w2(i) < -v_tol) ||
                 (state[i] == Slip::kBackward && w2(i) > v_tol)) {
        state[i] = Slip::kStick;
      } else {
        continue;
      }
      settled = false;
    }
    if (settled) {
      for (int i = 0; i < 6; ++i) {
        const bool stick = state[i] == Slip::kStick;
        lambda(i) = stick ? std::clamp(l2(i), -c(i), c(i)) : slip_impulse(state[i], c(i));
        w(i) = stick ? 0.0 : w2(i);
      }
      break;
    }
  }
  if (!w.allFinite()) return false;
  *v_plus = w;
  if (impulse != nullptr) *impulse = lambda;
  return true;
}

}  // namespace dentsim
