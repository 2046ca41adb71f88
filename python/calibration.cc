// Calibration from Python (docs/calibration.md): read a calibration log (calibration/log.h, what
// `dentsim excite` writes) as arrays, and fit a device model to one with Ceres
// (calibration/fit.h fit_calibration) under the options and defaults of `dentsim calibrate`,
// returning the numbers of its JSON report (same keys; `--truth` and `--plots` are the CLI's).
#include <cmath>
#include <optional>

#include "calibration/fit.h"
#include "calibration/log.h"
#include "device/phantom_device.h"
#include "device/velocity_estimator.h"
#include "python/module.h"
#include "reference/core/io.h"
#include "reference/phantom/phantom_params.h"

namespace dentsim::python {
namespace {

py::array_t<double> rows_of(const std::vector<Vec6>& v) {
  py::array_t<double> a({static_cast<py::ssize_t>(v.size()), py::ssize_t{6}});
  auto w = a.mutable_unchecked<2>();
  for (std::size_t k = 0; k < v.size(); ++k)
    for (int j = 0; j < 6; ++j) w(static_cast<py::ssize_t>(k), j) = v[k](j);
  return a;
}

std::vector<double> vec6_list(const Vec6& x) { return std::vector<double>(x.data(), x.data() + 6); }

py::dict log_dict(const CalibrationLog& log) {
  py::dict d;
  d["t"] = py::array_t<double>(static_cast<py::ssize_t>(log.t.size()), log.t.data());
  d["q"] = rows_of(log.q);
  d["qd"] = rows_of(log.qd);
  d["tau"] = rows_of(log.tau);
  d["comments"] = log.comments;
  return d;
}

// `dentsim calibrate`'s checks of the low-pass against the log (cli/cmd_calibrate.cc), with the
// argument names of calibrate().
void check_lowpass(double fc, const CalibrationLog& log, const std::string& path) {
  if (fc == 0.0) return;
  const double duration = log.t.back() - log.t.front();
  const double T = duration / (log.size() - 1);
  if (!(fc * T <= 0.45)) {
    throw InputError("calibrate: lowpass_hz " + std::to_string(fc) + ": above 0.45 / (time step " +
                     std::to_string(T) + " s of " + path + ") = " + std::to_string(0.45 / T) +
                     " Hz; expected a cut-off below the Nyquist frequency");
  }
  if (!(fc * duration >= 4.0)) {
    throw InputError("calibrate: lowpass_hz " + std::to_string(fc) + ": below 4 / (duration " +
                     std::to_string(duration) + " s of " + path +
                     ") = " + std::to_string(4.0 / duration) +
                     " Hz; the filter's transient would cover the whole log");
  }
}

py::dict calibrate(const py::handle& log_arg, const py::object& prior_arg, double lowpass_hz,
                   int lowpass_order, int max_samples, int max_iterations,
                   const py::object& velocity_lag, double torque_shift,
                   const std::string& coulomb_velocity, bool model_mismatch_term) {
  const std::string path = path_arg(log_arg, "calibrate: log");
  if (!(lowpass_hz >= 0.0 && std::isfinite(lowpass_hz))) {
    throw InputError("calibrate: lowpass_hz: expected a finite frequency >= 0 Hz, got " +
                     std::to_string(lowpass_hz));
  }
  if (max_samples < 100) throw InputError("calibrate: max_samples: expected >= 100");
  if (max_iterations < 1) throw InputError("calibrate: max_iterations: expected >= 1");
  if (!(std::abs(torque_shift) <= 100.0))
    throw InputError("calibrate: torque_shift: expected |s| <= 100");
  if (lowpass_order != 1 && lowpass_order != 2) {
    throw InputError("calibrate: lowpass_order: expected 1 or 2, got " +
                     std::to_string(lowpass_order));
  }
  if (coulomb_velocity != "filtered" && coulomb_velocity != "raw") {
    throw InputError("calibrate: coulomb_velocity: expected 'filtered' or 'raw', got '" +
                     coulomb_velocity + "'");
  }
  std::optional<double> lag;  // empty: "auto"
  if (!(py::isinstance<py::str>(velocity_lag) && velocity_lag.cast<std::string>() == "auto")) {
    if (!py::isinstance<py::float_>(velocity_lag) && !py::isinstance<py::int_>(velocity_lag)) {
      throw InputError("calibrate: velocity_lag: expected 'auto' or 0 <= ticks <= 100");
    }
    lag = velocity_lag.cast<double>();
    if (!(*lag >= 0.0 && *lag <= 100.0)) {
      throw InputError("calibrate: velocity_lag: expected 'auto' or 0 <= ticks <= 100, got " +
                       std::to_string(*lag));
    }
  }
  const PhantomParams prior = prior_arg.is_none()
                                  ? default_phantom_params()
                                  : load_phantom_params(path_arg(prior_arg, "calibrate: prior"));
  const CalibrationLog log = read_calibration_log(path);
  check_lowpass(lowpass_hz, log, path);

  FitOptions fo;
  fo.lowpass_hz = lowpass_hz;
  fo.lowpass_order = lowpass_order;
  fo.max_samples = max_samples;
  fo.max_iterations = max_iterations;
  fo.torque_shift_samples = torque_shift;
  fo.coulomb_from_filtered_velocity = coulomb_velocity == "filtered";
  fo.model_mismatch_term = model_mismatch_term;
  double velocity_lag_ticks = 0.0;
  if (lag) {
    velocity_lag_ticks = *lag;
  } else {
    // The simulated device's driver (the estimator `dentsim excite` runs), as the CLI's "auto".
    const double T = (log.t.back() - log.t.front()) / (log.size() - 1);
    const VelocityEstimatorParams vp = phantom_device_config(prior).velocity;
    velocity_lag_ticks =
        driver_velocity_lag_ticks(vp.filter == VelocityFilter::kFirstOrderLowPass, vp.cutoff_hz, T);
  }
  if (velocity_lag_ticks > 0.0) {
    fo.position_shift_samples = velocity_lag_ticks;
    fo.torque_shift_samples += velocity_lag_ticks + 0.5;
  }
  FitResult r;
  {
    py::gil_scoped_release release;  // Ceres: seconds
    r = fit_calibration(log, prior, fo);
  }

  py::dict j;
  j["log"] = path;
  j["converged"] = r.converged;
  j["solver_report"] = r.report;
  j["iterations"] = r.iterations;
  j["samples"] = r.samples;
  j["lowpass_hz"] = lowpass_hz;
  j["lowpass_order"] = fo.lowpass_order;
  j["velocity_lag_ticks"] = velocity_lag_ticks;
  j["coulomb_velocity"] = coulomb_velocity;
  j["position_shift_samples"] = fo.position_shift_samples;
  j["torque_shift_samples"] = fo.torque_shift_samples;
  j["residual_rms_n_m"] = r.residual_rms;
  j["residual_rms_joint_n_m"] = vec6_list(r.residual_rms_joint);
  j["condition_number"] = r.condition_number;
  j["identifiable_count"] = r.identifiable;
  j["std_newey_west_lags"] = r.hac_lags;
  py::list params, not_id;
  for (const FitParameter& fp : r.params) {
    py::dict e;
    e["name"] = fp.name;
    e["prior"] = fp.prior;
    e["value"] = fp.value;
    e["std"] = fp.std;
    e["std_statistical"] = fp.std_statistical;
    e["std_model"] = fp.std_model;
    e["std_white"] = fp.std_white;
    e["identifiable"] = fp.identifiable;
    if (!fp.identifiable) not_id.append(fp.name);
    params.append(e);
  }
  j["parameters"] = params;
  j["model_mismatch"] = r.model_mismatch;
  j["model_mismatch_reasons"] = r.model_mismatch_reasons;
  j["model_mismatch_term"] = fo.model_mismatch_term;
  py::dict diag;
  diag["lag1_autocorrelation"] = vec6_list(r.diagnostics.lag1_autocorrelation);
  diag["rms_slow_quarter_n_m"] = vec6_list(r.diagnostics.rms_slow);
  diag["rms_fast_quarter_n_m"] = vec6_list(r.diagnostics.rms_fast);
  j["residual_diagnostics"] = diag;
  j["not_identifiable_left_at_prior"] = not_id;
  // Beyond the CLI's report: the fitted model file's text (the CLI's -o MODEL; written there only
  // when the fit converged) and the samples used, for plots.
  j["fitted_model"] = phantom_params_to_text(r.fitted);
  py::dict used;
  used["t"] = py::array_t<double>(static_cast<py::ssize_t>(r.t.size()), r.t.data());
  used["tau_measured"] = rows_of(r.tau_measured);
  used["tau_predicted"] = rows_of(r.tau_predicted);
  j["samples_used"] = used;
  return j;
}

}  // namespace

void bind_calibration(py::module_& m) {
  m.def(
      "read_calibration_log",
      [](const py::handle& path) {
        return log_dict(read_calibration_log(path_arg(path, "read_calibration_log: path")));
      },
      py::arg("path"),
      "Read a calibration log (`dentsim excite -o LOG`; calibration/log.h): a dict of t (n,) [s], "
      "q, qd, tau (n, 6) [rad, rad/s, N m] and the comment lines. A bad log raises "
      "dentsim.InputError naming the file, the line and the problem.");
  m.def("calibrate", &calibrate, py::arg("log"), py::arg("prior") = py::none(),
        py::arg("lowpass_hz") = 10.0, py::arg("lowpass_order") = 2, py::arg("max_samples") = 3000,
        py::arg("max_iterations") = 100, py::arg("velocity_lag") = "auto",
        py::arg("torque_shift") = 0.0, py::arg("coulomb_velocity") = "filtered",
        py::arg("model_mismatch_term") = true,
        R"(Fit the device's inertial and friction parameters to a calibration log (Ceres), as
`dentsim calibrate LOG --json FILE -o MODEL` with the same options and defaults:
prior (model file; None: the shipped default), lowpass_hz, lowpass_order, max_samples,
max_iterations, velocity_lag ('auto' or ticks), torque_shift, coulomb_velocity ('filtered' or
'raw'), model_mismatch_term (False: --no-model-mismatch).

Returns the CLI's JSON report as a dict (converged, residual_rms_n_m, condition_number,
parameters [name, prior, value, std, ..., identifiable], ...) plus "fitted_model" (the fitted
device model file's text; check "converged" before using it) and "samples_used" (t,
tau_measured, tau_predicted arrays). The GIL is released during the fit.)");
}

}  // namespace dentsim::python
