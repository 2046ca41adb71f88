#include "validation/zwidth_experiment.h"

#include <algorithm>
#include <cmath>

#include "reference/core/io.h"

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

// The grip detector's traces: the best release point of PMI + PD, if there is one.
void run_grip_traces(ZwidthExperimentResult& r) {
  const ZwidthExperiment& e = r.experiment;
  for (std::size_t k = 0; k < e.operators.size(); ++k) {
    if (e.operators[k] != ZwidthOperator::kRelease) continue;
    for (const ZwidthMethodResult& mr : r.methods) {
      const ZwidthSweep& rs = mr.sweeps[k];
      if (mr.method != Method::kPmiPd || rs.best < 0) continue;
      ZwidthScenario fixed = e.scenario;
      fixed.grip_detector = false;
      r.grip_trace_gains = rs.points[rs.best].gains;
      r.grip_trace_fixed = ZwidthTrace{};
      r.grip_trace_detector = ZwidthTrace{};
      run_zwidth_once(Method::kPmiPd, ZwidthOperator::kRelease, r.grip_trace_gains, fixed, 0.0,
                      &r.grip_trace_fixed);
      run_zwidth_once(Method::kPmiPd, ZwidthOperator::kRelease, r.grip_trace_gains, e.scenario, 0.0,
                      &r.grip_trace_detector);
      r.has_grip_traces = true;
    }
  }
}

nlohmann::json gains_json(const ZwidthGains& g) {
  return {{"k_vc_n_per_m", g.k_vc}, {"b_vc_n_s_per_m", g.b_vc}, {"k_tooth_n_per_m", g.k_tooth}};
}

nlohmann::json grid_json(const ZwidthGrid& g) {
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

nlohmann::json finite_or_null(double x) {
  return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr);
}

}  // namespace

ZwidthExperimentResult run_zwidth_experiment(
    const ZwidthExperiment& e, const std::function<void(ZwidthOperator, int, int)>& progress) {
  if (e.methods.empty() || e.operators.empty()) {
    throw InputError("zwidth experiment: expected at least one method and one operator");
  }
  ZwidthExperimentResult r;
  r.experiment = e;
  r.device_tip_damping_n_s_per_m = testbed_tip_damping(e.scenario);
  r.device_tip_quantum_m = testbed_tip_quantum(e.scenario);
  r.methods.resize(e.methods.size());
  for (std::size_t mi = 0; mi < e.methods.size(); ++mi) r.methods[mi].method = e.methods[mi];

  // The strictest operator (force) on the full grid, the others on the small grid.
  for (std::size_t k = 0; k < e.operators.size(); ++k) {
    const ZwidthOperator op = e.operators[k];
    const bool strict = op == ZwidthOperator::kForce;
    const std::vector<ZwidthSweep> sweeps =
        run_zwidth_sweep(e.methods, {op}, strict ? e.grid : e.other_grid, e.scenario, e.threads,
                         [&](int done, int total) {
                           if (progress) progress(op, done, total);
                         });
    for (std::size_t mi = 0; mi < e.methods.size(); ++mi) {
      ZwidthMethodResult& mr = r.methods[mi];
      mr.sweeps.push_back(sweeps[mi]);
      if (strict) mr.headline = static_cast<int>(k);
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

  // Sensitivity at each method's headline point (hand variants: grip operator).
  if (e.sensitivity) {
    for (ZwidthMethodResult& mr : r.methods) {
      const ZwidthSweep& s = mr.headline_sweep();
      if (s.best < 0) continue;
      const ZwidthGains g = s.points[s.best].gains;
      for (const ZwidthSensitivityVariant& variant : zwidth_sensitivity_variants()) {
        ZwidthScenario v = e.scenario;
        variant.apply(v);
        mr.sensitivity.push_back(
            {variant.name, variant.op, run_zwidth_point(mr.method, variant.op, g, v)});
      }
    }
  }

  if (e.traces) {
    for (ZwidthMethodResult& mr : r.methods) {
      const ZwidthSweep& s = mr.headline_sweep();
      if (s.best < 0) continue;
      run_zwidth_once(s.method, s.op, s.points[s.best].gains, e.scenario, 0.0, &mr.trace);
    }
    if (e.scenario.grip_detector) run_grip_traces(r);
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
  return out;
}

}  // namespace dentsim
