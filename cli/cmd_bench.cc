// `dentsim bench --json FILE --out DIR`: run time against error (issue #14;
// validation/time_vs_error.h). The drill scene's scripted hand with one setting varied at a time
// (servo rate, tooth resolution, float device terms, reference vs fast), each run compared with
// the finest reference run. Writes the JSON (`variants`, `reference_variant`), DIR/pareto.png
// (time against error) and DIR/time_vs_error.md (the table with the command that made it).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "cli/interrupt.h"
#include "cli/mpi_sweep.h"
#include "cli/outputs.h"
#include "cli/plot.h"
#include "cli/progress.h"
#include "cli/registry.h"
#include "reference/core/io.h"
#include "validation/time_vs_error.h"

namespace dentsim::cli {
namespace {

struct Options {
  std::string json;
  std::string out;
  TimeVsErrorConfig config;
  std::vector<std::string> variants;
  double smooth_ms = 10.0;
  bool list = false;
  std::string command_line;  // for the table's header
};

void write_pareto(const TimeVsErrorResult& r, const std::string& path) {
  // The finest run is the yardstick (its error is 0 by construction): not plotted. Errors of
  // exactly 0 (a variant equal to the yardstick up to the compared quantity) sit at a floor.
  constexpr double kFloor = 1e-12;
  plot::Figure rms, vol;
  rms.title = "Run time against force error vs " + r.reference_variant + " (each point a variant)";
  // The servo's own tick (a simulated run's field edit takeovers and waits left out: the worker's
  // work in real time; validation/time_vs_error.h).
  rms.xlabel = vol.xlabel = "servo tick, median [us] (log; the field edit's stand-in left out)";
  rms.ylabel = "force RMS error vs the finest run [N]";
  vol.title = "Run time against removed-volume error vs " + r.reference_variant;
  vol.ylabel = "removed volume error [mm^3]";
  rms.log_y = vol.log_y = rms.log_x = vol.log_x = true;
  for (const BenchVariant& v : r.variants) {
    if (v.name == r.reference_variant) continue;
    plot::Series a;
    a.label = v.name;
    a.points = true;
    a.x = {v.servo_tick_us_median};
    a.y = {std::max(v.force_rms_error_n, kFloor)};
    plot::Series b = a;
    b.y = {std::max(v.removed_volume_error_mm3, kFloor)};
    rms.series.push_back(a);
    vol.series.push_back(b);
  }
  plot::write_png({rms, vol}, path, 1, 900, 420);
}

void run(Options& o) {
  if (o.list) {
    if (!writes_outputs()) return;
    for (const std::string& n : time_vs_error_variant_names(o.config))
      std::printf("%s\n", n.c_str());
    return;
  }
  if (o.out.empty()) throw InputError("--out DIR is required (the plot and the table go there)");
  check_outputs({{"--json", o.json}}, {{"--out", o.out}});
  make_output_dir({"--out", o.out});
  o.config.only = o.variants;
  o.config.smooth_s = 1e-3 * o.smooth_ms;
  // The runs go through cli/mpi_sweep.h: under mpirun each rank simulates its share of them and
  // every rank gets every run back (the errors against the finest run are computed from them);
  // alone, this process runs them one after the other as before. Rank 0 reports the runs it
  // starts; the others stay quiet.
  const bool quiet = !writes_outputs();
  ProgressBar bar("bench", !quiet);
  // Ctrl-C / SIGTERM: no new run starts, the runs done so far go to --json marked partial, exit
  // 130 / 143 (cli/interrupt.h).
  const StopOnSignal stop;
  StoppableJobs jobs(stop);
  TimeVsErrorResult r;
  try {
    r = run_time_vs_error(
        o.config,
        [&bar, quiet](int done, int total, const std::string& name) {
          if (quiet) return;
          // One reporter: the run's line goes through the bar (no collision on a terminal).
          if (!name.empty()) {
            bar.message("bench: run " + std::to_string(done + 1) + "/" + std::to_string(total) +
                        " " + name);
          }
          bar.update(total > 0 ? static_cast<double>(done) / total : 1.0);
        },
        [&](int n, const std::function<nlohmann::json(int)>& job) {
          SweepOptions so;
          so.results_on_every_rank = true;
          return sweep(n, jobs.wrap("runs", job), {}, so);
        });
  } catch (const std::exception&) {
    if (!stop.requested()) throw;
    bar.finish();
    throw jobs.stopped("bench", o.json, !quiet);
  }
  bar.finish();
  if (quiet) return;  // rank 0 prints and writes
  const std::string table = time_vs_error_table(r);
  std::fputs(table.c_str(), stdout);
  if (!o.json.empty()) write_json(o.json, time_vs_error_json(r));
  write_pareto(r, o.out + "/pareto.png");
  write_file_atomic(o.out + "/time_vs_error.md", "Command: `" + o.command_line + "`\n\n" + table);
  std::printf("outputs: %s/pareto.png %s/time_vs_error.md%s%s\n", o.out.c_str(), o.out.c_str(),
              o.json.empty() ? "" : " ", o.json.c_str());
}

void setup_bench(CLI::App& app) {
  auto o = std::make_shared<Options>();
  CLI::App* sub = app.add_subcommand(
      "bench",
      "Run time against error: the drill scene with one setting varied at a time (servo rate,\n"
      "tooth resolution, float device terms, reference vs fast), each run's tick time and its\n"
      "force and removed-volume error against the finest reference run; a Pareto plot");
  sub->add_option("--json", o->json, "Write the numbers to FILE (variants, reference_variant)");
  sub->add_option("--out", o->out,
                  "REQUIRED unless --list: write DIR/pareto.png and DIR/time_vs_error.md");
  sub->add_option("--scene", o->config.scene, "Built-in scene or scene file")
      ->capture_default_str();
  sub->add_option("--contact-model", o->config.contact_model,
                  "Run every variant and the finest run with this tooth contact model (sdf, field, "
                  "faces; default: the scene's)")
      ->check(CLI::IsMember({"sdf", "field", "faces"}));
  sub->add_option("--duration", o->config.duration_s,
                  "Simulate this long instead of the scene's duration [s] (0 = the scene's)")
      ->check(finite_range(0.0, 3600.0));
  sub->add_option("--variants", o->variants,
                  "Run only these variants (names from --list; the finest reference always runs)");
  sub->add_option("--reference-tick-hz", o->config.finest.tick_hz,
                  "Servo rate of the finest reference run [Hz]")
      ->capture_default_str()
      ->check(finite_range(100.0, 20000.0));
  sub->add_option("--reference-resolution", o->config.finest.resolution,
                  "Tooth resolution of the finest reference run (power of two, 32-512)")
      ->capture_default_str();
  sub->add_option("--base-resolution", o->config.base.resolution,
                  "Tooth resolution the variants start from")
      ->capture_default_str();
  sub->add_option("--compare-dt", o->config.compare_dt_s,
                  "Grid on which forces are compared (zero-order hold) [s]")
      ->capture_default_str()
      ->check(finite_range(1e-5, 0.1));
  sub->add_option("--smooth-ms", o->smooth_ms,
                  "Compare forces averaged over this trailing window [ms] (0 = tick by tick)")
      ->capture_default_str()
      ->check(finite_range(0.0, 1000.0));
  sub->add_flag("--list", o->list, "List the variants' names and exit");
  sub->callback([o] {
    // The command as it ran (the table says how to make it again).
    char b[256];
    std::snprintf(b, sizeof(b),
                  " --duration %g --reference-tick-hz %g --reference-resolution %d --smooth-ms %g",
                  o->config.duration_s, o->config.finest.tick_hz, o->config.finest.resolution,
                  o->smooth_ms);
    o->command_line = "dentsim bench --scene " + o->config.scene + b;
    if (!o->config.contact_model.empty()) {
      o->command_line += " --contact-model " + o->config.contact_model;
    }
    if (o->config.base.resolution != BenchSettings{}.resolution) {
      o->command_line += " --base-resolution " + std::to_string(o->config.base.resolution);
    }
    if (!o->variants.empty()) {
      o->command_line += " --variants";
      for (const std::string& v : o->variants) o->command_line += " '" + v + "'";
    }
    o->command_line += " --json FILE --out DIR";
    run(*o);
  });
}
DENTSIM_REGISTER_COMMAND(setup_bench);

}  // namespace
}  // namespace dentsim::cli
