// `dentsim zwidth`: the Z-width experiment of issue #7 (thesis §4.2, Fig. 4.9-4.11), protocol in
// docs/zwidth_protocol.md, implementation in validation/zwidth.h. Sweeps K_vc, b_vc and K_tooth
// for each method under each operator on the simulated Phantom (or the 1-DoF axis testbed),
// writes the verdict of every grid point to --json and the figures to --out.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "cli/plot.h"
#include "cli/registry.h"
#include "reference/core/io.h"
#include "validation/zwidth.h"

namespace dentsim::cli {
namespace {

struct ZwidthOptions {
  std::string json;
  std::string out;
  bool quick = false;
  std::vector<std::string> methods = {"explicit", "pmi", "pmi-pd"};
  std::vector<std::string> operators = {"force", "grip", "tap", "release"};
  std::string testbed = "phantom";
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
  std::vector<double> tap_speeds;
  double proxy_damping = -1.0;  // < 0: the rule b_2 = k_vc T / 2
};

bool show_progress() { return isatty(2) && std::getenv("CI") == nullptr; }

void progress_bar(const char* what, int done, int total) {
  if (!show_progress()) return;
  const int width = 40;
  const int filled = total > 0 ? width * done / total : width;
  std::fprintf(stderr, "\r%-12s [%s%s] %d/%d", what, std::string(filled, '#').c_str(),
               std::string(width - filled, '.').c_str(), done, total);
  if (done == total) std::fprintf(stderr, "\n");
}

const double kThesis[3] = {315.0, 570.0, 3000.0};  // thesis Fig. 4.11 [N/m]

double thesis_value(Method m) {
  return m == Method::kExplicitVc ? kThesis[0] : m == Method::kPmiVc ? kThesis[1] : kThesis[2];
}

nlohmann::json gains_json(const ZwidthGains& g) {
  return {{"k_vc_n_per_m", g.k_vc}, {"b_vc_n_s_per_m", g.b_vc}, {"k_tooth_n_per_m", g.k_tooth}};
}

nlohmann::json run_json(const ZwidthRun& r) {
  return {{"approach_speed_m_s", r.approach_speed_m_s},
          {"finite", r.finite},
          {"faults", r.faults},
          {"saturated", r.saturated},
          {"growth_rate_per_s", r.growth_rate_per_s},
          {"growth_limit_per_s", r.growth_limit_per_s},
          {"last_amplitude_m", r.last_amplitude_m},
          {"amplitude_bound_m", r.amplitude_bound_m},
          {"energy_max_j", r.energy_max_j},
          {"energy_final_j", r.energy_final_j},
          {"energy_tol_j", r.energy_tol_j},
          {"max_force_n", r.max_force_n},
          {"max_penetration_m", r.max_penetration_m},
          {"z_width_n_per_m", r.z_width_n_per_m},
          {"static_stiffness_n_per_m", r.static_stiffness_n_per_m},
          {"contact_time_s", r.contact_time_s},
          {"proxy_tunnelled", r.proxy_tunnelled},
          {"grip_switches", r.grip_switches},
          {"grip_agreement", r.grip_agreement},
          {"release_detected_after_s", r.release_detected_after_s},
          {"grip_statistic_max_on", r.grip_statistic_max_on},
          {"grip_statistic_min_on", r.grip_statistic_min_on},
          {"grip_statistic_max_off", r.grip_statistic_max_off},
          {"stable", r.stable},
          {"passive", r.passive}};
}

nlohmann::json sweep_json(const ZwidthSweep& s) {
  nlohmann::json j;
  j["z_width_n_per_m"] = s.z_width_n_per_m();
  j["gains"] = s.best >= 0 ? gains_json(s.points[s.best].gains) : nlohmann::json(nullptr);
  nlohmann::json pts = nlohmann::json::array();
  for (const ZwidthPoint& p : s.points) {
    nlohmann::json pj = gains_json(p.gains);
    pj["stable"] = p.stable;
    pj["passive"] = p.passive;
    pj["z_width_n_per_m"] = p.z_width_n_per_m;
    nlohmann::json runs = nlohmann::json::array();
    for (const ZwidthRun& r : p.runs) runs.push_back(run_json(r));
    pj["runs"] = runs;
    pts.push_back(pj);
  }
  j["points"] = pts;
  // The same maximum under the literal growth criterion, lambda <= 0 for every run (the
  // protocol allows lambda <= ln 2 / (hold - settle): docs/zwidth_protocol.md).
  double strict = 0.0;
  for (const ZwidthPoint& p : s.points) {
    bool ok = p.stable && p.passive;
    for (const ZwidthRun& r : p.runs) ok = ok && r.growth_rate_per_s <= 0.0;
    if (ok) strict = std::max(strict, p.z_width_n_per_m);
  }
  j["z_width_strict_growth_n_per_m"] = strict;
  return j;
}

ZwidthGrid full_grid() {
  ZwidthGrid g;
  g.k_vc = {100, 200, 300, 400, 600, 800, 1200, 1600, 2400, 3200};
  g.b_vc = {0.1, 0.5, 1.0, 2.0, 4.0};
  g.k_tooth = {1500, 3000, 6000, 12000};
  return g;
}

// The grid of the other operators (grip, tap, release): the thesis's neighbourhood and the
// corners of the force grid's stable region, at the coupling damping that is stable for all.
ZwidthGrid other_grid() {
  ZwidthGrid g;
  g.k_vc = {400, 1600, 3200};
  g.b_vc = {2.0};
  g.k_tooth = {1500, 3000, 12000};
  return g;
}

ZwidthGrid quick_grid() {
  ZwidthGrid g;
  g.k_vc = {200, 400, 800, 1600, 3200};
  g.b_vc = {0.5, 2.0};
  g.k_tooth = {1500, 3000, 12000};
  return g;
}

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
// run of PMI + PD at `g` with the hand's mass fixed in the model and one with the detector; the
// penetration of both, and the detector's statistic and state.
void write_grip_detector_plot(const std::string& dir, const ZwidthScenario& sc,
                              const ZwidthGains& g) {
  std::filesystem::create_directories(dir);
  ZwidthScenario fixed = sc;
  fixed.grip_detector = false;
  ZwidthTrace tf, td;
  run_zwidth_once(Method::kPmiPd, ZwidthOperator::kRelease, g, fixed, 0.0, &tf);
  run_zwidth_once(Method::kPmiPd, ZwidthOperator::kRelease, g, sc, 0.0, &td);
  char gains[96];
  std::snprintf(gains, sizeof gains, "(K_vc %g, b_vc %g, K_tooth %g), model hand mass x%g", g.k_vc,
                g.b_vc, g.k_tooth, sc.grasp_mass_scale);
  plot::Figure pen{std::string("pmi-pd, release: device penetration ") + gains, "time [s]",
                   "penetration [mm]", {}, false, false};
  pen.series.push_back({"hand mass fixed in the model", tf.t, to_mm(tf.penetration_m)});
  pen.series.push_back({"with the grip detector", td.t, to_mm(td.penetration_m)});
  plot::Figure st{"grip detector: statistic s = P1 - P0 and state (1 = gripped)", "time [s]",
                  "s [N^2/kg] / state", {}, false, false};
  std::vector<double> state;
  for (int v : td.grip_state) state.push_back(v);
  st.series.push_back({"s", td.t, td.grip_statistic});
  st.series.push_back({"state", td.t, state});
  const double t_end = td.t.empty() ? 1.0 : td.t.back();
  st.series.push_back({"release threshold", {0.0, t_end},
                       {sc.grip_detector_params.release_threshold,
                        sc.grip_detector_params.release_threshold},
                       false, -1, true});
  plot::write_png({pen, st}, dir + "/grip_detector.png", 1, 900, 320);
}

void write_plots(const std::string& dir, const std::vector<ZwidthSweep>& force_sweeps,
                 const ZwidthGrid& grid, const ZwidthScenario& sc,
                 const std::vector<std::vector<double>>& op_values,
                 const std::vector<std::string>& op_names) {
  std::filesystem::create_directories(dir);
  // Fig. 4.9-4.10: force vs penetration at each method's best point (force operator).
  std::vector<plot::Figure> fp, ft;
  for (const ZwidthSweep& s : force_sweeps) {
    if (s.best < 0) continue;
    ZwidthTrace tr;
    const ZwidthGains g = s.points[s.best].gains;
    run_zwidth_once(s.method, s.op, g, sc, 0.0, &tr);
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
  std::vector<plot::CategoryMap> maps;
  const std::size_t nt = grid.k_tooth.size(), nk = grid.k_vc.size();
  for (const ZwidthSweep& s : force_sweeps) {
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
  for (const ZwidthSweep& s : force_sweeps) b.labels.push_back(method_name(s.method));
  b.set_names.push_back("thesis");
  std::vector<double> th;
  for (const ZwidthSweep& s : force_sweeps) th.push_back(thesis_value(s.method));
  b.values.push_back(th);
  for (std::size_t i = 0; i < op_names.size(); ++i) {
    b.set_names.push_back(op_names[i]);
    b.values.push_back(op_values[i]);
  }
  plot::write_png(b, dir + "/summary.png");
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
  check_output_paths({{"--json", o.json}});
  std::vector<Method> methods;
  for (const std::string& m : o.methods) {
    try {
      methods.push_back(parse_method(m));
    } catch (const std::exception&) {
      throw InputError("--methods: expected explicit, pmi or pmi-pd, got '" + m + "'");
    }
  }
  std::vector<ZwidthOperator> ops;
  for (const std::string& s : o.operators) ops.push_back(parse_operator(s));
  if (methods.empty() || ops.empty()) throw InputError("--methods/--operators: empty list");

  ZwidthScenario sc;
  sc.testbed = parse_testbed(o.testbed);
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
  if (o.proxy_damping >= 0.0) {
    if (!std::isfinite(o.proxy_damping)) throw InputError("--proxy-damping: expected a finite value");
    sc.proxy_damping_rule = false;
    sc.proxy.damping_lin = o.proxy_damping;
  }
  const int threads = o.threads > 0
                          ? o.threads
                          : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  ZwidthGrid grid = o.quick ? quick_grid() : full_grid();
  ZwidthGrid small = o.quick ? quick_grid() : other_grid();
  for (const auto* v : {&o.k_vc, &o.b_vc, &o.k_tooth}) {
    for (double x : *v) {
      if (!(x >= 0.0) || !std::isfinite(x)) {
        throw InputError("--k-vc/--b-vc/--k-tooth: expected finite values >= 0, got " +
                         std::to_string(x));
      }
    }
  }
  if (!o.k_vc.empty()) grid.k_vc = small.k_vc = o.k_vc;
  if (!o.b_vc.empty()) grid.b_vc = small.b_vc = o.b_vc;
  if (!o.k_tooth.empty()) grid.k_tooth = small.k_tooth = o.k_tooth;
  const double b_d = testbed_tip_damping(sc);
  const double delta = testbed_tip_quantum(sc);

  // The strictest operator (force) on the full grid, the others on the small grid.
  std::vector<ZwidthSweep> force_sweeps;
  std::vector<std::vector<ZwidthSweep>> per_op(ops.size());
  for (std::size_t k = 0; k < ops.size(); ++k) {
    const bool strict = ops[k] == ZwidthOperator::kForce;
    const std::string label = operator_name(ops[k]);
    per_op[k] = run_zwidth_sweep(methods, {ops[k]}, strict ? grid : small, sc, threads,
                                 [&](int d, int t) { progress_bar(label.c_str(), d, t); });
    if (strict) force_sweeps = per_op[k];
  }

  nlohmann::json out;
  out["testbed"] = testbed_name(sc.testbed);
  out["tick_s"] = sc.tick;
  out["hold_s"] = sc.hold_s;
  out["tap_speeds_m_s"] = sc.tap_speeds_m_s;
  out["push_force_n"] = sc.push_force_n;
  out["observer_gain_per_s"] = sc.observer_gain;
  out["observer_input_matched"] = sc.observer_input_matched;
  out["grasp_mass_scale"] = sc.grasp_mass_scale;
  out["grip_detector"] = sc.grip_detector;
  out["proxy_damping_rule"] = sc.proxy_damping_rule;
  out["proxy_damping_n_s_per_m"] = sc.proxy.damping_lin;
  out["tip_radius_m"] = sc.tip_radius_m;
  out["voxel_size_m"] = sc.voxel_size_m;
  out["device_tip_damping_n_s_per_m"] = b_d;
  out["device_tip_quantum_m"] = delta;
  out["grid"] = {{"k_vc_n_per_m", grid.k_vc},
                 {"b_vc_n_s_per_m", grid.b_vc},
                 {"k_tooth_n_per_m", grid.k_tooth}};
  out["grid_other_operators"] = {{"k_vc_n_per_m", small.k_vc},
                                 {"b_vc_n_s_per_m", small.b_vc},
                                 {"k_tooth_n_per_m", small.k_tooth}};
  std::printf(
      "testbed %s, T = %.3g ms, device damping at the tip b_d = %.4g N s/m, tip encoder "
      "quantum %.3g mm\n",
      testbed_name(sc.testbed), sc.tick * 1e3, b_d, delta * 1e3);
  std::printf("%-8s %10s %24s", "method", "thesis", "Z-width [N/m] (gains)");
  for (ZwidthOperator op : ops) std::printf(" %9s", operator_name(op));
  std::printf(" %12s %12s\n", "CS bound", "PMI bound");
  std::vector<double> strict_values;
  std::vector<std::vector<double>> op_values(ops.size());
  for (std::size_t mi = 0; mi < methods.size(); ++mi) {
    const Method m = methods[mi];
    nlohmann::json mj;
    const ZwidthSweep* strict = nullptr;
    for (std::size_t k = 0; k < ops.size(); ++k) {
      mj["operators"][operator_name(ops[k])] = sweep_json(per_op[k][mi]);
      op_values[k].push_back(per_op[k][mi].z_width_n_per_m());
      if (ops[k] == ZwidthOperator::kForce) strict = &per_op[k][mi];
    }
    if (strict == nullptr) strict = &per_op[0][mi];
    const double z = strict->z_width_n_per_m();
    strict_values.push_back(z);
    mj["z_width_n_per_m"] = z;
    mj["strictest_operator"] = operator_name(strict->op);
    mj["gains"] = strict->best >= 0 ? gains_json(strict->points[strict->best].gains)
                                    : nlohmann::json(nullptr);
    mj["thesis_z_width_n_per_m"] = thesis_value(m);
    const double bvc = strict->best >= 0 ? strict->points[strict->best].gains.b_vc : 0.0;
    const double cs = colgate_schenkel_max_stiffness(b_d, bvc, sc.tick);
    const double pb = pmi_coupling_max_stiffness(b_d, bvc, sc.tick, sc.tick);
    mj["colgate_schenkel_max_stiffness_n_per_m"] = cs;
    mj["pmi_coupling_bound_n_per_m"] = pb;
    out["methods"][method_name(m)] = mj;
    char gains[64] = "-";
    if (strict->best >= 0) {
      const ZwidthGains& g = strict->points[strict->best].gains;
      std::snprintf(gains, sizeof gains, "(%g, %g, %g)", g.k_vc, g.b_vc, g.k_tooth);
    }
    std::printf("%-8s %10.0f %9.1f %14s", method_name(m), thesis_value(m), z, gains);
    for (std::size_t k = 0; k < ops.size(); ++k) std::printf(" %9.1f", op_values[k].back());
    std::printf(" %12.1f %12.1f\n", cs, pb);
  }
  auto value_of = [&](Method m) {
    for (std::size_t i = 0; i < methods.size(); ++i) {
      if (methods[i] == m) return strict_values[i];
    }
    return std::nan("");
  };
  const double e = value_of(Method::kExplicitVc);
  const double r1 = e > 0 ? value_of(Method::kPmiVc) / e : std::nan("");
  const double r2 = e > 0 ? value_of(Method::kPmiPd) / e : std::nan("");
  out["ratio_pmi_over_explicit"] = std::isfinite(r1) ? nlohmann::json(r1) : nlohmann::json(nullptr);
  out["ratio_pmipd_over_explicit"] =
      std::isfinite(r2) ? nlohmann::json(r2) : nlohmann::json(nullptr);
  std::printf("ratio pmi/explicit %.2f (thesis 1.8), pmi-pd/explicit %.2f (thesis 9.5)\n", r1, r2);

  // Sensitivity at each method's best point under the force operator (hand: grip operator).
  if (o.sensitivity) {
    struct Variant {
      std::string name;
      ZwidthOperator op;
      std::function<void(ZwidthScenario&)> apply;
    };
    const std::vector<Variant> variants = {
        {"nominal", ZwidthOperator::kForce, [](ZwidthScenario&) {}},
        {"hand_low (grip, Z_h x0.5)", ZwidthOperator::kGrip,
         [](ZwidthScenario& s) {
           s.hand.k_lin *= 0.5;
           s.hand.b_lin *= 0.5;
           s.hand.mass *= 0.5;
         }},
        {"hand_high (grip, Z_h x2)", ZwidthOperator::kGrip,
         [](ZwidthScenario& s) {
           s.hand.k_lin *= 2.0;
           s.hand.b_lin *= 2.0;
           s.hand.mass *= 2.0;
         }},
        {"jitter +-0.2 T", ZwidthOperator::kForce,
         [](ZwidthScenario& s) { s.jitter_half_width = 0.2 * s.tick; }},
        {"observer L = 100/s", ZwidthOperator::kForce,
         [](ZwidthScenario& s) { s.observer_gain = 100.0; }},
        {"observer L = 500/s", ZwidthOperator::kForce,
         [](ZwidthScenario& s) { s.observer_gain = 500.0; }},
        {"observer L = 900/s", ZwidthOperator::kForce,
         [](ZwidthScenario& s) { s.observer_gain = 900.0; }},
        {"observer input unmatched (thesis)", ZwidthOperator::kForce,
         [](ZwidthScenario& s) { s.observer_input_matched = false; }},
        {"model -20 %", ZwidthOperator::kForce,
         [](ZwidthScenario& s) {
           s.model_mass_scale = 0.8;
           s.model_damping_scale = 0.8;
         }},
        {"model +20 %", ZwidthOperator::kForce,
         [](ZwidthScenario& s) {
           s.model_mass_scale = 1.2;
           s.model_damping_scale = 1.2;
         }},
        {"4 kHz", ZwidthOperator::kForce, [](ZwidthScenario& s) { s.tick = 0.25e-3; }},
    };
    std::printf("\nsensitivity at each method's best point (force operator unless noted):\n");
    for (std::size_t mi = 0; mi < methods.size(); ++mi) {
      const ZwidthSweep& s = force_sweeps.empty() ? per_op[0][mi] : force_sweeps[mi];
      if (s.best < 0) continue;
      const ZwidthGains g = s.points[s.best].gains;
      for (std::size_t vi = 0; vi < variants.size(); ++vi) {
        ZwidthScenario v = sc;
        variants[vi].apply(v);
        const ZwidthPoint p = run_zwidth_point(methods[mi], variants[vi].op, g, v);
        std::printf("  %-8s %-28s stable %d passive %d Z-width %8.1f N/m\n",
                    method_name(methods[mi]), variants[vi].name.c_str(), p.stable, p.passive,
                    p.z_width_n_per_m);
        out["methods"][method_name(methods[mi])]["sensitivity"][variants[vi].name] = {
            {"operator", operator_name(variants[vi].op)},
            {"stable", p.stable},
            {"passive", p.passive},
            {"z_width_n_per_m", p.z_width_n_per_m}};
      }
    }
  }

  if (!o.out.empty()) {
    std::vector<std::string> names;
    for (ZwidthOperator op : ops) names.push_back(operator_name(op));
    write_plots(o.out, force_sweeps.empty() ? per_op[0] : force_sweeps,
                force_sweeps.empty() ? small : grid, sc, op_values, names);
  }
  if (!o.out.empty() && sc.grip_detector) {
    // At the best release point of PMI + PD with the detector (if release was run for it).
    for (std::size_t k = 0; k < ops.size(); ++k) {
      if (ops[k] != ZwidthOperator::kRelease) continue;
      for (std::size_t mi = 0; mi < methods.size(); ++mi) {
        const ZwidthSweep& rs = per_op[k][mi];
        if (methods[mi] == Method::kPmiPd && rs.best >= 0) {
          write_grip_detector_plot(o.out, sc, rs.points[rs.best].gains);
        }
      }
    }
  }
  if (!o.json.empty()) write_json(o.json, out);
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
  sub->add_option("--proxy-damping", o->proxy_damping,
                  "A fixed proxy damping b_2 [N s/m] for every method instead of the rule "
                  "b_2 = K_vc T / 2");
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
