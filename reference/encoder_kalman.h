// Model-based sub-count estimate of the device's joint state from quantised encoders (issue #29
// item 3; docs/derivations/quiet_stiffness.md "The encoder Kalman filter").
//
// The driver reports q_m = Delta floor(q / Delta) per joint (an incremental counter: the true angle
// lies in the cell [q_m, q_m + Delta)) and a velocity differentiated from q_m. Fed to the tick as
// they are, each count steps the coupling and the contact by K Delta (the static staircase of the
// derivation). This filter estimates (q, qd) per joint between counts with the device's own model:
//
//   predict   a    = M^-1 (tau_prev + f_hat - g - tau_f)        (the tick's last terms; Coriolis
//                                                               neglected at haptic speeds)
//             (tau_f left out with EncoderKalmanParams::model_friction false: at a haptic
//             standstill Coulomb friction is set-valued, and the model's smooth
//             f_c tanh(qd_hat / v_s) at the filter's own velocity is a velocity feedback ~f_c / v_s
//             inside the filter that the coupled M^-1 carries from the arm's joints into the
//             gimbal's; docs/derivations/quiet_stiffness.md 8.6)
//             (with EncoderKalmanParams::stick_slip the friction is set-valued instead: a =
//             (v+ - qd_hat) / T with v+ from encoder_stick_slip_velocity below, 8.7)
//             q-   = q_hat + T qd_hat + T^2/2 a,  qd- = qd_hat + T a
//   correct   r    = (q_m + Delta/2) - q-
//             q_hat = q- + alpha r,  qd_hat = qd- + (beta / T) r
//   project   q_hat into the cell [q_m, q_m + Delta]  (never further from the truth than a count)
//
// alpha, beta are the steady-state Kalman gains of a double integrator driven by white
// acceleration noise of std sigma_a per tick, measured with the quantisation's noise
// Delta / sqrt(12) (Kalata, "The tracking index", IEEE TAES 20(2), 1984):
//   lambda = sigma_a T^2 / (Delta / sqrt(12)),  r = (4 + lambda - sqrt(8 lambda + lambda^2)) / 4,
//   alpha = 1 - r^2,  beta = 2 (1 - r)^2.
// sigma_a is the acceleration of the force the model does not know (the hand's force beyond the
// observer's estimate): a tip force of std sigma_f per axis and a grip torque sigma_f * lever on
// joint i, over its inertia: sigma_a,i = sigma_f (|J_v,i| + lever |J_w,i|) / M_ii. Nothing here is
// fitted to a scene: Delta from the device, T from the clock, M and J_t from the device model,
// sigma_f and the lever from the hand (EncoderKalmanParams).
#pragma once

#include "reference/core/pipeline.h"  // EncoderKalmanState; EncoderKalmanParams (core/params.h)

namespace dentsim {

// Kalata's steady-state alpha-beta gains for tracking index lambda >= 0.
void alpha_beta_gains(double lambda, double* alpha, double* beta);

// Starts the estimate in the middle of the measured cells with velocity qd0.
void encoder_kalman_reset(const Vec6& q_meas, const Vec6& qd0, const Vec6& quantum,
                          EncoderKalmanState& s);

// One tick: predicts with acceleration `accel` over T, corrects with the measured angles and
// projects into their cells. Joints with a zero quantum take the measurement (q_meas, qd_meas).
// sigma_a: per-joint acceleration noise std [rad/s^2]. No allocation.
void encoder_kalman_update(const Vec6& q_meas, const Vec6& qd_meas, const Vec6& quantum,
                           const Vec6& accel, const Vec6& sigma_a, double T,
                           EncoderKalmanState& s);

// The velocity after one tick T of a joint system with set-valued (stick-slip) Coulomb friction
// and implicit viscous friction, all joints coupled by the inertia M
// (docs/derivations/quiet_stiffness.md 8.7):
//   M (v+ - v) = T (r - B v+) + lambda,   B = diag(b),
//   per joint i either v+_i = 0 and |lambda_i| <= f_c,i T          (stick)
//              or lambda_i = -sign(v+_i) f_c,i T                   (slip),
// with r the torque without friction (tau_prev + f_hat - g in the filter). With A = M + T B and
// the Delassus matrix W = A^-1, v+ = v_free + W lambda, v_free = W (M v + T r): a box-constrained
// LCP, the minimum of 1/2 lambda^T W lambda + lambda^T v_free over the box, unique for M SPD.
// Solved by projected Gauss-Seidel (at most kStickSlipSweeps sweeps), then made exact on the
// active set it found (the sticking joints' impulses solved, the sliding ones' at their bound;
// at most kStickSlipPivots corrections; if those do not settle, the Gauss-Seidel answer stands).
// Sticking joints get v+_i = 0 exactly. Returns false (outputs untouched) when A is not SPD, T is
// not > 0 or an input or the answer is not finite. impulse (may be null): lambda [N m s].
// No allocation, no exception.
inline constexpr int kStickSlipSweeps = 40;
inline constexpr int kStickSlipPivots = 8;
bool encoder_stick_slip_velocity(const Mat6& M, const Vec6& b, const Vec6& f_c, const Vec6& v,
                                 const Vec6& r, double T, Vec6* v_plus, Vec6* impulse = nullptr);

}  // namespace dentsim
