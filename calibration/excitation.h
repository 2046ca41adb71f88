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

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
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

// How an excitation run ended (issue #33): the log up to the stop, and why it stopped early.
struct ExcitationOutcome {
  CalibrationLog log;  // t from the excitation's start; log.incomplete = stop_reason when stopped
  bool complete = false;
  std::string stop_reason;           // "" when complete
  std::uint32_t fault = kFaultNone;  // the device's faults at the stop (kFaultNone: a guard or
                                     // an interruption stopped it, or it completed)
  bool interrupted = false;          // stopped by the stop request (SIGINT / SIGTERM)
  double stop_t = 0.0;  // [s] device time of the stop from the excitation's start (< 0: before)
  // Guarded runs (run_guarded_excitation): what the guards did.
  double max_command_ratio = 0.0;  // max over ticks and joints of |tau_cmd_j| / tau_max_j
  double max_speed_rad_s = 0.0;    // max low-passed |qd_j| over the run
  long ticks = 0, clamped_ticks = 0, late_ticks = 0, guard_ticks = 0;
  double min_time_scale = 1.0;  // the slowest the velocity/torque guard made the excitation
  Vec6 gravity_offset = Vec6::Zero();  // the integral action at the end of the settle [N m]
};

// run_excitation, but a device fault ends the run with the log up to it (ExcitationOutcome)
// instead of throwing; `stop_request` (optional, e.g. set by a SIGINT handler) ends it alike.
ExcitationOutcome run_excitation_until_stop(Device& device, const PhantomParams& p,
                                            const Excitation& exc, double duration,
                                            const TrackingParams& tracking = {},
                                            ExactState exact_state = {},
                                            const std::atomic<bool>* stop_request = nullptr);

// An excitation on a device whose model is not known (a new device: issue #33). `prior` is only
// the best guess: whatever its mismatch with the device (gravity, masses, friction), the run stays
// inside the device's limits by construction:
//   1. hold: the arm is held where it stands (the first reading, which must be inside the prior's
//      joint ranges) by the prior's gravity and the PD below, all ramped in from zero over
//      torque_ramp_s, with integral action whose gain is ramped in over the hold: it takes up
//      what the prior's gravity gets wrong (identified before anything moves);
//   2. approach: a minimum-jerk move to the excitation's home pose exc.q0() at most
//      approach_speed_rad_s, then settle_s of hold there (gravity_offset: the integral then);
//   3. the excitation (logged, `duration` [s] of device time), tracked by
//      tau = M qdd_r + C(q, qd) qd + g + tau_f(qd_r) + K_p e + K_d de + K_i int e  (prior's model,
//      K_i = K_p integral_corner, anti-windup: no integration into a clamped command);
//   4. a clean stop: the excitation faded out over fade_out_s, a hold, the torque ramped down to
//      zero over stop_ramp_s (not logged).
// Every command is clamped to torque_fraction x the device's tau_max (never near its fault
// threshold). Late ticks are ridden through: the reference advances by the measured tick but at
// most max_reference_step_s per tick (a stalled loop does not make the reference jump ahead).
// Velocity guard: while a joint's low-passed speed exceeds velocity_guard x the excitation's
// qd_max, or a command is clamped, the excitation's time scale backs off (down to
// min_time_scale; the path, inside the joint limits, is unchanged) and recovers afterwards. The
// run stops, zero torque at once, the log kept and marked incomplete, on: a device fault, a
// non-finite sample, a joint beyond velocity_stop x qd_max during the excitation (before it, an
// arm that moves while the torque ramps in is held by the PD), or outside the prior's joint range
// (by more than range_tolerance_rad), or the stop request (then through the clean stop).
struct GuardedExcitationParams {
  double torque_ramp_s = 1.0;
  double hold_s = 2.0;
  double approach_speed_rad_s = 0.25;
  double settle_s = 1.0;
  double fade_out_s = 1.0, stop_hold_s = 0.25, stop_ramp_s = 0.5;
  double integral_corner = 0.1;  // K_i = K_p x integral_corner x w_c
  double torque_fraction = 1.0;
  double velocity_guard = 1.5, velocity_stop = 3.0;
  double guard_lowpass_hz = 20.0;  // of |qd| for the guard (encoder quantisation)
  double min_time_scale = 0.2;
  double time_scale_down_per_s = 2.0, time_scale_up_per_s = 0.25;
  double max_reference_step_s = 5e-3;
  double range_tolerance_rad = 0.05;
};
ExcitationOutcome run_guarded_excitation(Device& device, const PhantomParams& prior,
                                         const Excitation& exc, double duration,
                                         const GuardedExcitationParams& g = {},
                                         const TrackingParams& tracking = {},
                                         const std::atomic<bool>* stop_request = nullptr);

// Noise-free data by inverse dynamics of the model `truth` along the reference trajectory:
// q, qd exact, tau = M qdd + C qd + g + tau_f, sampled every `dt` [s] (no tracking error, no
// quantisation; the test oracle for the fit).
CalibrationLog synthesize_log(const PhantomParams& truth, const Excitation& exc, double duration,
                              double dt);

}  // namespace dentsim
