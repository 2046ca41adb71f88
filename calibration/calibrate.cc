#include "calibration/calibrate.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <limits>
#include <optional>
#include <random>
#include <stdexcept>

#include "device/phantom_device.h"
#include "device/velocity_estimator.h"
#include "reference/core/io.h"
#include "reference/phantom/phantom_model.h"

namespace dentsim {
namespace {

// The lag --velocity-lag gives in ticks; empty for 'auto'.
std::optional<double> fixed_velocity_lag(const std::string& text, const std::string& name) {
  if (text == "auto") return std::nullopt;
  double lag = 0.0;
  std::size_t used = 0;
  try {
    lag = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || !(lag >= 0.0 && lag <= 100.0)) {
    throw InputError(name + ": expected 'auto' or 0 <= TICKS <= 100, got '" + text + "'");
  }
  return lag;
}

// The zero-phase low-pass needs its cut-off below the Nyquist frequency (the Butterworth's
// prewarping tan(pi fc T) has a pole at fc T = 1/2) and its transient, one cut-off period trimmed
// at each end of the log, shorter than a quarter of the log.
void check_lowpass(double fc, const CalibrationLog& log, const std::string& path,
                   const std::string& name) {
  if (fc == 0.0) return;
  const double duration = log.t.back() - log.t.front();
  const double T = duration / (log.size() - 1);
  if (!(fc * T <= 0.45)) {
    throw InputError(name + " " + std::to_string(fc) + " Hz: above 0.45 / (time step " +
                     std::to_string(T) + " s of " + path + ") = " + std::to_string(0.45 / T) +
                     " Hz; expected a cut-off below the Nyquist frequency");
  }
  if (!(fc * duration >= 4.0)) {
    throw InputError(name + " " + std::to_string(fc) + " Hz: below 4 / (duration " +
                     std::to_string(duration) + " s of " + path +
                     ") = " + std::to_string(4.0 / duration) +
                     " Hz; the filter's transient would cover the whole log");
  }
}

std::vector<double> vec6_list(const Vec6& x) { return std::vector<double>(x.data(), x.data() + 6); }

}  // namespace

void check_calibrate_options(const CalibrateOptions& o, const CalibrateOptionNames& names) {
  if (!(o.lowpass_hz >= 0.0 && std::isfinite(o.lowpass_hz))) {
    throw InputError(names.lowpass_hz + ": expected a finite frequency >= 0 Hz, got " +
                     std::to_string(o.lowpass_hz));
  }
  if (o.max_samples < 100) throw InputError(names.max_samples + ": expected >= 100");
  if (o.max_iterations < 1) throw InputError(names.max_iterations + ": expected >= 1");
  if (!(std::abs(o.torque_shift) <= 100.0))
    throw InputError(names.torque_shift + ": expected |s| <= 100");
  if (o.lowpass_order != 1 && o.lowpass_order != 2) {
    throw InputError(names.lowpass_order + ": expected 1 or 2, got " +
                     std::to_string(o.lowpass_order));
  }
  if (o.coulomb_velocity != "filtered" && o.coulomb_velocity != "raw") {
    throw InputError(names.coulomb_velocity + ": expected 'filtered' or 'raw', got '" +
                     o.coulomb_velocity + "'");
  }
  if (!(o.min_speed >= 0.0 && o.min_speed <= 10.0)) {
    throw InputError(names.min_speed + ": expected a speed in [0, 10] rad/s, got " +
                     std::to_string(o.min_speed));
  }
  if (o.coulomb_smoothing != "fit" && o.coulomb_smoothing != "prior") {
    throw InputError(names.coulomb_smoothing + ": expected 'fit' or 'prior', got '" +
                     o.coulomb_smoothing + "'");
  }
  if (o.coulomb_sign != "erf" && o.coulomb_sign != "tanh" && o.coulomb_sign != "prior" &&
      o.coulomb_sign != "fit") {
    throw InputError(names.coulomb_sign + ": expected 'erf', 'tanh', 'fit' or 'prior', got '" +
                     o.coulomb_sign + "'");
  }
  fixed_velocity_lag(o.velocity_lag, names.velocity_lag);
}

bool CalibrateOutcome::finite() const {
  bool ok = std::isfinite(fit.residual_rms);
  for (const FitParameter& fp : fit.params) ok = ok && std::isfinite(fp.value);
  return ok;
}

std::string fitted_model_name(const std::string& prior_name, const std::string& log_path,
                              const std::string& date) {
  return prior_name + " (fitted from " + log_path + " on " + date + ")";
}

std::string utc_date_today() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[16];
  std::strftime(buf, sizeof buf, "%Y-%m-%d", &tm);
  return buf;
}

CalibrateOutcome calibrate_log(const CalibrationLog& log, const std::string& log_path,
                               const PhantomParams& prior, const CalibrateOptions& o,
                               const CalibrateOptionNames& names) {
  check_calibrate_options(o, names);
  if (!log.incomplete.empty() && !o.allow_incomplete) {
    throw InputError(log_path + ": the log is marked incomplete (" + log.incomplete +
                     "); a fit of it is refused unless " + names.allow_incomplete + " is given");
  }
  check_lowpass(o.lowpass_hz, log, log_path, names.lowpass_hz);
  CalibrateOutcome c;
  c.log_path = log_path;
  c.options = o;
  FitOptions& fo = c.fit_options;
  fo.lowpass_hz = o.lowpass_hz;
  fo.lowpass_order = o.lowpass_order;
  fo.max_samples = o.max_samples;
  fo.max_iterations = o.max_iterations;
  fo.torque_shift_samples = o.torque_shift;
  fo.coulomb_from_filtered_velocity = o.coulomb_velocity == "filtered";
  fo.model_mismatch_term = o.model_mismatch_term;
  fo.law_mismatch_term = o.law_mismatch_term;
  fo.min_speed_rad_s = o.min_speed;
  fo.fit_coulomb_smoothing = o.coulomb_smoothing == "fit";
  if (o.coulomb_sign == "prior") {
    fo.coulomb_sign.reset();
  } else {
    fo.coulomb_sign = o.coulomb_sign == "tanh" ? CoulombSign::kTanh : CoulombSign::kErf;
  }
  fo.fit_coulomb_sign = o.coulomb_sign == "fit";
  if (const std::optional<double> lag = fixed_velocity_lag(o.velocity_lag, names.velocity_lag)) {
    c.velocity_lag_ticks = *lag;
  } else {
    // The simulated device's driver (the estimator `dentsim excite` runs).
    const double T = (log.t.back() - log.t.front()) / (log.size() - 1);
    const VelocityEstimatorParams vp = phantom_device_config(prior).velocity;
    c.velocity_lag_ticks =
        driver_velocity_lag_ticks(vp.filter == VelocityFilter::kFirstOrderLowPass, vp.cutoff_hz, T);
  }
  if (c.velocity_lag_ticks > 0.0) {
    fo.position_shift_samples = c.velocity_lag_ticks;
    fo.torque_shift_samples += c.velocity_lag_ticks + 0.5;
  }
  c.fit = fit_calibration(log, prior, fo);
  c.fit.fitted.name = fitted_model_name(prior.name, log_path, utc_date_today());
  c.log_incomplete = log.incomplete;
  return c;
}

ModelError truth_model_error(const PhantomParams& truth, const PhantomParams& model, int poses) {
  const PhantomModelD mt(truth), mm(model);
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  ModelError e;
  for (int k = 0; k < poses; ++k) {
    Vec6 q;
    for (int i = 0; i < 6; ++i)
      q(i) = truth.q_min_rad(i) + u(rng) * (truth.q_max_rad(i) - truth.q_min_rad(i));
    const Mat6 Mt = mt.M(q);
    const Mat6 M = mm.M(q);
    e.mass_matrix = std::max(e.mass_matrix, (M - Mt).norm() / Mt.norm());
    e.arm_mass_matrix =
        std::max(e.arm_mass_matrix, (M.topLeftCorner<3, 3>() - Mt.topLeftCorner<3, 3>()).norm() /
                                        Mt.topLeftCorner<3, 3>().norm());
    e.gimbal_mass_matrix = std::max(
        e.gimbal_mass_matrix, (M.bottomRightCorner<3, 3>() - Mt.bottomRightCorner<3, 3>()).norm() /
                                  Mt.bottomRightCorner<3, 3>().norm());
    const Vec6 gt = mt.g(q);
    e.gravity = std::max(e.gravity, (mm.g(q) - gt).norm() / gt.norm());
  }
  return e;
}

nlohmann::json model_error_to_json(const ModelError& e) {
  return {{"mass_matrix", e.mass_matrix},
          {"arm_mass_matrix", e.arm_mass_matrix},
          {"gimbal_mass_matrix", e.gimbal_mass_matrix},
          {"gravity", e.gravity}};
}

TruthComparison compare_with_truth(const FitResult& fit, const PhantomParams& prior,
                                   const PhantomParams& truth) {
  TruthComparison c;
  const CalibVec xt = pack_calib_params(truth);
  for (std::size_t i = 0; i < fit.params.size(); ++i) {
    const FitParameter& fp = fit.params[i];
    ParameterTruth pt;
    pt.truth = xt(static_cast<Eigen::Index>(i));
    if (fp.identifiable) {
      const double err = std::abs(fp.value - pt.truth);
      pt.rel_error = err / std::max(std::abs(pt.truth), 1e-300);
      pt.error_over_std = fp.std > 0.0 ? err / fp.std : std::numeric_limits<double>::infinity();
      c.max_rel_error = std::max(c.max_rel_error, pt.rel_error);
    }
    c.params.push_back(pt);
  }
  c.fitted = truth_model_error(truth, fit.fitted);
  c.prior = truth_model_error(truth, prior);
  return c;
}

nlohmann::json calibration_report_json(const CalibrateOutcome& c, const TruthComparison* truth) {
  const FitResult& r = c.fit;
  const FitOptions& fo = c.fit_options;
  nlohmann::json j;
  j["log"] = c.log_path;
  j["converged"] = r.converged;
  j["solver_report"] = r.report;
  j["iterations"] = r.iterations;
  j["samples"] = r.samples;
  j["lowpass_hz"] = c.options.lowpass_hz;
  j["lowpass_order"] = fo.lowpass_order;
  j["velocity_lag_ticks"] = c.velocity_lag_ticks;
  j["coulomb_velocity"] = c.options.coulomb_velocity;
  j["position_shift_samples"] = fo.position_shift_samples;
  j["torque_shift_samples"] = fo.torque_shift_samples;
  j["residual_rms_n_m"] = r.residual_rms;
  j["residual_rms_joint_n_m"] = vec6_list(r.residual_rms_joint);
  j["condition_number"] = r.condition_number;
  j["identifiable_count"] = r.identifiable;
  j["std_newey_west_lags"] = r.hac_lags;
  nlohmann::json params = nlohmann::json::array(), not_id = nlohmann::json::array(),
                 moved = nlohmann::json::array();
  for (std::size_t i = 0; i < r.params.size(); ++i) {
    const FitParameter& fp = r.params[i];
    nlohmann::json e{{"name", fp.name},
                     {"prior", fp.prior},
                     {"value", fp.value},
                     {"std", fp.std},
                     {"std_statistical", fp.std_statistical},
                     {"std_model", fp.std_model},
                     {"std_law", fp.std_law},
                     {"std_white", fp.std_white},
                     {"identifiable", fp.identifiable}};
    // Not identifiable: left at the prior only if its value is the prior's. A parameter in a
    // near-null direction that also enters an identifiable combination moves with it (issue #33:
    // upper_arm.mass_kg was listed as left at the prior at 0.2359 -> 0.2625), and one below the
    // noise floor keeps the value the data barely pin.
    if (!fp.identifiable) {
      if (std::abs(fp.value - fp.prior) <= kLeftAtPriorRelTol * std::abs(fp.prior)) {
        not_id.push_back(fp.name);
      } else {
        char why[200];
        if (fp.structurally_identifiable) {
          std::snprintf(why, sizeof why,
                        "practically: statistical std %.3g above %.3g x the prior (%.3g)",
                        fp.std_statistical, fo.max_rel_std, fp.prior);
        } else {
          std::snprintf(why, sizeof why,
                        "structurally: in the near-null space, moved with the identifiable "
                        "combinations it enters");
        }
        moved.push_back(
            {{"name", fp.name}, {"prior", fp.prior}, {"value", fp.value}, {"why", why}});
      }
    }
    if (truth && fp.identifiable) {
      const ParameterTruth& pt = truth->params[i];
      e["truth"] = pt.truth;
      e["rel_error"] = pt.rel_error;
      e["error_over_std"] = pt.error_over_std;
    }
    params.push_back(e);
  }
  j["parameters"] = params;
  j["model_mismatch"] = r.model_mismatch;
  j["model_mismatch_reasons"] = r.model_mismatch_reasons;
  j["model_mismatch_term"] = fo.model_mismatch_term;
  j["law_mismatch_term"] = fo.model_mismatch_term && fo.law_mismatch_term;
  j["residual_diagnostics"] = {
      {"lag1_autocorrelation", vec6_list(r.diagnostics.lag1_autocorrelation)},
      {"rms_slow_quarter_n_m", vec6_list(r.diagnostics.rms_slow)},
      {"rms_fast_quarter_n_m", vec6_list(r.diagnostics.rms_fast)}};
  {
    const ResidualDiagnostics& dg = r.diagnostics;
    nlohmann::json& jd = j["residual_diagnostics"];
    nlohmann::json rho = nlohmann::json::array(), white = nlohmann::json::array(),
                   length = nlohmann::json::array(), bins = nlohmann::json::array();
    for (int q = 0; q < 6; ++q) {
      rho.push_back(dg.autocorrelation[q]);
      white.push_back(dg.white[q]);
      length.push_back(dg.correlation_length[q]);
      const ResidualDiagnostics::VelocityBins& vb = dg.residual_vs_velocity[q];
      bins.push_back(
          {{"qd_rad_s", vb.qd}, {"mean_n_m", vb.mean}, {"rms_n_m", vb.rms}, {"rows", vb.rows}});
    }
    jd["autocorrelation_lags"] = dg.autocorrelation_lags;
    jd["autocorrelation"] = rho;
    jd["ljung_box_q"] = vec6_list(dg.ljung_box_q);
    jd["ljung_box_threshold_99"] = dg.ljung_box_threshold;
    jd["white"] = white;
    jd["correlation_length_samples"] = length;
    jd["newey_west_lags"] = r.hac_lags;
    jd["residual_vs_velocity"] = bins;
  }
  j["not_identifiable_left_at_prior"] = not_id;
  j["not_identifiable_moved"] = moved;
  j["log_incomplete"] =
      c.log_incomplete.empty() ? nlohmann::json(nullptr) : nlohmann::json(c.log_incomplete);
  j["fitted_model_name"] = r.fitted.name;
  // The friction law's shape: rows dropped near stiction, v_s per joint and its profile.
  j["min_speed_rad_s"] = fo.min_speed_rad_s;
  j["rows_used"] = std::vector<int>(r.rows_used.data(), r.rows_used.data() + 6);
  nlohmann::json smoothing{{"fitted", fo.fit_coulomb_smoothing},
                           {"v_s_rad_s", vec6_list(r.coulomb_smoothing_rad_s)}};
  smoothing["sign"] = nlohmann::json::array();
  for (CoulombSign cs : r.coulomb_sign) smoothing["sign"].push_back(coulomb_sign_name(cs));
  if (fo.fit_coulomb_smoothing) {
    nlohmann::json rss = nlohmann::json::array();
    for (const std::vector<double>& curve : r.coulomb_smoothing_profile.rss) rss.push_back(curve);
    nlohmann::json cand_sign = nlohmann::json::array();
    for (CoulombSign cs : r.coulomb_smoothing_profile.sign)
      cand_sign.push_back(coulomb_sign_name(cs));
    smoothing["profile"] = {{"v_s_rad_s", r.coulomb_smoothing_profile.v_s_rad_s},
                            {"sign", cand_sign},
                            {"rss_n2_m2", rss}};
  }
  j["coulomb_smoothing"] = smoothing;
  if (truth) {
    j["max_rel_error"] = truth->max_rel_error;
    // The base parameters (what the observer uses): M(q) and g(q) of the fitted model and of the
    // prior against the truth (truth_model_error).
    j["truth_model_error"] = {{"fitted", model_error_to_json(truth->fitted)},
                              {"prior", model_error_to_json(truth->prior)}};
  }
  return j;
}

}  // namespace dentsim
