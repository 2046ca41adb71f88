// Run time against error (issue #14, `dentsim bench`): one scene (the built-in drill by default:
// the same scripted hand every run) simulated with one setting varied at a time — the servo rate,
// the tooth's resolution, the device terms in float, the tick's implementation — and each run
// compared with the finest reference run (the reference pipeline at the highest rate and the
// finest tooth).
//
// Per variant:
// - tick_us_median / tick_us_p99: wall-clock time of the servo tick (the pipeline's stages and
//   drilling; the simulated device's physics excluded) [us];
// - servo_tick_us_median / servo_tick_us_p99: the servo's own tick, without what its publish did
//   in the field edit worker's stead (the takeovers and waits of a simulated run, report.json
//   timing_us servo_tick; sim/simulator.h): the tick a real-time servo runs. Equal to the tick
//   where nothing was stood in for (another contact model, the reference pipeline);
// - cpu_s_per_simulated_s: the mean tick time times the ticks per simulated second (the servo
//   computation one second of haptics costs);
// - force_rms_error_n / force_max_error_n: the force fed back to the device, T1's force part
//   (world), against the finest run's: both held over their ticks (zero-order hold, what the
//   device holds), averaged over a trailing window of `smooth_s` (10 ms: the force as the hand
//   feels it, below ~100 Hz; the tick-to-tick part is encoder-quantisation noise through the
//   velocity estimate and the observer, which no rate or resolution makes converge), compared
//   on a common grid of `compare_dt_s`: RMS and max of |f - f_finest| [N]. The unsmoothed
//   comparison is reported too (force_rms_error_raw_n, force_max_error_raw_n);
// - removed_volume_error_mm3: |removed volume - the finest run's| [mm^3] (a volume compares
//   across resolutions; a count of voxels would not).
// The drill is a chaotic closed loop once it cuts (docs/results/fast_crosscheck.md): after the
// first voxel whose removal tick differs, two runs follow different trajectories and the
// difference is bounded only by the force rendered. The errors are therefore those of the whole
// user-visible run, not of one tick; docs/results/time_vs_error.md reads them.
#pragma once

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace dentsim {

// One run's settings: every variant is the base with one of these changed.
struct BenchSettings {
  std::string pipeline = "fast";  // fast/registry.h
  double tick_hz = 1000.0;
  int resolution = 128;             // tooth grid (power of two, 32..512)
  bool float_device_terms = false;  // fast::PhantomModelFloat (fast pipeline only)
};

struct TimeVsErrorConfig {
  std::string scene = "drill";  // built-in scene or scene file
  double duration_s = 0.0;      // > 0: instead of the scene's duration
  // Non-empty: every run (the finest too) with the scene's tooth.contact_model set to this ("sdf",
  // "field", "faces"; docs/scenes.md); empty: the scene's own.
  std::string contact_model;
  BenchSettings base;           // the variants vary this one setting at a time
  BenchSettings finest{"reference", 8000.0, 512, false};  // the error's yardstick
  // Names of the variants to run (see time_vs_error_variant_names); empty = all. The finest
  // reference run always runs.
  std::vector<std::string> only;
  double compare_dt_s = 1e-3;  // the common time grid of the force comparison
  double smooth_s = 10e-3;     // trailing-mean window of the compared forces (0 = none)
};

struct BenchVariant {
  std::string name;
  BenchSettings settings;
  long ticks = 0;
  double simulated_s = 0.0;
  double tick_us_median = 0.0, tick_us_p99 = 0.0, tick_us_mean = 0.0;
  double servo_tick_us_median = 0.0, servo_tick_us_p99 = 0.0;
  // The field edit's batches the servo edited itself / waited for (simulation; 0 otherwise).
  long field_edit_servo_takeovers = 0, field_edit_worker_waits = 0;
  double cpu_s_per_simulated_s = 0.0;
  double force_rms_error_n = 0.0, force_max_error_n = 0.0;          // smoothed
  double force_rms_error_raw_n = 0.0, force_max_error_raw_n = 0.0;  // tick by tick
  double removed_volume_mm3 = 0.0;
  double removed_volume_error_mm3 = 0.0;
  double max_force_n = 0.0;  // the largest force fed back (the error's scale) [N]
};

struct TimeVsErrorResult {
  TimeVsErrorConfig config;
  std::string reference_variant;       // the finest run's name
  std::vector<BenchVariant> variants;  // the finest reference run first
};

// The names the variants of `config` would have, in order (for --help and validation).
std::vector<std::string> time_vs_error_variant_names(const TimeVsErrorConfig& config);

// Runs the jobs job(0), ..., job(n - 1) — independent simulations, each returning its run as
// JSON — and returns the n results in index order, on every process that calls it. The default
// runs them here one after the other; `dentsim bench` passes one that spreads them over MPI ranks
// (cli/mpi_sweep.h). Job 0 is the finest run, job k the k-th variant; the errors against the
// finest run are computed from the gathered runs, so they do not depend on where the jobs ran
// (the tick times do: they are wall-clock times of whichever core ran the job).
using BenchJobRunner = std::function<std::vector<nlohmann::json>(
    int n, const std::function<nlohmann::json(int)>& job)>;

// Runs the finest reference run and every variant. progress(done, total, name) before each run
// (from the process that runs it) and progress(total, total, "") at the end. Throws InputError
// for an unknown variant name, a bad setting or a bad scene.
TimeVsErrorResult run_time_vs_error(
    const TimeVsErrorConfig& config,
    const std::function<void(int, int, const std::string&)>& progress = {},
    const BenchJobRunner& runner = {});

// The result as JSON: `variants` (each with `name`, `settings`, `tick_us_median`, `tick_us_p99`,
// `force_rms_error_n`, `force_max_error_n`, `removed_volume_error_mm3`, `servo_tick_us_median`,
// `servo_tick_us_p99`, ...) and
// `reference_variant` (issue #14's contract), and as a Markdown table.
nlohmann::json time_vs_error_json(const TimeVsErrorResult& r);
std::string time_vs_error_table(const TimeVsErrorResult& r);

}  // namespace dentsim
