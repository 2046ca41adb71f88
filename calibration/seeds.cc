#include "calibration/seeds.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include "calibration/excitation.h"
#include "device/phantom_device.h"
#include "device/simulated_phantom.h"
#include "reference/core/io.h"

namespace dentsim {
namespace {

// Uniform in [lo, hi] from one draw of the 64-bit generator: the top 53 bits as a double in
// [0, 1) (exact), so the sequence does not depend on the standard library's distribution code.
double draw_factor(std::mt19937_64& rng, double lo, double hi) {
  const double u = static_cast<double>(rng() >> 11) * 0x1.0p-53;
  return lo + (hi - lo) * u;
}

}  // namespace

PerturbedDevice perturb_device(const PhantomParams& base, std::uint64_t seed) {
  PerturbedDevice d;
  d.params = base;
  PhantomParams& p = d.params;
  std::mt19937_64 rng(seed);
  const auto draw = [&](const std::string& name) {
    const double f = draw_factor(rng, kSeedFactorMin, kSeedFactorMax);
    d.factor_names.push_back(name);
    d.factors.push_back(f);
    return f;
  };
  // Model-file order (reference/phantom/phantom_params.cc), as the script iterates the file.
  const std::pair<const char*, PhantomBody*> bodies[] = {{"base", &p.base},
                                                         {"upper_arm", &p.upper_arm},
                                                         {"forearm", &p.forearm},
                                                         {"crank", &p.crank},
                                                         {"parallel_link", &p.parallel_link},
                                                         {"gimbal_yaw", &p.gimbal_yaw},
                                                         {"gimbal_pitch", &p.gimbal_pitch},
                                                         {"gimbal_roll", &p.gimbal_roll}};
  for (const auto& [name, body] : bodies) {
    body->mass_kg *= draw(std::string(name) + ".mass_kg");
    // One factor for the three principal moments keeps the triangle inequality of the base's.
    body->inertia_kg_m2 *= draw(std::string(name) + ".inertia_kg_m2");
  }
  const std::pair<const char*, Vec6*> joints[] = {
      {"armature_kg_m2", &p.armature_kg_m2},
      {"damping_n_m_s_per_rad", &p.damping_n_m_s_per_rad},
      {"coulomb_n_m", &p.coulomb_n_m}};
  for (const auto& [name, v] : joints) {
    for (int j = 0; j < 6; ++j) (*v)(j) *= draw(std::string(name) + "." + std::to_string(j + 1));
  }
  p.name = "perturbed default Phantom, seed " + std::to_string(seed);
  validate_phantom_params(p, p.name);
  return d;
}

bool within_bar(const SeedParameter& p) {
  return p.rel_error <= kParameterRelBar || p.error_over_std <= kParameterStdBar;
}

bool is_gimbal_coulomb(const std::string& name) {
  return name == "coulomb_n_m.4" || name == "coulomb_n_m.5" || name == "coulomb_n_m.6";
}

int SeedResult::checked() const {
  return static_cast<int>(std::count_if(params.begin(), params.end(),
                                        [](const SeedParameter& p) { return p.identifiable; }));
}

std::vector<SeedParameter> SeedResult::outside() const {
  std::vector<SeedParameter> out;
  for (const SeedParameter& p : params)
    if (p.identifiable && !within_bar(p)) out.push_back(p);
  return out;
}

SeedRun run_seed(const PhantomParams& base, std::uint64_t seed, const SeedRunOptions& o) {
  SeedRun run;
  run.truth = perturb_device(base, seed).params;
  const PhantomParams& p = run.truth;

  // `dentsim excite --device truth --seed S --duration T --design-iterations K`
  // (cli/cmd_calibrate.cc): designed on the truth, tracked with the truth as feed-forward.
  const Vec6 q0 = phantom_home_q(p);
  ExcitationParams ep;
  ep.seed = seed;
  ExcitationDesign design = design_excitation(p, q0, ep, o.design_iterations);
  SimulatedPhantom dev(phantom_plant(p), phantom_device_config(p), phantom_home_q(p));
  ExcitationOutcome ran = run_excitation_until_stop(dev, p, design.excitation, o.duration_s,
                                                    TrackingParams{}, {}, o.stop_request);
  if (ran.interrupted) {
    throw SeedInterrupted("calibrate-seeds: seed " + std::to_string(seed) + ": excitation " +
                          ran.stop_reason);
  }
  // As run_excitation: a device fault is an error of the seed.
  if (!ran.complete) throw InputError("excite: " + ran.stop_reason);
  run.log = std::move(ran.log);
  run.log.comments.push_back(" device: " + p.name);
  run.log.comments.push_back(" excitation: seed " + std::to_string(seed) +
                             ", regressor condition number " +
                             std::to_string(design.condition_seeded) + " (seeded series) -> " +
                             std::to_string(design.condition_designed) +
                             " (designed: " + std::to_string(design.iterations) + " iterations)");

  // `dentsim calibrate LOG --truth truth [--no-model-mismatch]` with the command's defaults.
  const PhantomParams& prior = base;
  CalibrateOptions co;
  co.lowpass_hz = o.lowpass_hz;
  co.max_samples = o.max_samples;
  co.max_iterations = o.max_iterations;
  co.model_mismatch_term = o.model_mismatch_term;
  co.law_mismatch_term = o.law_mismatch_term;
  co.min_speed = o.min_speed;
  co.coulomb_smoothing = o.coulomb_smoothing;
  co.coulomb_sign = o.coulomb_sign;
  const CalibrateOutcome c =
      calibrate_log(run.log, "the log of seed " + std::to_string(seed), prior, co);
  if (!c.finite()) {
    throw std::runtime_error("calibrate-seeds: seed " + std::to_string(seed) +
                             ": the fit ended with a non-finite residual or parameter");
  }
  const FitResult& fit = c.fit;
  run.fitted = fit.fitted;
  const TruthComparison truth = compare_with_truth(fit, prior, p);

  SeedResult& r = run.result;
  r.seed = seed;
  r.converged = fit.converged;
  r.identifiable = fit.identifiable;
  r.condition_number = fit.condition_number;
  r.residual_rms_n_m = fit.residual_rms;
  r.excitation_condition_seeded = design.condition_seeded;
  r.excitation_condition_designed = design.condition_designed;
  r.model_mismatch = fit.model_mismatch;
  r.model_mismatch_reasons = fit.model_mismatch_reasons;
  for (std::size_t i = 0; i < fit.params.size(); ++i) {
    const FitParameter& fp = fit.params[i];
    SeedParameter sp;
    sp.name = fp.name;
    sp.identifiable = fp.identifiable;
    sp.truth = truth.params[i].truth;
    sp.value = fp.value;
    sp.std = fp.std;
    sp.std_statistical = fp.std_statistical;
    sp.std_model = fp.std_model;
    sp.std_law = fp.std_law;
    sp.rel_error = truth.params[i].rel_error;
    sp.error_over_std = truth.params[i].error_over_std;
    r.params.push_back(sp);
  }
  r.fitted = truth.fitted;
  r.prior = truth.prior;
  return run;
}

SeedSummary summarize(const std::vector<SeedResult>& results) {
  SeedSummary s;
  std::vector<double> m;
  double sum_z2 = 0.0;
  int finite = 0;
  for (const SeedResult& r : results) {
    ++s.fits;
    s.converged += r.converged;
    s.checked += r.checked();
    for (const SeedParameter& p : r.outside()) {
      ++s.outside;
      s.outside_gimbal_coulomb += is_gimbal_coulomb(p.name);
    }
    m.push_back(r.fitted.mass_matrix);
    s.mass_matrix_within_bar += r.fitted.mass_matrix <= kMassMatrixBar;
    s.gimbal_mass_matrix_max = std::max(s.gimbal_mass_matrix_max, r.fitted.gimbal_mass_matrix);
    s.model_mismatch_flagged += r.model_mismatch;
    for (const SeedParameter& p : r.params) {
      if (!p.identifiable) continue;
      const double z = p.error_over_std;
      if (std::isfinite(z)) {
        sum_z2 += z * z;
        ++finite;
      }
      s.beyond_1_std += !(z <= 1.0);
      s.beyond_2_std += !(z <= 2.0);
      s.beyond_3_std += !(z <= 3.0);
    }
  }
  s.error_over_std_rms = finite > 0 ? std::sqrt(sum_z2 / finite) : 0.0;
  if (!m.empty()) {
    std::sort(m.begin(), m.end());
    const std::size_t n = m.size();
    s.mass_matrix_median = n % 2 ? m[n / 2] : 0.5 * (m[n / 2 - 1] + m[n / 2]);
    s.mass_matrix_max = m.back();
  }
  return s;
}

namespace {

ModelError model_error_from_json(const nlohmann::json& j) {
  ModelError e;
  e.mass_matrix = j.at("mass_matrix").get<double>();
  e.arm_mass_matrix = j.at("arm_mass_matrix").get<double>();
  e.gimbal_mass_matrix = j.at("gimbal_mass_matrix").get<double>();
  e.gravity = j.at("gravity").get<double>();
  return e;
}

}  // namespace

nlohmann::json seed_result_to_json(const SeedResult& r) {
  nlohmann::json params = nlohmann::json::array(), outside = nlohmann::json::array();
  for (const SeedParameter& p : r.params) {
    nlohmann::json e{{"name", p.name},
                     {"identifiable", p.identifiable},
                     {"truth", p.truth},
                     {"value", p.value},
                     {"std", p.std},
                     {"std_statistical", p.std_statistical},
                     {"std_model", p.std_model},
                     {"std_law", p.std_law},
                     {"rel_error", p.rel_error}};
    // JSON has no infinity: null stands for it.
    e["error_over_std"] = std::isfinite(p.error_over_std) ? nlohmann::json(p.error_over_std)
                                                          : nlohmann::json(nullptr);
    params.push_back(e);
  }
  for (const SeedParameter& p : r.outside()) outside.push_back(p.name);
  return {{"seed", r.seed},
          {"converged", r.converged},
          {"identifiable_count", r.identifiable},
          {"checked", r.checked()},
          {"outside_bar", outside},
          {"condition_number", r.condition_number},
          {"residual_rms_n_m", r.residual_rms_n_m},
          {"excitation_condition_seeded", r.excitation_condition_seeded},
          {"excitation_condition_designed", r.excitation_condition_designed},
          {"model_mismatch", r.model_mismatch},
          {"model_mismatch_reasons", r.model_mismatch_reasons},
          {"truth_model_error",
           {{"fitted", model_error_to_json(r.fitted)}, {"prior", model_error_to_json(r.prior)}}},
          {"parameters", params}};
}

SeedResult seed_result_from_json(const nlohmann::json& j) {
  SeedResult r;
  r.seed = j.at("seed").get<std::uint64_t>();
  r.converged = j.at("converged").get<bool>();
  r.identifiable = j.at("identifiable_count").get<int>();
  r.condition_number = j.at("condition_number").get<double>();
  r.residual_rms_n_m = j.at("residual_rms_n_m").get<double>();
  r.excitation_condition_seeded = j.at("excitation_condition_seeded").get<double>();
  r.excitation_condition_designed = j.at("excitation_condition_designed").get<double>();
  r.model_mismatch = j.at("model_mismatch").get<bool>();
  r.model_mismatch_reasons = j.at("model_mismatch_reasons").get<std::vector<std::string>>();
  r.fitted = model_error_from_json(j.at("truth_model_error").at("fitted"));
  r.prior = model_error_from_json(j.at("truth_model_error").at("prior"));
  for (const nlohmann::json& e : j.at("parameters")) {
    SeedParameter p;
    p.name = e.at("name").get<std::string>();
    p.identifiable = e.at("identifiable").get<bool>();
    p.truth = e.at("truth").get<double>();
    p.value = e.at("value").get<double>();
    p.std = e.at("std").get<double>();
    p.std_statistical = e.at("std_statistical").get<double>();
    p.std_model = e.at("std_model").get<double>();
    p.std_law = e.value("std_law", 0.0);
    p.rel_error = e.at("rel_error").get<double>();
    const nlohmann::json& eos = e.at("error_over_std");
    p.error_over_std = eos.is_null() ? std::numeric_limits<double>::infinity() : eos.get<double>();
    r.params.push_back(p);
  }
  return r;
}

nlohmann::json seed_summary_to_json(const SeedSummary& s) {
  return {{"fits", s.fits},
          {"converged", s.converged},
          {"identifiable_checked", s.checked},
          {"outside_bar", s.outside},
          {"outside_bar_gimbal_coulomb", s.outside_gimbal_coulomb},
          {"mass_matrix_error_median", s.mass_matrix_median},
          {"mass_matrix_error_max", s.mass_matrix_max},
          {"mass_matrix_within_bar", s.mass_matrix_within_bar},
          {"gimbal_mass_matrix_error_max", s.gimbal_mass_matrix_max},
          {"model_mismatch_flagged", s.model_mismatch_flagged},
          {"error_over_std_rms", s.error_over_std_rms},
          {"beyond_1_std", s.beyond_1_std},
          {"beyond_2_std", s.beyond_2_std},
          {"beyond_3_std", s.beyond_3_std},
          {"bar",
           {{"parameter_rel_error", kParameterRelBar},
            {"parameter_error_over_std", kParameterStdBar},
            {"mass_matrix_rel_error", kMassMatrixBar}}}};
}

}  // namespace dentsim
