// `dentsim calibrate LOG` as a library (docs/calibration.md): the command's options and defaults,
// their checks (alone and against the log), the velocity lag 'auto', the fit (fit.h) and the JSON
// report, with --truth the comparison against the true model. One implementation for the command
// (cli/cmd_calibrate.cc: flags, files, plots, printing), the Python binding dentsim.calibrate
// (python/calibration.cc) and `calibrate-seeds` (seeds.h run_seed).
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "calibration/fit.h"
#include "calibration/log.h"
#include "reference/phantom/phantom_params.h"

namespace dentsim {

// The options of `dentsim calibrate`, with its defaults.
struct CalibrateOptions {
  double lowpass_hz = 10.0;  // --lowpass: zero-phase low-pass of qd and tau [Hz], 0 = off
  int lowpass_order = 2;     // --lowpass-order: 1 or 2 (FitOptions::lowpass_order)
  int max_samples = 3000;    // --max-samples: >= 100
  int max_iterations = 100;  // --max-iterations: Ceres iteration limit, >= 1
  // --velocity-lag: 'auto' (the simulated Phantom's driver estimator, driver_velocity_lag_ticks)
  // or the lag d in ticks as text, 0 <= d <= 100. With d > 0, q is taken d ticks and tau
  // d + 1/2 + torque_shift ticks earlier.
  std::string velocity_lag = "auto";
  double torque_shift = 0.0;                  // --torque-shift [ticks], |s| <= 100
  std::string coulomb_velocity = "filtered";  // --coulomb-velocity: 'filtered' or 'raw'
  bool model_mismatch_term = true;            // false: --no-model-mismatch
  bool law_mismatch_term = true;              // false: --no-law-mismatch (FitOptions)
  double min_speed = 0.2;                     // --min-speed [rad/s], 0..10 (FitOptions)
  // --coulomb-smoothing: 'fit' (v_s per joint by profile, FitOptions::fit_coulomb_smoothing) or
  // 'prior' (the prior model's v_s)
  std::string coulomb_smoothing = "fit";
  std::string coulomb_sign = "prior";  // --coulomb-sign: erf, tanh, fit or prior (FitOptions)
  // --allow-incomplete: fit a log marked incomplete (an excitation stopped by a fault or an
  // interruption, CalibrationLog::incomplete); refused by default.
  bool allow_incomplete = false;
};

// What the error messages call each option: the command's flags by default (a binding passes its
// own argument names).
struct CalibrateOptionNames {
  std::string lowpass_hz = "--lowpass";
  std::string lowpass_order = "--lowpass-order";
  std::string max_samples = "--max-samples";
  std::string max_iterations = "--max-iterations";
  std::string velocity_lag = "--velocity-lag";
  std::string torque_shift = "--torque-shift";
  std::string coulomb_velocity = "--coulomb-velocity";
  std::string min_speed = "--min-speed";
  std::string coulomb_smoothing = "--coulomb-smoothing";
  std::string coulomb_sign = "--coulomb-sign";
  std::string allow_incomplete = "--allow-incomplete";
};

// The checks that need no log. Throws InputError "<name>: expected ..., got ...".
void check_calibrate_options(const CalibrateOptions& options,
                             const CalibrateOptionNames& names = {});

struct CalibrateOutcome {
  std::string log_path;  // as given (the report's "log"; named in messages)
  CalibrateOptions options;
  double velocity_lag_ticks = 0.0;  // resolved ('auto': the driver's lag at the log's time step)
  FitOptions fit_options;           // what fit_calibration ran with
  FitResult fit;
  std::string log_incomplete;  // the log's CalibrationLog::incomplete (fitted with the flag)
  // The residual RMS and every parameter value are finite (the command writes nothing otherwise).
  bool finite() const;
};

// The fitted model's name (issue #33: a fitted file must not pass for its prior):
// "<prior name> (fitted from LOG on YYYY-MM-DD)". The model file's `name` is free text, so the
// format is unchanged and older readers read it.
std::string fitted_model_name(const std::string& prior_name, const std::string& log_path,
                              const std::string& date);
// Today's date, UTC, as YYYY-MM-DD.
std::string utc_date_today();

// Checks the options (check_calibrate_options), refuses a log marked incomplete unless
// options.allow_incomplete (InputError naming the log, the reason and the flag), then the low-pass against the log `log_path`
// (below 0.45 / time step, and at least 4 / duration, so that the filter's transient does not
// cover the log; InputError naming the option and the log), resolves the velocity lag and runs
// fit_calibration from `prior`; the fitted model is named by fitted_model_name (today). A fit that did not converge or ended non-finite is returned as it
// is (CalibrateOutcome::finite, FitResult::converged).
CalibrateOutcome calibrate_log(const CalibrationLog& log, const std::string& log_path,
                               const PhantomParams& prior, const CalibrateOptions& options,
                               const CalibrateOptionNames& names = {});

// The max relative error (Frobenius / Euclidean) of `model`'s M(q), its arm 3x3 block and g(q)
// against `truth`'s over `poses` poses drawn uniform in the truth's joint-limit box
// (std::mt19937_64 seeded 1: the poses of `dentsim calibrate --truth`).
struct ModelError {
  double mass_matrix = 0.0, arm_mass_matrix = 0.0, gravity = 0.0;
  // The gimbal's 3x3 block (joints 4-6): a few 1e-6 kg m^2 next to the arm's 1e-3, so the whole
  // matrix's relative error does not see it (a nearly singular gimbal block reads as 0 % there).
  double gimbal_mass_matrix = 0.0;
  bool operator==(const ModelError&) const = default;
};
ModelError truth_model_error(const PhantomParams& truth, const PhantomParams& model,
                             int poses = 200);
// {"mass_matrix", "arm_mass_matrix", "gimbal_mass_matrix", "gravity"} (the report's
// truth_model_error entries).
nlohmann::json model_error_to_json(const ModelError& e);

// A fit against the true model (`dentsim calibrate --truth`).
struct ParameterTruth {
  double truth = 0.0;  // the true value (every parameter)
  // Identifiable parameters only (0 otherwise): |value - truth| / |truth|, and |value - truth| /
  // std (infinity when std = 0).
  double rel_error = 0.0, error_over_std = 0.0;
};
struct TruthComparison {
  std::vector<ParameterTruth> params;  // kCalibParams, in FitResult::params order
  double max_rel_error = 0.0;          // over the identifiable parameters
  ModelError fitted, prior;            // truth_model_error of the fitted model and of the prior
};
TruthComparison compare_with_truth(const FitResult& fit, const PhantomParams& prior,
                                   const PhantomParams& truth);

// The report `dentsim calibrate --json` writes (docs/calibration.md): log, converged,
// solver_report, ..., parameters [name, prior, value, std, std_statistical, std_model, std_white,
// identifiable], model_mismatch..., residual_diagnostics, not_identifiable_left_at_prior (the
// parameters not identifiable whose value is the prior's, within kLeftAtPriorRelTol),
// not_identifiable_moved (the others: name, prior, value, why), log_incomplete; with a
// truth comparison also each identifiable parameter's truth, rel_error and error_over_std,
// max_rel_error and truth_model_error.
inline constexpr double kLeftAtPriorRelTol = 1e-6;
nlohmann::json calibration_report_json(const CalibrateOutcome& outcome,
                                       const TruthComparison* truth = nullptr);

}  // namespace dentsim
