// `dentsim zwidth`: the Z-width experiment of issue #7 (thesis §4.2, Fig. 4.9-4.11), protocol in
// docs/zwidth_protocol.md. The experiment (grids, operators, bounds, ratios, sensitivity) is
// validation/zwidth_experiment.h; this file turns the flags into a ZwidthExperiment, runs it,
// prints the table, writes the JSON (--json) and draws the figures (--out).
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "cli/interrupt.h"
#include "cli/mpi_sweep.h"
#include "cli/outputs.h"
#include "cli/plot.h"
#include "cli/progress.h"
#include "cli/registry.h"
#include "fast/registry.h"
#include "reference/core/io.h"
#include "reference/phantom/phantom_params.h"
#include "validation/zwidth_experiment.h"

namespace dentsim::cli {
namespace {

struct ZwidthOptions {
  std::string json;
  std::string out;
  bool quick = false;
  std::vector<std::string> methods = {"explicit", "pmi", "pmi-pd"};
  std::vector<std::string> operators = {"force", "grip", "tap", "release"};
  std::string testbed = "phantom";
  std::string pipeline = "fast";
  int threads = 0;
  double hold_s = 5.0;
  double tick_ms = 1.0;
  double push_n = 1.5;
  bool sensitivity = false;
  std::vector<double> k_vc, b_vc, k_tooth;  // grid overrides (every operator)
  double observer_gain = ZwidthScenario{}.observer_gain;
  bool observer_unmatched = false;
  double grasp_mass = 0.0;
  bool grip_detector = false;
  bool encoder_kalman = false;    // --encoder-kalman: method.encoder_kalman on every run
  bool lag_compensation = false;  // --lag-compensation: method.lag_compensation on every run
  // --encoder-kalman-friction-model: method.encoder_kalman_friction_model on every run
  std::string encoder_kalman_friction_model = "smooth";
  std::vector<double> tap_speeds;
  double proxy_damping = -1.0;  // < 0: the rule b_2 = k_vc T / 2
  std::string device_model;     // --device MODEL ("" = the default model)
  std::string pipeline_model;   // --pipeline-model MODEL ("" = the device's)
};

// Category of a point for the stability map.
int category(const ZwidthPoint& p) {
  if (p.stable && p.passive) return 0;
  if (p.stable) return 1;
  if (p.passive) return 2;
  return 3;
}

std::vector<double> to_mm(const std::vector<double>& metres) {
  std::vector<double> out;
  out.reserve(metres.size());
  for (double x : metres) out.push_back(x * 1e3);
  return out;
}

// The grip detector at work (docs/derivations/decomposition_and_observer.md §9): one `release`
// run of PMI + PD at its best point with the hand's mass fixed in the model and one with the
// detector; the penetration of both, and the detector's statistic and state.
void write_grip_detector_plot(const std::string& dir, const ZwidthExperimentResult& r) {
  std::filesystem::create_directories(dir);
  const ZwidthScenario& sc = r.experiment.scenario;
  const ZwidthGains& g = r.grip_trace_gains;
  const ZwidthTrace &tf = r.grip_trace_fixed, &td = r.grip_trace_detector;
  char gains[96];
  std::snprintf(gains, sizeof gains, "(K_vc %g, b_vc %g, K_tooth %g), model hand mass x%g", g.k_vc,
                g.b_vc, g.k_tooth, sc.grasp_mass_scale);
  plot::Figure pen{std::string("pmi-pd, release: device penetration ") + gains,
                   "time [s]",
                   "penetration [mm]",
                   {},
                   false,
                   false};
  pen.series.push_back({"hand mass fixed in the model", tf.t, to_mm(tf.penetration_m)});
  pen.series.push_back({"with the grip detector", td.t, to_mm(td.penetration_m)});
  plot::Figure st{"grip detector: statistic s = P1 - P0 and state (1 = gripped)",
                  "time [s]",
                  "s [N^2/kg] / state",
                  {},
                  false,
                  false};
  std::vector<double> state;
  for (int v : td.grip_state) state.push_back(v);
  st.series.push_back({"s", td.t, td.grip_statistic});
  st.series.push_back({"state", td.t, state});
  const double t_end = td.t.empty() ? 1.0 : td.t.back();
  st.series.push_back(
      {"release threshold",
       {0.0, t_end},
       {sc.grip_detector_params.release_threshold, sc.grip_detector_params.release_threshold},
       false,
       -1,
       true});
  plot::write_png({pen, st}, dir + "/grip_detector.png", 1, 900, 320);
}

void write_plots(const std::string& dir, const ZwidthExperimentResult& r) {
  std::filesystem::create_directories(dir);
  // Fig. 4.9-4.10: force vs penetration at each method's best point (force operator).
  std::vector<plot::Figure> fp, ft;
  for (const ZwidthMethodResult& mr : r.methods) {
    const ZwidthSweep& s = mr.headline_sweep();
    if (s.best < 0) continue;
    const ZwidthTrace& tr = mr.trace;
    const ZwidthGains g = s.points[s.best].gains;
    plot::Figure f{std::string(method_name(s.method)) + ": force vs penetration (K_vc " +
                       std::to_string(static_cast<int>(g.k_vc)) + ", b_vc " +
                       std::to_string(g.b_vc).substr(0, 4) + ", K_tooth " +
                       std::to_string(static_cast<int>(g.k_tooth)) + ")",
                   "device penetration [mm]",
                   "force fed back [N]",
                   {},
                   false,
                   false};
    plot::Series ser{"measured", to_mm(tr.penetration_m), tr.force_n};
    f.series.push_back(ser);
    const double z = s.z_width_n_per_m();
    const double pmax = *std::max_element(tr.penetration_m.begin(), tr.penetration_m.end());
    f.series.push_back({"Z-width line", {0.0, pmax * 1e3}, {0.0, z * pmax}, false, -1, true});
    fp.push_back(f);
    plot::Figure t{std::string(method_name(s.method)) + ": force and penetration over time",
                   "time [s]",
                   "force [N] / penetration [mm]",
                   {},
                   false,
                   false};
    t.series.push_back({"force [N]", tr.t, tr.force_n});
    t.series.push_back({"penetration [mm]", tr.t, to_mm(tr.penetration_m)});
    ft.push_back(t);
  }
  if (!fp.empty()) plot::write_png(fp, dir + "/force_vs_penetration.png", 1, 900, 360);
  if (!ft.empty()) plot::write_png(ft, dir + "/time_series.png", 1, 900, 300);
  // Stability maps: one panel per method and b_vc (k_tooth across, k_vc up).
  const ZwidthGrid& grid = r.headline_grid();
  std::vector<plot::CategoryMap> maps;
  const std::size_t nt = grid.k_tooth.size(), nk = grid.k_vc.size();
  for (const ZwidthMethodResult& mr : r.methods) {
    const ZwidthSweep& s = mr.headline_sweep();
    for (std::size_t ib = 0; ib < grid.b_vc.size(); ++ib) {
      plot::CategoryMap m;
      m.title = std::string(method_name(s.method)) +
                ", b_vc = " + std::to_string(grid.b_vc[ib]).substr(0, 4) + " N s/m";
      m.xlabel = "K_tooth [N/m]";
      m.ylabel = "K_vc [N/m]";
      m.xs = grid.k_tooth;
      m.ys = grid.k_vc;
      m.category_names = {"stable+passive", "stable, active", "unstable, passive",
                          "unstable+active"};
      m.category_colors = {2, 1, 4, 3};
      for (std::size_t ik = 0; ik < nk; ++ik) {
        for (std::size_t it = 0; it < nt; ++it) {
          m.cells.push_back(category(s.points[it + nt * (ik + nk * ib)]));
        }
      }
      maps.push_back(m);
    }
  }
  if (!maps.empty()) {
    plot::write_png(maps, dir + "/stability_map.png", static_cast<int>(grid.b_vc.size()), 360, 340);
  }
  // Fig. 4.11: summary bars.
  plot::BarChart b;
  b.title = "Z-width per method (thesis vs measured per operator)";
  b.ylabel = "Z-width [N/m]";
  for (const ZwidthMethodResult& mr : r.methods) b.labels.push_back(method_name(mr.method));
  b.set_names.push_back("thesis");
  std::vector<double> th;
  for (const ZwidthMethodResult& mr : r.methods) th.push_back(mr.thesis_z_width_n_per_m);
  b.values.push_back(th);
  const std::vector<ZwidthOperator>& ops = r.experiment.operators;
  for (std::size_t k = 0; k < ops.size(); ++k) {
    b.set_names.push_back(operator_name(ops[k]));
    std::vector<double> values;
    for (const ZwidthMethodResult& mr : r.methods) values.push_back(mr.sweeps[k].z_width_n_per_m());
    b.values.push_back(values);
  }
  plot::write_png(b, dir + "/summary.png");
}

// "(K_vc, b_vc, K_tooth)" of point i of a sweep, "-" for none (i < 0).
std::string point_gains(const ZwidthSweep& s, int i) {
  if (i < 0) return "-";
  const ZwidthGains& g = s.points[i].gains;
  char gains[64];
  std::snprintf(gains, sizeof gains, "(%g, %g, %g)", g.k_vc, g.b_vc, g.k_tooth);
  return gains;
}

// The table on stdout: each method's headline Z-width beside the thesis's, per operator, the
// bounds, the ratios and the sensitivity.
void print_summary(const ZwidthExperimentResult& r) {
  const ZwidthScenario& sc = r.experiment.scenario;
  const std::vector<ZwidthOperator>& ops = r.experiment.operators;
  std::printf(
      "testbed %s, %s pipeline, T = %.3g ms, device damping at the tip b_d = %.4g N s/m, tip "
      "encoder quantum %.3g mm\n",
      testbed_name(sc.testbed), sc.pipeline.c_str(), sc.tick * 1e3, r.device_tip_damping_n_s_per_m,
      r.device_tip_quantum_m * 1e3);
  std::printf("%-8s %10s %24s", "method", "thesis", "Z-width [N/m] (gains)");
  for (ZwidthOperator op : ops) std::printf(" %9s", operator_name(op));
  std::printf(" %12s %12s\n", "CS bound", "PMI bound");
  for (const ZwidthMethodResult& mr : r.methods) {
    const ZwidthSweep& s = mr.headline_sweep();
    std::printf("%-8s %10.0f %9.1f %14s", method_name(mr.method), mr.thesis_z_width_n_per_m,
                mr.z_width_n_per_m(), point_gains(s, s.best).c_str());
    for (const ZwidthSweep& sw : mr.sweeps) std::printf(" %9.1f", sw.z_width_n_per_m());
    std::printf(" %12.1f %12.1f\n", mr.colgate_schenkel_max_stiffness_n_per_m,
                mr.pmi_coupling_bound_n_per_m);
  }
  // A ratio that is not a number says why (zwidth_ratio_reason), never a bare nan.
  auto ratio = [&r](double x, Method m) {
    char b[32];
    std::snprintf(b, sizeof b, "%.2f", x);
    return std::isfinite(x) ? std::string(b) : "n/a (" + zwidth_ratio_reason(r, m) + ")";
  };
  std::printf("ratio pmi/explicit %s (thesis 1.8), pmi-pd/explicit %s (thesis 9.5)\n",
              ratio(r.ratio_pmi_over_explicit, Method::kPmiVc).c_str(),
              ratio(r.ratio_pmipd_over_explicit, Method::kPmiPd).c_str());
  // The quiet Z-width (issue #29): over points that are stable, passive and quiet (force ripple
  // <= 5 % of the contact force and of the force fed back, contact on every tick, no loss).
  std::printf(
      "\nquiet Z-width (stable, passive and quiet: ripple <= %.0f %%, contact on every "
      "tick, no contact loss):\n",
      100.0 * sc.quiet.ripple_max);
  std::printf("%-8s %24s", "method", "quiet Z-width (gains)");
  for (ZwidthOperator op : ops) std::printf(" %9s", operator_name(op));
  std::printf("\n");
  for (const ZwidthMethodResult& mr : r.methods) {
    const ZwidthSweep& s = mr.headline_sweep();
    std::printf("%-8s %9.1f %14s", method_name(mr.method), mr.quiet_z_width_n_per_m(),
                point_gains(s, s.best_quiet).c_str());
    for (const ZwidthSweep& sw : mr.sweeps) std::printf(" %9.1f", sw.quiet_z_width_n_per_m());
    std::printf("\n");
  }
  // A quiet ratio over a method with no quiet point is not a number: printed as n/a.
  auto quiet_ratio = [](double x) {
    char b[32];
    std::snprintf(b, sizeof b, "%.2f", x);
    return std::isfinite(x) ? std::string(b) : std::string("n/a (no quiet point)");
  };
  std::printf("quiet ratios: pmi/explicit %s, pmi-pd/explicit %s",
              quiet_ratio(r.quiet_ratio_pmi_over_explicit).c_str(),
              quiet_ratio(r.quiet_ratio_pmipd_over_explicit).c_str());
  const ZwidthMethodResult* ex = nullptr;
  const ZwidthMethodResult* pd = nullptr;
  for (const ZwidthMethodResult& mr : r.methods) {
    if (mr.method == Method::kExplicitVc) ex = &mr;
    if (mr.method == Method::kPmiPd) pd = &mr;
  }
  if (ex != nullptr && pd != nullptr) {
    std::printf("; pmi-pd/explicit per operator:");
    for (std::size_t k = 0; k < ops.size(); ++k) {
      const double z = ex->sweeps[k].quiet_z_width_n_per_m();
      std::printf(" %s %s", operator_name(ops[k]),
                  quiet_ratio(z > 0.0 && pd->sweeps[k].quiet_z_width_n_per_m() > 0.0
                                  ? pd->sweeps[k].quiet_z_width_n_per_m() / z
                                  : std::nan(""))
                      .c_str());
    }
  }
  std::printf("\n");
  if (!r.experiment.sensitivity) return;
  std::printf("\nsensitivity at each method's best point (force operator unless noted):\n");
  for (const ZwidthMethodResult& mr : r.methods) {
    for (const ZwidthSensitivityResult& v : mr.sensitivity) {
      std::printf("  %-8s %-28s stable %d passive %d Z-width %8.1f N/m\n", method_name(mr.method),
                  v.variant.c_str(), v.point.stable, v.point.passive, v.point.z_width_n_per_m);
    }
  }
}

void run_zwidth(const ZwidthOptions& o) {
  if (!(o.hold_s >= 5.0))
    throw InputError("--hold: expected >= 5 s of contact, got " + std::to_string(o.hold_s));
  if (!(o.tick_ms > 0.0 && o.tick_ms <= 10.0)) {
    throw InputError("--tick-ms: expected a tick in (0, 10] ms, got " + std::to_string(o.tick_ms));
  }
  if (!(o.push_n > 0.0 && o.push_n <= 20.0)) {
    throw InputError("--push: expected a force in (0, 20] N, got " + std::to_string(o.push_n));
  }
  check_outputs({{"--json", o.json}}, {{"--out", o.out}});
  ZwidthExperiment e;
  e.methods.clear();
  for (const std::string& m : o.methods) {
    try {
      e.methods.push_back(parse_method(m));
    } catch (const std::exception&) {
      throw InputError("--methods: expected explicit, pmi or pmi-pd, got '" + m + "'");
    }
  }
  e.operators.clear();
  for (const std::string& s : o.operators) e.operators.push_back(parse_operator(s));
  if (e.methods.empty() || e.operators.empty()) {
    throw InputError("--methods/--operators: empty list");
  }

  ZwidthScenario& sc = e.scenario;
  sc.testbed = parse_testbed(o.testbed);
  if (find_stage_table(o.pipeline) == nullptr) {
    throw InputError("--pipeline '" + o.pipeline + "': expected one of " + stage_table_names());
  }
  sc.pipeline = o.pipeline;
  sc.tick = o.tick_ms * 1e-3;
  sc.hold_s = o.hold_s;
  if (!o.tap_speeds.empty()) {
    for (double v : o.tap_speeds) {
      if (!(v > 0.0) || !std::isfinite(v) || v > 2.0) {
        throw InputError("--tap-speeds: expected approach speeds in (0, 2] m/s, got " +
                         std::to_string(v));
      }
    }
    sc.tap_speeds_m_s = o.tap_speeds;
  }
  sc.push_force_n = o.push_n;
  if (!(o.observer_gain > 0.0) || !(o.observer_gain * sc.tick < 1.0)) {
    throw InputError("--observer-gain: expected L > 0 with L T < 1 (T = " +
                     std::to_string(sc.tick) + " s), got " + std::to_string(o.observer_gain));
  }
  sc.observer_gain = o.observer_gain;
  sc.observer_input_matched = !o.observer_unmatched;
  if (!(o.grasp_mass >= 0.0) || !std::isfinite(o.grasp_mass)) {
    throw InputError("--grasp-mass: expected a finite scale >= 0, got " +
                     std::to_string(o.grasp_mass));
  }
  sc.grasp_mass_scale = o.grasp_mass;
  if (o.grip_detector && !(o.grasp_mass > 0.0)) {
    throw InputError("--grip-detector: needs --grasp-mass > 0 (the mass it switches)");
  }
  sc.grip_detector = o.grip_detector;
  sc.encoder_kalman = o.encoder_kalman;
  const std::string& fm = o.encoder_kalman_friction_model;
  if (fm != "smooth" && fm != "none" && fm != "stick_slip") {
    throw InputError("--encoder-kalman-friction-model: expected smooth, none or stick_slip, got '" +
                     fm + "'");
  }
  sc.encoder_kalman_friction = fm != "none";
  sc.encoder_kalman_stick_slip = fm == "stick_slip";
  sc.lag_compensation = o.lag_compensation;
  if (o.proxy_damping >= 0.0) {
    if (!std::isfinite(o.proxy_damping))
      throw InputError("--proxy-damping: expected a finite value");
    sc.proxy_damping_rule = false;
    sc.proxy.damping_lin = o.proxy_damping;
  }
  e.threads = o.threads > 0 ? o.threads
                            : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  if (o.quick) e.grid = e.other_grid = zwidth_quick_grid();
  for (const auto* v : {&o.k_vc, &o.b_vc, &o.k_tooth}) {
    for (double x : *v) {
      if (!(x >= 0.0) || !std::isfinite(x)) {
        throw InputError("--k-vc/--b-vc/--k-tooth: expected finite values >= 0, got " +
                         std::to_string(x));
      }
    }
  }
  if (!o.k_vc.empty()) e.grid.k_vc = e.other_grid.k_vc = o.k_vc;
  if (!o.b_vc.empty()) e.grid.b_vc = e.other_grid.b_vc = o.b_vc;
  if (!o.k_tooth.empty()) e.grid.k_tooth = e.other_grid.k_tooth = o.k_tooth;
  e.sensitivity = o.sensitivity;
  e.traces = !o.out.empty();

  // The jobs go through cli/mpi_sweep.h: under mpirun each rank runs its share of the grid points
  // (and of the re-runs at the best points) on its --threads workers, and every rank gets every
  // result (the re-runs are enumerated from the grid's); alone, this process runs them all as
  // before. Progress (cli/progress.h: a bar on a terminal, lines with the time left in a log):
  // the grid stage per operator alone; rank 0's share of each stage under mpirun.
  const bool alone = sweep_world().size == 1;
  // Ctrl-C / SIGTERM: no new job starts (the running ones finish), the jobs done so far go to
  // --json marked partial, exit 130 / 143 (cli/interrupt.h).
  const StopOnSignal stop;
  StoppableJobs jobs(stop);
  ProgressBar bar("zwidth", writes_outputs());
  const ZwidthJobRunner runner = [&](const std::string& stage, int n,
                                     const std::function<nlohmann::json(int)>& job) {
    SweepOptions so;
    so.threads = e.threads;
    so.results_on_every_rank = true;
    return sweep(
        n, jobs.wrap(stage, job),
        [&stage, &bar, alone](int done, int owned) {
          if (!alone) {
            bar.update(
                owned > 0 ? static_cast<double>(done) / owned : 1.0,
                "rank 0 " + stage + " " + std::to_string(done) + "/" + std::to_string(owned));
          }
        },
        so);
  };
  if (!o.device_model.empty() || !o.pipeline_model.empty()) {
    if (sc.testbed != ZwidthTestbed::kPhantom) {
      throw InputError("--device/--pipeline-model: device model files need --testbed phantom");
    }
    if (!o.device_model.empty()) sc.phantom_device_params = load_phantom_params(o.device_model);
    if (!o.pipeline_model.empty())
      sc.phantom_pipeline_params = load_phantom_params(o.pipeline_model);
  }
  // Up front: how much work this is (the bar's lines then give the time left).
  std::size_t grid_runs = 0;
  for (ZwidthOperator op : e.operators) {
    grid_runs += e.methods.size() * (op == ZwidthOperator::kForce ? e.grid : e.other_grid).size();
  }
  if (writes_outputs()) {
    std::fprintf(stderr,
                 "dentsim zwidth: %zu grid runs (%zu methods x %zu operators), each about %.0f s "
                 "of simulated contact at T = %g ms, on %d thread(s) x %d rank(s), then the "
                 "re-runs at each method's best point (%.0f s simulated in the grid alone: "
                 "minutes of work), progress %s\n",
                 grid_runs, e.methods.size(), e.operators.size(), sc.hold_s, o.tick_ms, e.threads,
                 sweep_world().size, static_cast<double>(grid_runs) * sc.hold_s,
                 bar.lines() ? "every 5 s with the time left" : "on the bar below");
  }
  std::vector<int> op_done(e.operators.size(), 0);
  int all_done = 0;
  ZwidthExperimentResult r;
  try {
    r = run_zwidth_experiment(
        e,
        [&](ZwidthOperator op, int done, int total) {
          if (!alone) return;
          ++all_done;
          bar.update(static_cast<double>(all_done) / static_cast<double>(grid_runs),
                     std::string(operator_name(op)) + " " + std::to_string(done) + "/" +
                         std::to_string(total));
        },
        runner);
  } catch (const std::exception&) {
    if (!stop.requested()) throw;
    bar.finish();
    // What it has: every job this rank finished, in the wire format of the sweep.
    throw jobs.stopped("zwidth", o.json, writes_outputs(), {{"grid_runs", grid_runs}});
  }
  bar.finish();
  if (!writes_outputs()) return;  // rank 0 prints and writes
  print_summary(r);
  if (!o.out.empty()) {
    write_plots(o.out, r);
    if (r.has_grip_traces) write_grip_detector_plot(o.out, r);
  }
  if (!o.json.empty()) write_json(o.json, zwidth_experiment_json(r));
}

void setup_zwidth(CLI::App& app) {
  auto o = std::make_shared<ZwidthOptions>();
  CLI::App* sub = app.add_subcommand(
      "zwidth",
      "Z-width experiment (thesis §4.2): sweep K_vc, b_vc, K_tooth per method and operator on the "
      "simulated Phantom; stability and passivity per grid point");
  sub->add_option("--json", o->json, "Write the results as JSON to FILE");
  sub->add_option("--out", o->out, "Write the PNG plots to DIR");
  sub->add_flag("--quick", o->quick, "Short grid (5 K_vc x 2 b_vc x 3 K_tooth)");
  sub->add_option("--methods", o->methods, "Methods: explicit, pmi, pmi-pd")->capture_default_str();
  sub->add_option("--operators", o->operators,
                  "Operators: force, grip, tap, release (force is "
                  "the strictest: the headline Z-width)")
      ->capture_default_str();
  sub->add_option("--testbed", o->testbed, "phantom (simulated Phantom) or axis (1-DoF)")
      ->capture_default_str();
  sub->add_option("--pipeline", o->pipeline,
                  "The tick's implementation: " + stage_table_names() +
                      " (fast evaluates the Phantom through fast::PhantomModel)")
      ->capture_default_str();
  sub->add_option("--threads", o->threads, "Worker threads (0 = all cores)")
      ->capture_default_str()
      ->check(CLI::Range(0, 256));
  sub->add_option("--hold", o->hold_s, "Contact time per run [s]")
      ->capture_default_str()
      ->check(finite_range(5.0, 600.0));
  sub->add_option("--tick-ms", o->tick_ms, "Servo tick [ms]")->capture_default_str();
  sub->add_option("--push", o->push_n, "Operator force [N]")->capture_default_str();
  sub->add_option("--k-vc", o->k_vc, "Override the grid's K_vc values [N/m]");
  sub->add_option("--b-vc", o->b_vc, "Override the grid's b_vc values [N s/m]");
  sub->add_option("--k-tooth", o->k_tooth, "Override the grid's K_tooth values [N/m]");
  sub->add_option("--observer-gain", o->observer_gain, "Observer gain L [1/s] (pmi-pd)")
      ->capture_default_str();
  sub->add_option("--grasp-mass", o->grasp_mass,
                  "The pipeline's model carries SCALE x the hand's mass and inertia at the tip "
                  "(hand operators; 0 = off)")
      ->capture_default_str();
  sub->add_option("--tap-speeds", o->tap_speeds,
                  "Approach speeds of the tap operator [m/s] (default 0.05 0.15 0.3)");
  sub->add_flag("--grip-detector", o->grip_detector,
                "With --grasp-mass: judge tick by tick whether the hand is on the tool and use "
                "its mass only then (reference/grip_detector.h)");
  sub->add_flag("--encoder-kalman", o->encoder_kalman,
                "Every run with the method block's encoder Kalman filter (method.encoder_kalman: "
                "a sub-count estimate of the device state, reference/encoder_kalman.h)");
  sub->add_option("--encoder-kalman-friction-model", o->encoder_kalman_friction_model,
                  "With --encoder-kalman: the friction in its prediction "
                  "(method.encoder_kalman_friction_model): smooth (default), none or stick_slip");
  sub->add_flag("--lag-compensation", o->lag_compensation,
                "Every run with the method block's loop-lag compensation "
                "(method.lag_compensation, reference/lag_compensation.h)");
  sub->add_option("--proxy-damping", o->proxy_damping,
                  "A fixed proxy damping b_2 [N s/m] for every method instead of the rule "
                  "b_2 = K_vc T / 2");
  sub->add_option("--device", o->device_model,
                  "Device model file of the simulated Phantom (default: the built-in model; "
                  "`dentsim device show`)");
  sub->add_option("--pipeline-model", o->pipeline_model,
                  "Device model file the pipeline believes (observer, decomposition; default: "
                  "the device's, e.g. a `dentsim calibrate -o` fit)");
  sub->add_flag("--observer-unmatched", o->observer_unmatched,
                "Observer input as the thesis discretises it, not matched to the driver's "
                "velocity estimate (pmi-pd)");
  sub->add_flag("--sensitivity", o->sensitivity,
                "Re-run each method's best point with hand impedance low/high, tick jitter, "
                "observer gain L, +-20 % model error and 4 kHz");
  sub->callback([o] { run_zwidth(*o); });
}
DENTSIM_REGISTER_COMMAND(setup_zwidth);

}  // namespace
}  // namespace dentsim::cli
