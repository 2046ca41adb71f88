// `dentsim calibrate-seeds` (issues #17 and #20; docs/calibration.md "Calibration over seeded
// held-out devices"):
//
//   dentsim calibrate-seeds --json FILE [--first S] [--count N] [--device MODEL] [--duration T]
//       [--design-iterations K] [--no-model-mismatch] [--lowpass HZ] [--max-samples N]
//       [--max-iterations N] [--out DIR]
//
// For each seed S in [first, first + count): the base model perturbed by seed S, `excite` on the
// simulated device built from it, `calibrate --truth` (calibration/seeds.h, which says exactly
// what runs). Seeds are independent jobs: under `mpirun -n R` they are spread over the R ranks
// (cli/mpi_sweep.h) and rank 0 writes the one JSON, identical to a single process's. Progress (one
// line per seed, from the rank that ran it) on stderr; on stdout a per-seed table and the summary
// row of issue #17's bar. --out DIR keeps per seed DIR/seedS/{truth.json, log.csv, fit.json,
// model.json} (written by the rank that ran the seed: on a cluster DIR must be shared).
// Exit status 1 (after writing everything) if a fit did not converge, as `calibrate`. Ctrl-C /
// SIGTERM: the seeds done so far go to --json marked "partial", exit 130 / 143.
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include "calibration/seeds.h"
#include "cli/interrupt.h"
#include "cli/mpi_sweep.h"
#include "cli/registry.h"
#include "device/phantom_device.h"
#include "reference/core/io.h"
#include "reference/phantom/phantom_params.h"

namespace dentsim::cli {
namespace {

struct SeedsOptions {
  std::uint64_t first = 1;
  int count = 20;
  std::string device, json, out;
  bool no_model_mismatch = false;
  bool no_law_mismatch = false;
  SeedRunOptions run;
};

// Writes one seed's truth, log, result and fitted model under DIR/seedS.
void write_seed_files(const std::string& dir, const SeedRun& run) {
  const std::filesystem::path d =
      std::filesystem::path(dir) / ("seed" + std::to_string(run.result.seed));
  std::filesystem::create_directories(d);
  write_file_atomic((d / "truth.json").string(), phantom_params_to_text(run.truth));
  write_calibration_log((d / "log.csv").string(), run.log);
  write_json((d / "fit.json").string(), seed_result_to_json(run.result));
  // As `calibrate`: no model file from a fit that did not converge or does not validate.
  if (!run.result.converged) return;
  try {
    validate_phantom_params(run.fitted, "fitted model of seed " + std::to_string(run.result.seed));
  } catch (const InputError& e) {
    std::fprintf(stderr, "calibrate-seeds: %s; no model.json written\n", e.what());
    return;
  }
  write_file_atomic((d / "model.json").string(), phantom_params_to_text(run.fitted));
}

std::string percent(double x) {
  char b[32];
  std::snprintf(b, sizeof b, "%.2f %%", 100.0 * x);
  return b;
}

// "name 31 % (7.2 std), ..." or "none".
std::string outside_text(const SeedResult& r) {
  std::string s;
  for (const SeedParameter& p : r.outside()) {
    char b[160];
    std::snprintf(b, sizeof b, "%s%s %.0f %% (%.1f std)", s.empty() ? "" : ", ", p.name.c_str(),
                  100.0 * p.rel_error, p.error_over_std);
    s += b;
  }
  return s.empty() ? "none" : s;
}

void print_tables(const std::vector<SeedResult>& results, const SeedSummary& s,
                  bool model_mismatch_term, bool law_term) {
  std::printf(
      "| seed | converged | identifiable | outside 5 %% and 3 std | fitted M(q) error | fitted "
      "gimbal-block error | prior M(q) error | model_mismatch |\n|---|---|---|---|---|---|---|---|\n");
  for (const SeedResult& r : results) {
    std::printf("| %llu | %s | %d | %s | %s | %s | %s | %s |\n",
                static_cast<unsigned long long>(r.seed), r.converged ? "yes" : "no", r.checked(),
                outside_text(r).c_str(), percent(r.fitted.mass_matrix).c_str(),
                percent(r.fitted.gimbal_mass_matrix).c_str(), percent(r.prior.mass_matrix).c_str(),
                r.model_mismatch ? "yes" : "no");
  }
  std::printf(
      "\n| std reported | fits | identifiable parameters checked | outside 5 %% and 3 std | of "
      "which gimbal Coulomb | fitted M(q) error median / max | M(q) within 2 %% | gimbal-block "
      "error max | model_mismatch flagged |\n|---|---|---|---|---|---|---|---|---|\n");
  std::printf("| %s | %d | %d | %d | %d | %s / %s | %d | %s | %d |\n",
              !model_mismatch_term ? "statistical (Newey-West), without the model-mismatch term"
              : law_term           ? "total, with the model-mismatch and law terms"
                                   : "total, with the model-mismatch term (no law term)",
              s.fits, s.checked, s.outside, s.outside_gimbal_coulomb,
              percent(s.mass_matrix_median).c_str(), percent(s.mass_matrix_max).c_str(),
              s.mass_matrix_within_bar, percent(s.gimbal_mass_matrix_max).c_str(),
              s.model_mismatch_flagged);
  const double n = std::max(1, s.checked);
  std::printf(
      "\nerror / reported std over the %d checks: RMS %.2f; beyond 1 std %d (%.0f %%), beyond 2 "
      "std %d (%.0f %%), beyond 3 std %d (%.1f %%)\n",
      s.checked, s.error_over_std_rms, s.beyond_1_std, 100.0 * s.beyond_1_std / n, s.beyond_2_std,
      100.0 * s.beyond_2_std / n, s.beyond_3_std, 100.0 * s.beyond_3_std / n);
}

void setup_calibrate_seeds(CLI::App& app) {
  auto opt = std::make_shared<SeedsOptions>();
  CLI::App* sub = app.add_subcommand(
      "calibrate-seeds",
      "Calibration over seeded held-out devices (issue #17): per seed, the base device model with\n"
      "every body's mass and inertia and each joint's armature, damping and Coulomb friction\n"
      "scaled by U(0.75, 1.35), excited on the simulated Phantom and fitted as `excite` and\n"
      "`calibrate --truth` do; per-seed and summary errors against the truth. Seeds spread over\n"
      "MPI ranks under mpirun (one JSON, as a single process writes)");
  sub->add_option("--json", opt->json, "report to write (JSON: per-seed entries and the summary)")
      ->required();
  sub->add_option("--first", opt->first, "first seed, 0..2^64-1 (default 1)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--count", opt->count, "number of seeds (default 20)")
      ->check(CLI::Range(1, 100000));
  sub->add_option("--device", opt->device,
                  "base device model file to perturb, also the fit's prior (default: built-in\n"
                  "Premium 1.5A)");
  sub->add_option("--duration", opt->run.duration_s, "excitation length per seed [s] (default 20)")
      ->check(finite_range(1.0, 3600.0));
  sub->add_option("--design-iterations", opt->run.design_iterations,
                  "excite --design-iterations (0: the seeded series as drawn; default 40)")
      ->check(CLI::Range(0, 100000));
  sub->add_flag("--no-model-mismatch", opt->no_model_mismatch,
                "report the statistical std only (calibrate --no-model-mismatch)");
  sub->add_flag("--no-law-mismatch", opt->no_law_mismatch,
                "no law term in the std (calibrate --no-law-mismatch)");
  sub->add_option("--lowpass", opt->run.lowpass_hz,
                  "calibrate --lowpass [Hz] (default 10; 0 = off)")
      ->check(finite_range(0.0, 1e6));
  sub->add_option("--max-samples", opt->run.max_samples, "calibrate --max-samples (default 3000)")
      ->check(CLI::Range(100, 100000000));
  sub->add_option("--max-iterations", opt->run.max_iterations,
                  "calibrate --max-iterations (default 100)")
      ->check(CLI::Range(1, 1000000));
  sub->add_option("--min-speed", opt->run.min_speed,
                  "calibrate --min-speed [rad/s] (default 0.2; 0 = keep every row)")
      ->check(finite_range(0.0, 10.0));
  sub->add_option("--coulomb-smoothing", opt->run.coulomb_smoothing,
                  "calibrate --coulomb-smoothing: 'fit' (default) or 'prior'")
      ->check(CLI::IsMember({"fit", "prior"}));
  sub->add_option("--coulomb-sign", opt->run.coulomb_sign,
                  "calibrate --coulomb-sign: 'erf', 'tanh', 'fit' or 'prior' (default prior)")
      ->check(CLI::IsMember({"erf", "tanh", "fit", "prior"}));
  sub->add_option("--out", opt->out,
                  "directory for each seed's truth.json, log.csv, fit.json and model.json\n"
                  "(DIR/seedS/)");
  sub->callback([opt] {
    if (opt->count > 0 && opt->first > UINT64_MAX - static_cast<std::uint64_t>(opt->count - 1)) {
      throw InputError("--first " + std::to_string(opt->first) + " --count " +
                       std::to_string(opt->count) + ": the last seed would pass 2^64-1");
    }
    check_output_paths({{"--json", opt->json}}, {{"--device", opt->device}});
    if (!opt->out.empty()) {
      // Made before any work, so that an unusable DIR fails now and not after the first seed.
      std::error_code ec;
      std::filesystem::create_directories(opt->out, ec);
      if (ec || !std::filesystem::is_directory(opt->out)) {
        throw InputError("--out " + opt->out + ": cannot create the directory (" +
                         (ec ? ec.message() : "exists and is not a directory") + ")");
      }
    }
    const PhantomParams base =
        opt->device.empty() ? default_phantom_params() : load_phantom_params(opt->device);
    opt->run.model_mismatch_term = !opt->no_model_mismatch;
    opt->run.law_mismatch_term = !opt->no_law_mismatch;
    // The low-pass bounds of `calibrate` (calibration/calibrate.cc), checked before any work: below
    // the Nyquist frequency of the device's tick, and a transient (one cut-off period at each
    // end) shorter than a quarter of the log.
    const double fc = opt->run.lowpass_hz, T = phantom_device_config(base).jitter.period;
    if (fc != 0.0 && !(fc * T <= 0.45)) {
      throw InputError("--lowpass " + std::to_string(fc) + " Hz: above 0.45 / (tick " +
                       std::to_string(T) + " s); expected a cut-off below the Nyquist frequency");
    }
    if (fc != 0.0 && !(fc * (opt->run.duration_s - T) >= 4.0)) {
      throw InputError("--lowpass " + std::to_string(fc) + " Hz with --duration " +
                       std::to_string(opt->run.duration_s) +
                       " s: expected cut-off x duration >= 4 (the filter's transient would cover "
                       "the whole log)");
    }

    // The report's header (what ran), the same in a complete and in an interrupted report.
    nlohmann::json j;
    j["command"] = "calibrate-seeds";
    j["device"] = opt->device.empty() ? "builtin" : opt->device;
    j["first_seed"] = opt->first;
    j["count"] = opt->count;
    j["perturbation"] = {{"factor_min", kSeedFactorMin},
                         {"factor_max", kSeedFactorMax},
                         {"generator", "std::mt19937_64(seed), top 53 bits"}};
    j["options"] = {
        {"duration_s", opt->run.duration_s},
        {"design_iterations", opt->run.design_iterations},
        {"model_mismatch_term", opt->run.model_mismatch_term},
        {"law_mismatch_term", opt->run.model_mismatch_term && opt->run.law_mismatch_term},
        {"min_speed_rad_s", opt->run.min_speed},
        {"coulomb_smoothing", opt->run.coulomb_smoothing},
        {"coulomb_sign", opt->run.coulomb_sign},
        {"lowpass_hz", opt->run.lowpass_hz},
        {"max_samples", opt->run.max_samples},
        {"max_iterations", opt->run.max_iterations}};

    // Ctrl-C / SIGTERM (cli/interrupt.h): the seed in progress stops in its excitation (a fit
    // already started runs to its end), no new seed starts, the seeds done so far go to --json
    // marked partial (their "seeds" entries, the summary over them and "completed_jobs"), exit
    // 130 / 143. Their --out files are written as each seed ends.
    const StopOnSignal stop;
    StoppableJobs jobs(stop);
    opt->run.stop_request = &stop.flag();
    const auto start = std::chrono::steady_clock::now();
    const SweepWorld& world = sweep_world();
    std::vector<nlohmann::json> done_here;  // this rank's finished seeds (the jobs run in order)
    std::vector<nlohmann::json> gathered;
    try {
      gathered = sweep(
        opt->count,
        jobs.wrap("seeds", [&](int i) -> nlohmann::json {
          const std::uint64_t seed = opt->first + static_cast<std::uint64_t>(i);
          std::fprintf(
              stderr, "calibrate-seeds: seed %llu: excite %.0f s, fit...%s\n",
              static_cast<unsigned long long>(seed), opt->run.duration_s,
              world.size > 1 ? (" (rank " + std::to_string(world.rank) + ")").c_str() : "");
          const SeedRun run = run_seed(base, seed, opt->run);
          if (!opt->out.empty()) write_seed_files(opt->out, run);
          const SeedResult& r = run.result;
          std::fprintf(stderr,
                       "calibrate-seeds: seed %llu: %d identifiable, M(q) error %s, outside 5 %% "
                       "and 3 std: %s\n",
                       static_cast<unsigned long long>(seed), r.checked(),
                       percent(r.fitted.mass_matrix).c_str(), outside_text(r).c_str());
          done_here.push_back(seed_result_to_json(r));
          return done_here.back();
        }),
        [&](int done, int n) {
          std::fprintf(
              stderr, "calibrate-seeds: %d of %d seeds done here, %.0f s elapsed\n", done, n,
              std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
        });
    } catch (const std::exception&) {
      if (!stop.requested()) throw;
      // What it has: the seeds this rank finished, as a complete report would list them.
      std::vector<SeedResult> finished;
      for (const nlohmann::json& e : done_here) finished.push_back(seed_result_from_json(e));
      j["seeds"] = done_here;
      j["summary"] = seed_summary_to_json(summarize(finished));
      throw jobs.stopped("calibrate-seeds", opt->json, writes_outputs(), j);
    }
    if (!writes_outputs()) return;

    std::vector<SeedResult> results;
    nlohmann::json seeds = nlohmann::json::array();
    for (const nlohmann::json& e : gathered) {
      results.push_back(seed_result_from_json(e));
      seeds.push_back(e);
    }
    const SeedSummary s = summarize(results);
    j["seeds"] = seeds;
    j["summary"] = seed_summary_to_json(s);
    write_json(opt->json, j);
    print_tables(results, s, opt->run.model_mismatch_term, opt->run.law_mismatch_term);
    if (s.converged < s.fits) {
      std::string which;
      for (const SeedResult& r : results)
        if (!r.converged) which += (which.empty() ? "" : ", ") + std::to_string(r.seed);
      throw std::runtime_error("calibrate-seeds: the fit of seed(s) " + which +
                               " did not converge; see " + opt->json);
    }
  });
}
DENTSIM_REGISTER_COMMAND(setup_calibrate_seeds);

}  // namespace
}  // namespace dentsim::cli
