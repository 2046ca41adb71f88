// Calibration from Python (docs/calibration.md): read a calibration log (calibration/log.h, what
// `dentsim excite` writes) as arrays, and fit a device model to one with Ceres under the options
// and defaults of `dentsim calibrate` (calibration/calibrate.h calibrate_log, the command's own
// implementation), returning its JSON report as a dict (`--truth` and `--plots` are the CLI's).
#include <cstdio>

#include "calibration/calibrate.h"
#include "calibration/fit.h"
#include "calibration/log.h"
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

py::dict log_dict(const CalibrationLog& log) {
  py::dict d;
  d["t"] = py::array_t<double>(static_cast<py::ssize_t>(log.t.size()), log.t.data());
  d["q"] = rows_of(log.q);
  d["qd"] = rows_of(log.qd);
  d["tau"] = rows_of(log.tau);
  d["comments"] = log.comments;
  // The reason of a log marked incomplete ("# incomplete: REASON"), None for a complete log.
  d["incomplete"] = log.incomplete.empty() ? py::object(py::none()) : py::str(log.incomplete);
  return d;
}

// The option names of calibrate() in its error messages.
CalibrateOptionNames argument_names() {
  CalibrateOptionNames n;
  n.lowpass_hz = "calibrate: lowpass_hz";
  n.lowpass_order = "calibrate: lowpass_order";
  n.max_samples = "calibrate: max_samples";
  n.max_iterations = "calibrate: max_iterations";
  n.velocity_lag = "calibrate: velocity_lag";
  n.torque_shift = "calibrate: torque_shift";
  n.coulomb_velocity = "calibrate: coulomb_velocity";
  n.min_speed = "calibrate: min_speed";
  n.coulomb_smoothing = "calibrate: coulomb_smoothing";
  n.coulomb_sign = "calibrate: coulomb_sign";
  n.allow_incomplete = "allow_incomplete=True";
  return n;
}

py::dict calibrate(const py::handle& log_arg, const py::object& prior_arg, double lowpass_hz,
                   int lowpass_order, int max_samples, int max_iterations,
                   const py::object& velocity_lag, double torque_shift,
                   const std::string& coulomb_velocity, bool model_mismatch_term,
                   double min_speed, const std::string& coulomb_smoothing,
                   const std::string& coulomb_sign, bool law_mismatch_term,
                   bool allow_incomplete) {
  const std::string path = path_arg(log_arg, "calibrate: log");
  const CalibrateOptionNames names = argument_names();
  CalibrateOptions o;
  o.lowpass_hz = lowpass_hz;
  o.lowpass_order = lowpass_order;
  o.max_samples = max_samples;
  o.max_iterations = max_iterations;
  o.torque_shift = torque_shift;
  o.coulomb_velocity = coulomb_velocity;
  o.model_mismatch_term = model_mismatch_term;
  o.min_speed = min_speed;
  o.coulomb_smoothing = coulomb_smoothing;
  o.coulomb_sign = coulomb_sign;
  o.law_mismatch_term = law_mismatch_term;
  o.allow_incomplete = allow_incomplete;
  // 'auto' or a number of ticks, as the command's text (17 significant digits read back exactly).
  if (py::isinstance<py::str>(velocity_lag)) {
    o.velocity_lag = velocity_lag.cast<std::string>();
  } else if (py::isinstance<py::float_>(velocity_lag) || py::isinstance<py::int_>(velocity_lag)) {
    char text[40];
    std::snprintf(text, sizeof text, "%.17g", velocity_lag.cast<double>());
    o.velocity_lag = text;
  } else {
    throw InputError(names.velocity_lag + ": expected 'auto' or 0 <= TICKS <= 100, got " +
                     py::repr(velocity_lag).cast<std::string>());
  }
  check_calibrate_options(o, names);
  const PhantomParams prior = prior_arg.is_none()
                                  ? default_phantom_params()
                                  : load_phantom_params(path_arg(prior_arg, "calibrate: prior"));
  const CalibrationLog log = read_calibration_log(path);
  CalibrateOutcome c;
  {
    py::gil_scoped_release release;  // Ceres: seconds
    c = calibrate_log(log, path, prior, o, names);
  }
  const FitResult& r = c.fit;
  py::dict j = json_to_py(calibration_report_json(c));
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
      "q, qd, tau (n, 6) [rad, rad/s, N m], the comment lines and \"incomplete\" (the reason of a log "
      "marked incomplete by `excite`, None for a complete one). A bad log raises "
      "dentsim.InputError naming the file, the line and the problem.");
  m.def("calibrate", &calibrate, py::arg("log"), py::arg("prior") = py::none(),
        py::arg("lowpass_hz") = 10.0, py::arg("lowpass_order") = 2, py::arg("max_samples") = 3000,
        py::arg("max_iterations") = 100, py::arg("velocity_lag") = "auto",
        py::arg("torque_shift") = 0.0, py::arg("coulomb_velocity") = "filtered",
        py::arg("model_mismatch_term") = true, py::arg("min_speed") = 0.2,
        py::arg("coulomb_smoothing") = "fit", py::arg("coulomb_sign") = "prior",
        py::arg("law_mismatch_term") = true, py::arg("allow_incomplete") = false,
        R"(Fit the device's inertial and friction parameters to a calibration log (Ceres), as
`dentsim calibrate LOG --json FILE -o MODEL` with the same options and defaults:
prior (model file; None: the shipped default), lowpass_hz, lowpass_order, max_samples,
max_iterations, velocity_lag ('auto' or ticks), torque_shift, coulomb_velocity ('filtered' or
'raw'), model_mismatch_term (False: --no-model-mismatch), min_speed [rad/s] (--min-speed),
coulomb_smoothing ('fit' or 'prior'), coulomb_sign ('erf', 'tanh', 'fit' or 'prior'),
law_mismatch_term (False: --no-law-mismatch), allow_incomplete (True: --allow-incomplete, fit a
log marked incomplete, an excitation stopped by a device fault, a guard or an interruption;
refused by default with dentsim.InputError naming the log and the reason, as the command; the
report's "log_incomplete" then says why).

Returns the CLI's JSON report as a dict (converged, residual_rms_n_m, condition_number,
parameters [name, prior, value, std, ..., identifiable], ...) plus "fitted_model" (the fitted
device model file's text; check "converged" before using it) and "samples_used" (t,
tau_measured, tau_predicted arrays). The GIL is released during the fit.)");
}

}  // namespace dentsim::python
