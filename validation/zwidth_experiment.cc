#include "validation/zwidth_experiment.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <exception>
#include <limits>
#include <mutex>
#include <optional>
#include <thread>
#include <type_traits>

#include "reference/core/io.h"
#include "validation/thread_pool.h"

namespace dentsim {

ZwidthGrid zwidth_full_grid() {
  ZwidthGrid g;
  g.k_vc = {100, 200, 300, 400, 600, 800, 1200, 1600, 2400, 3200};
  g.b_vc = {0.1, 0.5, 1.0, 2.0, 4.0};
  g.k_tooth = {1500, 3000, 6000, 12000};
  return g;
}

ZwidthGrid zwidth_other_grid() {
  ZwidthGrid g;
  g.k_vc = {400, 1600, 3200};
  g.b_vc = {2.0};
  g.k_tooth = {1500, 3000, 12000};
  return g;
}

ZwidthGrid zwidth_quick_grid() {
  ZwidthGrid g;
  g.k_vc = {200, 400, 800, 1600, 3200};
  g.b_vc = {0.5, 2.0};
  g.k_tooth = {1500, 3000, 12000};
  return g;
}

double zwidth_thesis_value(Method m) {
  switch (m) {
    case Method::kExplicitVc:
      return 315.0;
    case Method::kPmiVc:
      return 570.0;
    case Method::kPmiPd:
      return 3000.0;
  }
  return 3000.0;
}

const std::vector<ZwidthSensitivityVariant>& zwidth_sensitivity_variants() {
  static const std::vector<ZwidthSensitivityVariant> variants = {
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
  return variants;
}

const ZwidthGrid& ZwidthExperimentResult::headline_grid() const {
  const auto& ops = experiment.operators;
  const bool force = std::find(ops.begin(), ops.end(), ZwidthOperator::kForce) != ops.end();
  return force ? experiment.grid : experiment.other_grid;
}

namespace {

// The headline Z-width of method m, NaN if m was not run.
double headline_of(const ZwidthExperimentResult& r, Method m) {
  for (const ZwidthMethodResult& mr : r.methods) {
    if (mr.method == m) return mr.z_width_n_per_m();
  }
  return std::nan("");
}

// The same over the quiet Z-widths.
double quiet_headline_of(const ZwidthExperimentResult& r, Method m) {
  for (const ZwidthMethodResult& mr : r.methods) {
    if (mr.method == m) return mr.quiet_z_width_n_per_m();
  }
  return std::nan("");
}

nlohmann::json gains_json(const ZwidthGains& g) {
  return {{"k_vc_n_per_m", g.k_vc}, {"b_vc_n_s_per_m", g.b_vc}, {"k_tooth_n_per_m", g.k_tooth}};
}

nlohmann::json grid_json(const ZwidthGrid& g) {
  return {{"k_vc_n_per_m", g.k_vc}, {"b_vc_n_s_per_m", g.b_vc}, {"k_tooth_n_per_m", g.k_tooth}};
}

// Every field of a run, once: the JSON of `dentsim zwidth` (run_json) and the jobs' wire format
// (zwidth_point_to_wire) are both made from this list, so a field added here reaches both.
// `contact` travels on the wire only (it is not in the contract).
template <class Run, class F>
void run_fields(Run& r, F&& f) {
  f("approach_speed_m_s", r.approach_speed_m_s);
  f("finite", r.finite);
  f("contact", r.contact);
  f("faults", r.faults);
  f("saturated", r.saturated);
  f("growth_rate_per_s", r.growth_rate_per_s);
  f("growth_limit_per_s", r.growth_limit_per_s);
  f("last_amplitude_m", r.last_amplitude_m);
  f("amplitude_bound_m", r.amplitude_bound_m);
  f("energy_max_j", r.energy_max_j);
  f("energy_final_j", r.energy_final_j);
  f("energy_tol_j", r.energy_tol_j);
  f("max_force_n", r.max_force_n);
  f("max_penetration_m", r.max_penetration_m);
  f("z_width_n_per_m", r.z_width_n_per_m);
  f("static_stiffness_n_per_m", r.static_stiffness_n_per_m);
  f("contact_time_s", r.contact_time_s);
  f("proxy_tunnelled", r.proxy_tunnelled);
  f("grip_switches", r.grip_switches);
  f("grip_agreement", r.grip_agreement);
  f("release_detected_after_s", r.release_detected_after_s);
  f("grip_statistic_max_on", r.grip_statistic_max_on);
  f("grip_statistic_min_on", r.grip_statistic_min_on);
  f("grip_statistic_max_off", r.grip_statistic_max_off);
  f("stable", r.stable);
  f("passive", r.passive);
  // The quiet measures of the contact (issue #29; sim/quiet_measures.h) and the verdict.
  f("quiet_ticks", r.quiet_measures.ticks);
  f("ripple_contact_force", r.quiet_measures.ripple_contact_force);
  f("ripple_device_force", r.quiet_measures.ripple_device_force);
  f("contact_fraction", r.quiet_measures.contact_fraction);
  f("contact_losses", r.quiet_measures.contact_losses);
  f("oscillation_amplitude_quanta", r.quiet_measures.oscillation_amplitude_quanta);
  f("quiet_static_stiffness_n_per_m", r.quiet_measures.static_stiffness_n_per_m);
  f("quiet_motor_energy_j", r.quiet_measures.motor_energy_j);
  f("quiet", r.quiet);
}

template <class T>
struct is_optional : std::false_type {};
template <class T>
struct is_optional<std::optional<T>> : std::true_type {};

nlohmann::json run_json(const ZwidthRun& r) {
  nlohmann::json j;
  run_fields(r, [&j](const char* key, const auto& v) {
    if (std::string(key) == "contact") return;
    if constexpr (is_optional<std::decay_t<decltype(v)>>::value) {
      j[key] = v ? nlohmann::json(*v) : nlohmann::json(nullptr);
    } else {
      j[key] = v;
    }
  });
  return j;
}

// A double on the wire: JSON numbers carry finite doubles exactly (shortest round-trip digits);
// NaN and the infinities, which JSON lacks (dump writes null), go as strings, NaN with its sign
// (printf shows it).
nlohmann::json wire(double x) {
  if (std::isfinite(x)) return x;
  if (std::isnan(x)) return std::signbit(x) ? "-nan" : "nan";
  return x > 0 ? "inf" : "-inf";
}

double double_from_wire(const nlohmann::json& j) {
  if (!j.is_string()) return j.get<double>();
  const std::string s = j.get<std::string>();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  if (s == "nan") return nan;
  if (s == "-nan") return -nan;
  if (s == "inf") return inf;
  if (s == "-inf") return -inf;
  throw std::runtime_error("zwidth job result: expected a number, got '" + s + "'");
}

nlohmann::json wire(const std::vector<double>& xs) {
  nlohmann::json a = nlohmann::json::array();
  for (double x : xs) a.push_back(wire(x));
  return a;
}

std::vector<double> doubles_from_wire(const nlohmann::json& j) {
  std::vector<double> out;
  out.reserve(j.size());
  for (const nlohmann::json& x : j) out.push_back(double_from_wire(x));
  return out;
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
    pj["quiet"] = p.quiet;
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
  // Over stable, passive and quiet points (issue #29).
  j["quiet_z_width_n_per_m"] = s.quiet_z_width_n_per_m();
  j["quiet_gains"] =
      s.best_quiet >= 0 ? gains_json(s.points[s.best_quiet].gains) : nlohmann::json(nullptr);
  return j;
}

nlohmann::json finite_or_null(double x) {
  return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr);
}

// The default ZwidthJobRunner: the jobs on `threads` std::threads of this process
// (run_jobs_on_threads: the lowest failing index's exception is rethrown).
std::vector<nlohmann::json> run_jobs_here(int n, const std::function<nlohmann::json(int)>& job,
                                          int threads) {
  std::vector<nlohmann::json> out(static_cast<std::size_t>(n));
  run_jobs_on_threads(n, threads, [&](int i) { out[static_cast<std::size_t>(i)] = job(i); });
  return out;
}

// The best point of a sweep: stable, passive (and with `quiet`, quiet), the largest Z-width, the
// first in grid order on a tie (as run_zwidth_sweep picks it).
int best_point(const ZwidthSweep& sw, bool quiet = false) {
  int best = -1;
  for (std::size_t i = 0; i < sw.points.size(); ++i) {
    const ZwidthPoint& p = sw.points[i];
    if (p.stable && p.passive && (p.quiet || !quiet) &&
        (best < 0 || p.z_width_n_per_m > sw.points[best].z_width_n_per_m)) {
      best = static_cast<int>(i);
    }
  }
  return best;
}

}  // namespace

nlohmann::json zwidth_point_to_wire(const ZwidthPoint& p) {
  nlohmann::json runs = nlohmann::json::array();
  for (const ZwidthRun& r : p.runs) {
    nlohmann::json rj;
    run_fields(r, [&rj](const char* key, const auto& v) {
      if constexpr (std::is_same_v<std::decay_t<decltype(v)>, double>) {
        rj[key] = wire(v);
      } else if constexpr (is_optional<std::decay_t<decltype(v)>>::value) {
        rj[key] = v ? wire(*v) : nlohmann::json(nullptr);
      } else {
        rj[key] = v;
      }
    });
    runs.push_back(rj);
  }
  return {{"gains", {wire(p.gains.k_vc), wire(p.gains.b_vc), wire(p.gains.k_tooth)}},
          {"runs", runs},
          {"stable", p.stable},
          {"passive", p.passive},
          {"quiet", p.quiet},
          {"z_width_n_per_m", wire(p.z_width_n_per_m)}};
}

ZwidthPoint zwidth_point_from_wire(const nlohmann::json& j) {
  ZwidthPoint p;
  const nlohmann::json& g = j.at("gains");
  p.gains = {double_from_wire(g.at(0)), double_from_wire(g.at(1)), double_from_wire(g.at(2))};
  for (const nlohmann::json& rj : j.at("runs")) {
    ZwidthRun r;
    run_fields(r, [&rj](const char* key, auto& v) {
      using T = std::decay_t<decltype(v)>;
      if constexpr (std::is_same_v<T, double>) {
        v = double_from_wire(rj.at(key));
      } else if constexpr (is_optional<T>::value) {
        if (rj.at(key).is_null()) {
          v.reset();
        } else {
          v = double_from_wire(rj.at(key));
        }
      } else {
        v = rj.at(key).get<T>();
      }
    });
    p.runs.push_back(r);
  }
  p.stable = j.at("stable").get<bool>();
  p.passive = j.at("passive").get<bool>();
  p.quiet = j.at("quiet").get<bool>();
  for (ZwidthRun& r : p.runs) r.quiet_measures.quiet = r.quiet;
  p.z_width_n_per_m = double_from_wire(j.at("z_width_n_per_m"));
  return p;
}

nlohmann::json zwidth_trace_to_wire(const ZwidthTrace& t) {
  return {{"t", wire(t.t)},
          {"penetration_m", wire(t.penetration_m)},
          {"force_n", wire(t.force_n)},
          {"energy_j", wire(t.energy_j)},
          {"grip_state", t.grip_state},
          {"grip_statistic", wire(t.grip_statistic)}};
}

ZwidthTrace zwidth_trace_from_wire(const nlohmann::json& j) {
  ZwidthTrace t;
  t.t = doubles_from_wire(j.at("t"));
  t.penetration_m = doubles_from_wire(j.at("penetration_m"));
  t.force_n = doubles_from_wire(j.at("force_n"));
  t.energy_j = doubles_from_wire(j.at("energy_j"));
  t.grip_state = j.at("grip_state").get<std::vector<int>>();
  t.grip_statistic = doubles_from_wire(j.at("grip_statistic"));
  return t;
}

ZwidthExperimentResult run_zwidth_experiment(
    const ZwidthExperiment& e, const std::function<void(ZwidthOperator, int, int)>& progress,
    const ZwidthJobRunner& runner) {
  if (e.methods.empty() || e.operators.empty()) {
    throw InputError("zwidth experiment: expected at least one method and one operator");
  }
  const ZwidthJobRunner run_jobs =
      runner ? runner
             : ZwidthJobRunner(
                   [&e](const std::string&, int n, const std::function<nlohmann::json(int)>& job) {
                     return run_jobs_here(n, job, e.threads);
                   });
  ZwidthExperimentResult r;
  r.experiment = e;
  r.device_tip_damping_n_s_per_m = testbed_tip_damping(e.scenario);
  r.device_tip_quantum_m = testbed_tip_quantum(e.scenario);
  r.methods.resize(e.methods.size());
  for (std::size_t mi = 0; mi < e.methods.size(); ++mi) r.methods[mi].method = e.methods[mi];

  // Stage "grid": the strictest operator (force) on the full grid, the others on the small grid;
  // one job per (operator, method, grid point), operator-major as the sweeps were run one after
  // the other.
  struct GridJob {
    std::size_t op, method, point;
  };
  std::vector<GridJob> grid_jobs;
  std::vector<int> op_total(e.operators.size(), 0), op_done(e.operators.size(), 0);
  for (std::size_t k = 0; k < e.operators.size(); ++k) {
    const ZwidthGrid& grid = e.operators[k] == ZwidthOperator::kForce ? e.grid : e.other_grid;
    for (std::size_t mi = 0; mi < e.methods.size(); ++mi) {
      ZwidthSweep s;
      s.method = e.methods[mi];
      s.op = e.operators[k];
      s.points.resize(grid.size());
      r.methods[mi].sweeps.push_back(std::move(s));
      for (std::size_t i = 0; i < grid.size(); ++i) grid_jobs.push_back({k, mi, i});
    }
    op_total[k] = static_cast<int>(e.methods.size() * grid.size());
  }
  std::mutex progress_mu;
  const std::vector<nlohmann::json> grid_results =
      run_jobs("grid", static_cast<int>(grid_jobs.size()), [&](int j) -> nlohmann::json {
        const GridJob& g = grid_jobs[j];
        const ZwidthOperator op = e.operators[g.op];
        const ZwidthGrid& grid = op == ZwidthOperator::kForce ? e.grid : e.other_grid;
        nlohmann::json out = zwidth_point_to_wire(
            run_zwidth_point(e.methods[g.method], op, grid.at(g.point), e.scenario));
        if (progress) {
          std::lock_guard<std::mutex> lock(progress_mu);
          progress(op, ++op_done[g.op], op_total[g.op]);
        }
        return out;
      });
  for (std::size_t j = 0; j < grid_jobs.size(); ++j) {
    const GridJob& g = grid_jobs[j];
    r.methods[g.method].sweeps[g.op].points[g.point] = zwidth_point_from_wire(grid_results[j]);
  }
  for (ZwidthMethodResult& mr : r.methods) {
    for (std::size_t k = 0; k < e.operators.size(); ++k) {
      mr.sweeps[k].best = best_point(mr.sweeps[k]);
      mr.sweeps[k].best_quiet = best_point(mr.sweeps[k], true);
      if (e.operators[k] == ZwidthOperator::kForce) mr.headline = static_cast<int>(k);
    }
  }

  const double b_d = r.device_tip_damping_n_s_per_m;
  for (ZwidthMethodResult& mr : r.methods) {
    const ZwidthSweep& s = mr.headline_sweep();
    mr.thesis_z_width_n_per_m = zwidth_thesis_value(mr.method);
    const double b_vc = s.best >= 0 ? s.points[s.best].gains.b_vc : 0.0;
    const double T = e.scenario.tick;
    mr.colgate_schenkel_max_stiffness_n_per_m = colgate_schenkel_max_stiffness(b_d, b_vc, T);
    mr.pmi_coupling_bound_n_per_m = pmi_coupling_max_stiffness(b_d, b_vc, T, T);
  }
  const double z_explicit = headline_of(r, Method::kExplicitVc);
  r.ratio_pmi_over_explicit =
      z_explicit > 0 ? headline_of(r, Method::kPmiVc) / z_explicit : std::nan("");
  r.ratio_pmipd_over_explicit =
      z_explicit > 0 ? headline_of(r, Method::kPmiPd) / z_explicit : std::nan("");
  const double q_explicit = quiet_headline_of(r, Method::kExplicitVc);
  r.quiet_ratio_pmi_over_explicit =
      q_explicit > 0 ? quiet_headline_of(r, Method::kPmiVc) / q_explicit : std::nan("");
  r.quiet_ratio_pmipd_over_explicit =
      q_explicit > 0 ? quiet_headline_of(r, Method::kPmiPd) / q_explicit : std::nan("");

  // Stage "re-runs" at each method's headline point: the sensitivity variants (hand variants
  // under the grip operator), the figures' traces, and the grip detector's pair of traces at the
  // best `release` point of PMI + PD (model with the hand's mass fixed, and with the detector).
  struct Rerun {
    enum Kind { kSensitivity, kTrace, kGripFixed, kGripDetector } kind;
    std::size_t method = 0, variant = 0;
  };
  std::vector<Rerun> reruns;
  const auto& variants = zwidth_sensitivity_variants();
  if (e.sensitivity) {
    for (std::size_t mi = 0; mi < r.methods.size(); ++mi) {
      if (r.methods[mi].headline_sweep().best < 0) continue;
      for (std::size_t v = 0; v < variants.size(); ++v) {
        reruns.push_back({Rerun::kSensitivity, mi, v});
      }
    }
  }
  if (e.traces) {
    for (std::size_t mi = 0; mi < r.methods.size(); ++mi) {
      if (r.methods[mi].headline_sweep().best >= 0) reruns.push_back({Rerun::kTrace, mi, 0});
    }
    if (e.scenario.grip_detector) {
      for (std::size_t k = 0; k < e.operators.size(); ++k) {
        if (e.operators[k] != ZwidthOperator::kRelease) continue;
        for (const ZwidthMethodResult& mr : r.methods) {
          const ZwidthSweep& rs = mr.sweeps[k];
          if (mr.method != Method::kPmiPd || rs.best < 0) continue;
          // (Every match has the same gains: the same sweep; the last one's are kept.)
          r.grip_trace_gains = rs.points[rs.best].gains;
          r.has_grip_traces = true;
        }
      }
      if (r.has_grip_traces) {
        reruns.push_back({Rerun::kGripFixed, 0, 0});
        reruns.push_back({Rerun::kGripDetector, 0, 0});
      }
    }
  }
  const std::vector<nlohmann::json> rerun_results =
      run_jobs("re-runs", static_cast<int>(reruns.size()), [&](int j) -> nlohmann::json {
        const Rerun& job = reruns[j];
        const ZwidthMethodResult& mr = r.methods[job.method];
        const ZwidthSweep& s = mr.headline_sweep();
        switch (job.kind) {
          case Rerun::kSensitivity: {
            const ZwidthSensitivityVariant& variant = variants[job.variant];
            ZwidthScenario v = e.scenario;
            variant.apply(v);
            return zwidth_point_to_wire(
                run_zwidth_point(mr.method, variant.op, s.points[s.best].gains, v));
          }
          case Rerun::kTrace: {
            ZwidthTrace trace;
            run_zwidth_once(s.method, s.op, s.points[s.best].gains, e.scenario, 0.0, &trace);
            return zwidth_trace_to_wire(trace);
          }
          case Rerun::kGripFixed:
          case Rerun::kGripDetector: {
            ZwidthScenario sc = e.scenario;
            if (job.kind == Rerun::kGripFixed) sc.grip_detector = false;
            ZwidthTrace trace;
            run_zwidth_once(Method::kPmiPd, ZwidthOperator::kRelease, r.grip_trace_gains, sc, 0.0,
                            &trace);
            return zwidth_trace_to_wire(trace);
          }
        }
        return nullptr;
      });
  for (std::size_t j = 0; j < reruns.size(); ++j) {
    const Rerun& job = reruns[j];
    ZwidthMethodResult& mr = r.methods[job.method];
    switch (job.kind) {
      case Rerun::kSensitivity: {
        const ZwidthSensitivityVariant& variant = variants[job.variant];
        mr.sensitivity.push_back(
            {variant.name, variant.op, zwidth_point_from_wire(rerun_results[j])});
        break;
      }
      case Rerun::kTrace:
        mr.trace = zwidth_trace_from_wire(rerun_results[j]);
        break;
      case Rerun::kGripFixed:
        r.grip_trace_fixed = zwidth_trace_from_wire(rerun_results[j]);
        break;
      case Rerun::kGripDetector:
        r.grip_trace_detector = zwidth_trace_from_wire(rerun_results[j]);
        break;
    }
  }
  return r;
}

nlohmann::json zwidth_experiment_json(const ZwidthExperimentResult& r) {
  const ZwidthExperiment& e = r.experiment;
  const ZwidthScenario& sc = e.scenario;
  nlohmann::json out;
  out["testbed"] = testbed_name(sc.testbed);
  out["pipeline"] = sc.pipeline;
  out["tick_s"] = sc.tick;
  out["hold_s"] = sc.hold_s;
  out["tap_speeds_m_s"] = sc.tap_speeds_m_s;
  out["push_force_n"] = sc.push_force_n;
  out["observer_gain_per_s"] = sc.observer_gain;
  out["observer_input_matched"] = sc.observer_input_matched;
  out["grasp_mass_scale"] = sc.grasp_mass_scale;
  out["grip_detector"] = sc.grip_detector;
  out["encoder_kalman"] = sc.encoder_kalman;
  out["encoder_kalman_friction_model"] = !sc.encoder_kalman_friction    ? "none"
                                         : sc.encoder_kalman_stick_slip ? "stick_slip"
                                                                        : "smooth";
  out["lag_compensation"] = sc.lag_compensation;
  out["proxy_damping_rule"] = sc.proxy_damping_rule;
  out["proxy_damping_n_s_per_m"] = sc.proxy.damping_lin;
  out["tip_radius_m"] = sc.tip_radius_m;
  out["voxel_size_m"] = sc.voxel_size_m;
  out["device_tip_damping_n_s_per_m"] = r.device_tip_damping_n_s_per_m;
  out["device_tip_quantum_m"] = r.device_tip_quantum_m;
  out["grid"] = grid_json(e.grid);
  out["grid_other_operators"] = grid_json(e.other_grid);
  for (const ZwidthMethodResult& mr : r.methods) {
    nlohmann::json mj;
    for (std::size_t k = 0; k < e.operators.size(); ++k) {
      mj["operators"][operator_name(e.operators[k])] = sweep_json(mr.sweeps[k]);
    }
    const ZwidthSweep& s = mr.headline_sweep();
    mj["z_width_n_per_m"] = s.z_width_n_per_m();
    mj["strictest_operator"] = operator_name(s.op);
    mj["gains"] = s.best >= 0 ? gains_json(s.points[s.best].gains) : nlohmann::json(nullptr);
    mj["thesis_z_width_n_per_m"] = mr.thesis_z_width_n_per_m;
    mj["quiet_z_width_n_per_m"] = s.quiet_z_width_n_per_m();
    mj["quiet_gains"] =
        s.best_quiet >= 0 ? gains_json(s.points[s.best_quiet].gains) : nlohmann::json(nullptr);
    mj["colgate_schenkel_max_stiffness_n_per_m"] = mr.colgate_schenkel_max_stiffness_n_per_m;
    mj["pmi_coupling_bound_n_per_m"] = mr.pmi_coupling_bound_n_per_m;
    for (const ZwidthSensitivityResult& v : mr.sensitivity) {
      mj["sensitivity"][v.variant] = {{"operator", operator_name(v.op)},
                                      {"stable", v.point.stable},
                                      {"passive", v.point.passive},
                                      {"z_width_n_per_m", v.point.z_width_n_per_m}};
    }
    out["methods"][method_name(mr.method)] = mj;
  }
  out["ratio_pmi_over_explicit"] = finite_or_null(r.ratio_pmi_over_explicit);
  out["ratio_pmipd_over_explicit"] = finite_or_null(r.ratio_pmipd_over_explicit);
  out["quiet_ratio_pmi_over_explicit"] = finite_or_null(r.quiet_ratio_pmi_over_explicit);
  out["quiet_ratio_pmipd_over_explicit"] = finite_or_null(r.quiet_ratio_pmipd_over_explicit);
  out["quiet_bounds"] = {{"ripple_max", sc.quiet.ripple_max},
                         {"contact_fraction_min", sc.quiet.contact_fraction_min},
                         {"contact_losses_max", sc.quiet.contact_losses_max},
                         {"ripple_window_s", sc.quiet.window_s},
                         {"settle_s", sc.quiet.settle_s}};
  if (const std::string why = zwidth_ratio_reason(r, Method::kPmiVc); !why.empty()) {
    out["ratio_pmi_over_explicit_reason"] = why;
  }
  if (const std::string why = zwidth_ratio_reason(r, Method::kPmiPd); !why.empty()) {
    out["ratio_pmipd_over_explicit_reason"] = why;
  }
  return out;
}

std::string zwidth_ratio_reason(const ZwidthExperimentResult& r, Method m) {
  const double ratio = m == Method::kPmiVc   ? r.ratio_pmi_over_explicit
                       : m == Method::kPmiPd ? r.ratio_pmipd_over_explicit
                                             : 1.0;
  if (std::isfinite(ratio)) return "";
  bool has_m = false, has_explicit = false;
  for (const ZwidthMethodResult& mr : r.methods) {
    has_m = has_m || mr.method == m;
    has_explicit = has_explicit || mr.method == Method::kExplicitVc;
  }
  if (!has_explicit) return "explicit was not run (--methods)";
  if (!has_m) return std::string(method_name(m)) + " was not run (--methods)";
  if (!(headline_of(r, Method::kExplicitVc) > 0.0)) {
    return "explicit has no stable and passive grid point (Z-width 0 N/m)";
  }
  return std::string(method_name(m)) + "'s Z-width is not finite";
}

}  // namespace dentsim
