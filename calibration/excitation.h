// Excitation trajectories for calibration (issue #5) and running them on a device.
//
// Trajectory: per joint j a finite Fourier series with base frequency w_f = 2 pi f_base [rad/s]
// and L harmonics (Swevers et al. 1997), faded in by a raised-cosine window so that it starts at
// rest at the home pose q0:
//     d_j(t) = sum_{l=1..L} a_jl sin(l w_f t) + b_jl cos(l w_f t) - b_jl       (d_j(0) = 0)
//     s(t)   = (1 - cos(pi t / T_r)) / 2 for t < T_r, 1 afterwards
//     q_j(t) = q0_j + s(t) d_j(t)
// q, qd, qdd are analytic (product rule). Coefficients a, b are drawn uniform in [-1, 1]
// (std::mt19937_64, seeded), divided by l, and scaled per joint by one factor so that, over a
// fine time grid (ramp + one period, 0.5 ms; 2 % margin),
// q stays in [q_min + margin, q_max - margin], |qd| <= qd_max, and the model's inverse-dynamics
// torque M qdd + C qd + g + tau_f stays within torque_fraction * tau_max (reduced until it does).
//
// Running (run_excitation): joint-space PD tracking with model feed-forward on a Device,
//     tau = M(q) qdd_ref + C(q, qd) qd + g(q) + tau_f(qd_ref) + K_p (q_ref - q) + K_d (qd_ref - qd)
// with K_p = M_jj(q0) w_c^2, K_d = 2 M_jj(q0) w_c (critically damped per joint, w_c [rad/s]).
// The log records, per tick, the sample (t, q, qd as the driver reports them) and the torque the
// device applied over that tick (after saturation). Units SI, device joint order (device.h).
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "calibration/log.h"
#include "device/device.h"
#include "reference/phantom/phantom_params.h"

namespace dentsim {

struct ExcitationParams {
  double base_frequency_hz = 0.2;  // f_base
  int harmonics = 5;               // L
  double ramp_s = 1.0;             // T_r
  double limit_margin_rad = 0.05;  // distance kept from each joint limit
  Vec6 qd_max_rad_s = Vec6::Constant(2.0);
  double torque_fraction = 0.7;  // of the model's torque limit
  std::uint64_t seed = 1;
};

using CoefficientMatrix = Eigen::Matrix<double, 6, Eigen::Dynamic>;

class Excitation {
 public:
  // Draws and scales the coefficients for the model `p` around `q0`. Throws InputError if the
  // home pose is outside the limits or no scale satisfies the torque limit.
  Excitation(const PhantomParams& p, const Vec6& q0, const ExcitationParams& e);
  // The same with the unit coefficients given (6 x e.harmonics each; design_excitation).
  Excitation(const PhantomParams& p, const Vec6& q0, const ExcitationParams& e,
             const CoefficientMatrix& a, const CoefficientMatrix& b);

  void eval(double t, Vec6* q, Vec6* qd, Vec6* qdd) const;
  const Vec6& q0() const { return q0_; }
  const ExcitationParams& params() const { return e_; }
  // Per-joint amplitude scale applied to the unit coefficients.
  const Vec6& scale() const { return scale_; }
  const CoefficientMatrix& a() const { return a_; }
  const CoefficientMatrix& b() const { return b_; }

 private:
  void fit_to_limits(const PhantomParams& p);
  void eval_unscaled(double t, Vec6* d, Vec6* dd, Vec6* ddd) const;

  ExcitationParams e_;
  Vec6 q0_;
  CoefficientMatrix a_, b_;
  Vec6 scale_ = Vec6::Ones();
};

// How well an excitation identifies the model (issue #17): the condition number of the regressor
// Y(q, qd, qdd) of calibration/fit.h, columns normalised as the fit normalises them, stacked over
// `samples` points of one period after the ramp: sigma_1 / sigma_rank. rank 0 takes the singular
// values above null_tol sigma_1 (the fit's identifiable subspace) and returns how many that was;
// the design fixes the rank of the seeded series so that it cannot improve the number by pushing a
// direction below the threshold.
struct ExcitationCondition {
  double condition_number = 0.0;
  int rank = 0;
};
ExcitationCondition excitation_condition(const PhantomParams& p, const Excitation& exc,
                                         int samples = 200, int rank = 0, double null_tol = 1e-6);

// An excitation designed for identification: from the seeded series, `iterations` steps of a
// seeded random local search on the unit coefficients (Gaussian steps, 1/l roll-off, step size
// grown on success and shrunk on failure), each candidate scaled into the joint, velocity and
// torque limits as the constructor does, kept when it lowers the condition number at the seeded
// series' rank (evaluated on 100 samples of the period). `progress` (optional) gets (iteration,
// best condition number).
struct ExcitationDesign {
  Excitation excitation;
  double condition_seeded = 0.0;    // the seeded series'
  double condition_designed = 0.0;  // the result's
  int rank = 0;
  int iterations = 0, accepted = 0;
};
ExcitationDesign design_excitation(const PhantomParams& p, const Vec6& q0,
                                   const ExcitationParams& e, int iterations,
                                   const std::function<void(int, double)>& progress = {});

struct TrackingParams {
  double bandwidth_rad_s = 2.0 * 3.14159265358979323846 * 5.0;  // w_c
};

// Runs `exc` for `duration` [s] on `device` (already at rest near exc.q0()), with the model `p`
// for the feed-forward. Throws InputError if the device faults (the log up to the fault would be
// misleading). With `exact_state` (a simulated device's ground truth, e.g. SimulatedPhantom's
// true_q / true_qd) the tracking and the log use it instead of the driver's q and qd: the
// "ideal sensing" harness that isolates the plant from quantisation and velocity estimation.
struct ExactState {
  const VecX* q = nullptr;
  const VecX* qd = nullptr;
};
CalibrationLog run_excitation(Device& device, const PhantomParams& p, const Excitation& exc,
                              double duration, const TrackingParams& tracking = {},
                              ExactState exact_state = {});

// Noise-free data by inverse dynamics of the model `truth` along the reference trajectory:
// q, qd exact, tau = M qdd + C qd + g + tau_f, sampled every `dt` [s] (no tracking error, no
// quantisation; the test oracle for the fit).
CalibrationLog synthesize_log(const PhantomParams& truth, const Excitation& exc, double duration,
                              double dt);

}  // namespace dentsim
