// Ceres fit of the Phantom's inertial and friction parameters from a calibration log (issue #5).
//
// Model (thesis (2.1), reference/phantom/phantom_model.h), per sample k and device joint j:
//     tau_k = M(q_k; p) qdd_k + C(q_k, qd_k; p) qd_k + g(q_k; p) + b qd_k + f_c tanh(qd_k / v_s)
// Parameters p (kCalibParams = 50, SI units, in this order):
//     for each of the 8 tree bodies (base, upper_arm, forearm, crank, parallel_link, gimbal_yaw,
//     gimbal_pitch, gimbal_roll): mass [kg] and the second moments of its mass distribution about
//     the CoM along its principal axes, d = (int x^2 dm, int y^2 dm, int z^2 dm) [kg m^2], so that
//     I = (d_y + d_z, d_x + d_z, d_x + d_y): d >= 0 is exactly the physical (triangle-inequality)
//     set of principal inertias, and I is linear in d;
//     armature_j [kg m^2], viscous damping b_j [N m s/rad], Coulomb f_c,j [N m] for j = 1..6.
// v_s per joint is chosen by profile least squares (FitOptions::fit_coulomb_smoothing) or kept at
// the prior's; rows of joint j with |qd_j| < min_speed_rad_s (stiction) are dropped.
// Geometry (lengths, CoM positions, axes) stays at the prior model file's values. With the
// CoM fixed, tau is linear in p: tau_k = Y_k p. Y_k (6 x 50) is obtained by differentiating the
// templated model with ceres::Jet at the prior (exact for a linear map; tested against the double
// inverse dynamics). The Ceres problem is then, in relative units x_i = p_i / s_i
// (s_i = |prior_i|, 1e-6 if the prior is 0):
//     min sum_k rho(|Y_k S x - tau_k|^2) + sum_i (w (x_i - x0_i))^2,
// rho the Huber loss (delta = huber_n_m), w the weak prior weight [N m per unit relative change],
// subject to x_i >= min_fraction (every parameter stays positive: the fitted file loads).
// qdd_k: central difference of qd over (t_k-1, t_k+1), after an optional zero-phase low-pass
// (forward-backward first order, cutoff lowpass_hz) applied alike to qd, tau and the Coulomb
// column tanh(qd_raw / v_s) ("parallel filtering"; docs/calibration.md says why this and not the
// integral form).
// Identifiability: SVD of the column-normalised stacked Jacobian J diag(1/|J_i|) at the solution;
// right singular vectors with sigma < null_tol sigma_max span the near-null space; parameter i is
// identifiable when its unit vector has a component below null_component in that space (else it
// is "not identifiable": only the prior fixes it along the null directions); a structurally
// identifiable parameter whose statistical standard deviation exceeds max_rel_std |prior| is not
// identifiable in practice (below the noise floor) and reported as such too; the model-mismatch
// terms (how far the law may move a parameter) widen its reported std, not this test. The condition
// number reported is sigma_max / sigma_min over the singular values kept. Standard deviations:
// Ceres covariance C of x (DENSE_SVD, prior included) in the Newey-West sandwich C S C, S the
// autocorrelation-consistent covariance of the score over L lags (fit.cc says why and how L is
// chosen); std_white = sqrt(C RSS / (m - n_identifiable)) is the textbook value for comparison.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "calibration/log.h"
#include "reference/phantom/phantom_params.h"

namespace dentsim {

inline constexpr int kCalibParams = 50;
using CalibVec = Eigen::Matrix<double, kCalibParams, 1>;
using Regressor = Eigen::Matrix<double, 6, kCalibParams>;

// Second moments d of principal inertias I (inverse of I = (d_y + d_z, d_x + d_z, d_x + d_y)).
Vec3 second_moments(const Vec3& I);
template <typename Derived>
Eigen::Matrix<typename Derived::Scalar, 3, 1> principal_inertia(
    const Eigen::MatrixBase<Derived>& d) {
  Eigen::Matrix<typename Derived::Scalar, 3, 1> I;
  I << d(1) + d(2), d(0) + d(2), d(0) + d(1);
  return I;
}

// Names ("upper_arm.mass_kg", "armature_kg_m2.3", ...), packing and unpacking.
std::vector<std::string> calib_param_names();
CalibVec pack_calib_params(const PhantomParams& p);
// `prior` with the 50 parameters replaced by `x`.
PhantomParams unpack_calib_params(const PhantomParams& prior, const CalibVec& x);

// Y(q, qd, qdd) at the geometry of `prior` (autodiff through PhantomModelT<ceres::Jet>).
Regressor calib_regressor(const PhantomParams& prior, const Vec6& q, const Vec6& qd,
                          const Vec6& qdd);
// The same Y built independently of the derivative path: tau is linear and homogeneous in p at
// fixed geometry, so column i is the double inverse dynamics M qdd + C qd + g + tau_f of the
// model whose 50 parameters are the unit vector e_i (the test oracle of calib_regressor).
Regressor calib_regressor_by_columns(const PhantomParams& prior, const Vec6& q, const Vec6& qd,
                                     const Vec6& qdd);

// Lag [ticks] of a driver velocity estimate (device/velocity_estimator.h) behind the sampled
// angle, at low frequency, for tick length T [s]: the backward difference (q_k - q_k-1) / T
// describes t_k - T/2 (1/2 tick); the first-order low-pass qd_k = qd_k-1 + a (raw_k - qd_k-1),
// a = 1 - exp(-2 pi f_c T), adds its DC group delay (1 - a) / a ticks. Phantom defaults
// (200 Hz, 1 kHz): 0.5 + 0.398 = 0.898 ticks.
double driver_velocity_lag_ticks(bool lowpass, double cutoff_hz, double T);

struct FitOptions {
  double lowpass_hz = 0.0;     // zero-phase low-pass of qd and tau; 0 = off
  int lowpass_order = 2;       // 1: first order; 2: second-order Butterworth (both zero-phase)
  int max_samples = 3000;      // samples used (evenly strided over the log)
  double huber_n_m = 0.02;     // Huber delta [N m]
  double prior_weight = 1e-6;  // w [N m per unit relative deviation]
  double null_tol = 1e-6;      // relative singular-value threshold of the near-null space
  double null_component = 1e-3;
  int max_iterations = 100;
  double min_fraction = 1e-3;  // lower bound of every parameter, relative to its prior
  // Aligns the held torque with the sampled state: the torque used with sample k is the logged
  // torque at fractional index k - torque_shift_samples (linear interpolation). A torque held
  // over [t_k, t_k+1] is centred at t_k + T/2, and a driver velocity with lag L [s] describes
  // t_k - L, so shift = L / T + 1/2 (docs/calibration.md). 0 = no shift.
  double torque_shift_samples = 0.0;
  // The same for the angle: the q used with sample k is q at fractional index
  // k - position_shift_samples. With a driver velocity lagging by d ticks
  // (driver_velocity_lag_ticks) and a torque held over the tick, position shift d and torque
  // shift d + 1/2 put q, qd and tau on the velocity's time line.
  double position_shift_samples = 0.0;
  // The velocity whose tanh(v / v_s) forms the Coulomb column (the column is then low-passed like
  // tau): the low-passed qd (true) or the logged qd (false). A noisy logged velocity flips sign
  // at random near every reversal, which shrinks the column there and biases f_c upwards
  // (errors in variables; docs/calibration.md has the numbers).
  bool coulomb_from_filtered_velocity = true;
  double max_rel_std = 0.1;  // std_statistical / |prior| above which: not identifiable
  // Drop, per joint, the torque rows of the slowest `exclude_slow_fraction` of the used samples
  // (by |qd_j|): where a joint reverses, its friction law matters most. 0: every row.
  double exclude_slow_fraction = 0.0;
  // Model-mismatch term (issue #17): refit without each joint's slowest quarter of rows and
  // compare (a Hausman-type test). With the right friction law both fits estimate the same
  // parameters and differ only by noise: Var(d) = Var(reduced) - Var(full) for d = reduced -
  // full. A real joint's friction is never the model's tanh, and the fit then moves with the
  // rows near reversals: std_model = sqrt(max(0, d^2 - Var(d))) is added to each parameter's std,
  // and |d| / sqrt(Var(d)) > 3 on a parameter the data pin is reported as a mismatch. Off: the
  // statistical std alone.
  bool model_mismatch_term = true;
  // The law term of the model-mismatch uncertainty (with model_mismatch_term): refit with each
  // joint's other smooth sign (tanh <-> erf; v_s profiled again with fit_coulomb_smoothing) on the
  // same rows. Both are smooth signs a real joint's friction may average to; the data seldom
  // tell them apart (docs/calibration.md: over 20 seeded devices neither wins), and where they do
  // not, what the parameters do when the law changes is uncertainty the statistics cannot see:
  // std_law = |law refit - fit| is added to each parameter's std, and a move beyond 3 statistical
  // std on a parameter the data pin is reported as a mismatch.
  bool law_mismatch_term = true;
  // Drop joint j's torque row where its low-passed speed |qd_j| is below this [rad/s]: in and
  // near stiction a joint's Coulomb friction is any torque within +-f_c, set by what holds the
  // joint, not by its velocity (MuJoCo's frictionloss, a real joint's static friction), so no
  // law of qd describes those rows and fitting them bends the inertias (docs/calibration.md,
  // "Stiction and the smooth sign"). Applied before exclude_slow_fraction. 0: every row.
  double min_speed_rad_s = 0.2;
  // Fit v_s of f_c tanh(qd / v_s) per joint (profile least squares over a grid, the fitted model
  // file carries it) instead of keeping the prior's: a joint whose velocity dithers (quantised
  // sensing, a stiff tracking loop, a light gimbal link) feels Coulomb friction averaged over the
  // dither, a smoother sign than its static law.
  bool fit_coulomb_smoothing = true;
  // The smooth sign of every joint's Coulomb law (CoulombSign; the fitted model carries it), or
  // nullopt: the prior's. erf is the sign averaged over a Gaussian velocity dither of std
  // v_s / sqrt(2) (what a dithering joint feels); tanh the default model's law. Over 20 seeded
  // devices neither wins on the gimbal Coulomb friction (docs/calibration.md): the prior's by
  // default.
  std::optional<CoulombSign> coulomb_sign;
  // With fit_coulomb_smoothing: the profile also chooses each joint's sign, tanh or erf
  // (coulomb_sign then only sets where the search starts).
  bool fit_coulomb_sign = false;
};

// The profile of FitOptions::fit_coulomb_smoothing: the residual sum of squares [N^2 m^2] of
// the kept rows for each candidate v_s of each joint (the others at their chosen values).
struct CoulombSmoothingProfile {
  std::vector<double> v_s_rad_s;
  std::vector<CoulombSign> sign;  // of each candidate
  std::array<std::vector<double>, 6> rss;
};

struct FitParameter {
  std::string name;
  double prior = 0.0, value = 0.0;
  // Reported uncertainty: sqrt(std_statistical^2 + std_model^2 + std_law^2) (std_statistical
  // alone when the model-mismatch term is off).
  double std = 0.0;
  double std_statistical = 0.0;  // Newey-West (autocorrelation-consistent) standard deviation
  double std_model = 0.0;        // the slow-row term (FitOptions::model_mismatch_term)
  double std_law = 0.0;          // the law term (FitOptions::law_mismatch_term)
  double std_white = 0.0;        // textbook std, residuals assumed independent (for comparison)
  bool identifiable = false;
  // Not in the near-null space (identifiable may still be false: below the noise floor).
  bool structurally_identifiable = false;
};

// What the residuals say about the model, per joint.
struct ResidualDiagnostics {
  Vec6 lag1_autocorrelation = Vec6::Zero();  // of the residual: autocorrelation[j][0]
  // RMS residual over the used samples in the slowest and the fastest quarter of |qd_j|: a
  // friction law that does not fit shows where the joint reverses (slow), not where it moves.
  Vec6 rms_slow = Vec6::Zero(), rms_fast = Vec6::Zero();
  // Whiteness, per joint over its kept rows: the residual's autocorrelation rho_l at lags
  // l = 1..K (K = autocorrelation_lags = 2 x the Newey-West lags, at least 10, at most a quarter
  // of the samples; pairs of kept rows only), the Ljung-Box statistic
  // Q = n (n + 2) sum_l rho_l^2 / (n - l) and the 99 % point of chi^2 with K degrees of freedom
  // (Wilson-Hilferty); Q above it: not white. After the zero-phase low-pass a residual is
  // correlated over the filter's time by construction, which the Newey-West std allows for over
  // FitResult::hac_lags samples: correlation_length, the first lag whose |rho| is inside the
  // white-noise band 2 / sqrt(n) (K + 1 if none), beyond hac_lags says that window is short.
  int autocorrelation_lags = 0;
  std::array<std::vector<double>, 6> autocorrelation;
  Vec6 ljung_box_q = Vec6::Zero();
  double ljung_box_threshold = 0.0;
  std::array<bool, 6> white{};
  std::array<int, 6> correlation_length{};
  // The residual against the signed velocity: joint j's kept rows by low-passed qd_j in (up to)
  // 5 bins of equal count on each side of 0, in order of qd: the bin's mean qd, the mean and RMS
  // residual, the rows. A friction law of the wrong shape shows as a pattern near qd = 0; a
  // direction-dependent Coulomb friction (f+ one way, f- the other: the symmetric law's
  // (f+ + f-) / 2 plus a constant (f+ - f-) / 2) as a mean offset of one sign on both sides.
  struct VelocityBins {
    std::vector<double> qd, mean, rms;
    std::vector<int> rows;
  };
  std::array<VelocityBins, 6> residual_vs_velocity;
};

struct FitResult {
  bool converged = false;
  std::string report;  // Ceres brief report
  int iterations = 0;
  PhantomParams fitted;
  std::vector<FitParameter> params;
  double residual_rms = 0.0;  // [N m] over all joints and samples used
  Vec6 residual_rms_joint = Vec6::Zero();
  double condition_number = 0.0;
  int samples = 0;
  int identifiable = 0;
  int hac_lags = 0;  // L of the Newey-West standard deviations (in used samples)
  ResidualDiagnostics diagnostics;
  // v_s of each joint's Coulomb law used by the fit (FitOptions::fit_coulomb_smoothing: chosen
  // by the profile, else the prior's); `fitted` carries it.
  Vec6 coulomb_smoothing_rad_s = Vec6::Zero();
  std::array<CoulombSign, 6> coulomb_sign{};          // the smooth sign used per joint
  CoulombSmoothingProfile coulomb_smoothing_profile;  // empty unless fitted
  // Rows used per joint (rows dropped by min_speed_rad_s / exclude_slow_fraction not counted).
  Eigen::Matrix<int, 6, 1> rows_used = Eigen::Matrix<int, 6, 1>::Zero();
  // The residuals say the model is not the plant: some parameter the data pin statistically moves
  // by more than 3 std of the difference when the slow rows are dropped (listed), or a joint's
  // residual at low speed is more than twice its residual at high speed (listed).
  bool model_mismatch = false;
  std::vector<std::string> model_mismatch_reasons;
  // The samples used: time, measured (filtered) and predicted torque.
  std::vector<double> t;
  std::vector<Vec6> tau_measured, tau_predicted;
  // Per used sample, the joints whose row the fit used (a dropped slow row has zero measured and
  // predicted torque above: no residual; plots draw only the rows used).
  std::vector<std::array<bool, 6>> row_used;
};

// Fits `log` starting from (and regularised towards) `prior`. Throws InputError if the log is
// too short for the options. A non-converged solve is reported in FitResult::converged.
FitResult fit_calibration(const CalibrationLog& log, const PhantomParams& prior,
                          const FitOptions& options = {});

}  // namespace dentsim
