// Calibration over seeded held-out perturbations of a simulated device (issue #17's bar; issue
// #20's "calibration over many seeds"; `dentsim calibrate-seeds`, docs/calibration.md).
//
// Per seed S:
//   1. truth = the base model with every body's mass and (one factor for all three of its)
//      principal inertias, and each joint's armature, viscous damping and Coulomb friction scaled
//      by a factor drawn uniform in [kSeedFactorMin, kSeedFactorMax] (perturb_device);
//   2. `dentsim excite --device truth --seed S`: the seeded Fourier series designed for
//      identification (design_excitation) on the truth, run under PD tracking with the truth as
//      feed-forward on the simulated Phantom built from the truth (MuJoCo's frictionloss,
//      quantised encoders, the driver's velocity estimate);
//   3. `dentsim calibrate LOG --truth truth` with the calibrate command's defaults (prior = the
//      base model, zero-phase 10 Hz Butterworth, velocity lag `auto`, Coulomb column from the
//      low-passed velocity, with or without the model-mismatch term): calibrate.h calibrate_log;
//   4. each identifiable parameter's error against the truth, and the fitted and prior M(q), arm
//      M(q) block and g(q) against the truth's over 200 seeded poses (calibrate.h
//      compare_with_truth).
// The numbers equal those of the two commands run on the same truth file (the log's CSV re-reads
// exactly). Deterministic: the same seed and options give bit-identical results.
//
// Issue #17's bar per identifiable parameter: relative error <= 5 % or error <= 3 reported std
// (within_bar); per fit: M(q) within 2 % of the truth (kMassMatrixBar).
//
// No MPI here: the CLI spreads the seeds over ranks (cli/mpi_sweep.h).
#pragma once

#include <atomic>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "calibration/calibrate.h"  // ModelError, truth_model_error
#include "calibration/fit.h"
#include "calibration/log.h"
#include "reference/phantom/phantom_params.h"

namespace dentsim {

inline constexpr double kSeedFactorMin = 0.75;
inline constexpr double kSeedFactorMax = 1.35;
// Issue #17's bar.
inline constexpr double kParameterRelBar = 0.05;  // relative error
inline constexpr double kParameterStdBar = 3.0;   // error / reported std
inline constexpr double kMassMatrixBar = 0.02;    // fitted M(q) relative error

// A perturbed device and the factors drawn, in drawing order: for each body of the model file in
// file order (base, upper_arm, forearm, crank, parallel_link, gimbal_yaw, gimbal_pitch,
// gimbal_roll) "BODY.mass_kg" then "BODY.inertia_kg_m2"; then "armature_kg_m2.J",
// "damping_n_m_s_per_rad.J", "coulomb_n_m.J" for J = 1..6 (34 factors). The order and the
// structure are those of scripts/calibration_seeds.py, but the generator is std::mt19937_64
// seeded with S (u = the top 53 bits of one draw / 2^53, factor = min + (max - min) u; spelled out
// rather than std::uniform_real_distribution, whose algorithm the standard leaves to the
// library), not Python's random: the same seed gives different devices here and in the script.
struct PerturbedDevice {
  PhantomParams params;
  std::vector<std::string> factor_names;
  std::vector<double> factors;
};
// Throws InputError if the perturbed model fails validate_phantom_params.
PerturbedDevice perturb_device(const PhantomParams& base, std::uint64_t seed);

// The options that matter of `dentsim excite` and `dentsim calibrate` (their defaults).
struct SeedRunOptions {
  double duration_s = 20.0;         // excite --duration (the CLI defaults it to 20, as the script)
  int design_iterations = 40;       // excite --design-iterations
  double lowpass_hz = 10.0;         // calibrate --lowpass
  int max_samples = 3000;           // calibrate --max-samples
  int max_iterations = 100;         // calibrate --max-iterations
  bool model_mismatch_term = true;  // calibrate without --no-model-mismatch
  bool law_mismatch_term = true;    // calibrate without --no-law-mismatch
  double min_speed = 0.2;           // calibrate --min-speed [rad/s]
  std::string coulomb_smoothing = "fit";  // calibrate --coulomb-smoothing
  std::string coulomb_sign = "prior";     // calibrate --coulomb-sign
  // Optional stop request (the CLI's SIGINT / SIGTERM flag, cli/interrupt.h): once set, the
  // excitation in progress stops at its next tick and run_seed throws SeedInterrupted (the seed
  // has no result; the fit, once started, runs to its end).
  const std::atomic<bool>* stop_request = nullptr;
};

// One fitted parameter against the truth (fields as in `dentsim calibrate --truth`'s JSON; the
// errors are 0 for a parameter that is not identifiable, which the bar does not check).
struct SeedParameter {
  std::string name;
  bool identifiable = false;
  double truth = 0.0, value = 0.0, std = 0.0, std_statistical = 0.0, std_model = 0.0;
  double std_law = 0.0;
  double rel_error = 0.0;       // |value - truth| / |truth|
  double error_over_std = 0.0;  // |value - truth| / std (infinity when std = 0)
  bool operator==(const SeedParameter&) const = default;
};
// Issue #17's bar for one parameter: rel_error <= 5 % or error_over_std <= 3.
bool within_bar(const SeedParameter& p);
// "coulomb_n_m.4", ".5", ".6": the gimbal joints' Coulomb friction (the known friction-law
// mismatch, docs/calibration.md).
bool is_gimbal_coulomb(const std::string& name);

struct SeedResult {
  std::uint64_t seed = 0;
  bool converged = false;
  int identifiable = 0;
  double condition_number = 0.0;  // the fit's
  double residual_rms_n_m = 0.0;
  double excitation_condition_seeded = 0.0, excitation_condition_designed = 0.0;
  bool model_mismatch = false;
  std::vector<std::string> model_mismatch_reasons;
  std::vector<SeedParameter> params;  // all kCalibParams, in calib_param_names() order
  ModelError fitted, prior;           // against the truth
  bool operator==(const SeedResult&) const = default;

  int checked() const;  // identifiable parameters
  // The identifiable parameters outside the bar (both beyond 5 % and beyond 3 std).
  std::vector<SeedParameter> outside() const;
};

// Everything one seed produced (the CLI writes the truth, the log and the fitted model to --out).
struct SeedRun {
  SeedResult result;
  PhantomParams truth, fitted;
  CalibrationLog log;
};
// Thrown by run_seed when options.stop_request stopped the seed's excitation.
struct SeedInterrupted : std::runtime_error {
  using std::runtime_error::runtime_error;
};
// Steps 1-4 above for `seed`, base model `base`. Throws InputError on bad options (a log too short
// for the low-pass), std::runtime_error when the fit ends non-finite, SeedInterrupted on a stop
// request.
SeedRun run_seed(const PhantomParams& base, std::uint64_t seed, const SeedRunOptions& options);

struct SeedSummary {
  int fits = 0, converged = 0;
  int checked = 0;                                         // identifiable parameters over all fits
  int outside = 0;                                         // of those, outside both 5 % and 3 std
  int outside_gimbal_coulomb = 0;                          // of those, gimbal Coulomb friction
  double mass_matrix_median = 0.0, mass_matrix_max = 0.0;  // fitted M(q) error
  int mass_matrix_within_bar = 0;                          // fits with M(q) within 2 %
  double gimbal_mass_matrix_max = 0.0;                     // worst fitted gimbal-block error
  int model_mismatch_flagged = 0;
  // Whether the reported std is the right size: |value - truth| / std over the checked parameters
  // (RMS over the finite ones; an error with std = 0 counts as beyond every bound). A std that
  // fits the errors gives RMS near 1 and about 32 / 5 / 0.3 % beyond 1 / 2 / 3 std for Gaussian
  // errors; RMS well below 1 is a std wider than the errors need.
  double error_over_std_rms = 0.0;
  int beyond_1_std = 0, beyond_2_std = 0, beyond_3_std = 0;
  bool operator==(const SeedSummary&) const = default;
};
// The median is the mean of the two middle values for an even count.
SeedSummary summarize(const std::vector<SeedResult>& results);

// JSON (the per-seed entries and the summary of `dentsim calibrate-seeds --json`); numbers
// round-trip exactly, an infinite error_over_std is written as null.
nlohmann::json seed_result_to_json(const SeedResult& r);
SeedResult seed_result_from_json(const nlohmann::json& j);
nlohmann::json seed_summary_to_json(const SeedSummary& s);

}  // namespace dentsim
