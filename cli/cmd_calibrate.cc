// `dentsim excite` and `dentsim calibrate` (issue #5, docs/calibration.md).
//
//   dentsim excite [--device MODEL] -o LOG [--duration S] [--seed N]
//     runs a seeded Fourier excitation (calibration/excitation.h) under joint-space PD tracking on
//     the simulated Phantom built from MODEL (default: the built-in Premium 1.5A model) and
//     writes the calibration log (calibration/log.h).
//   dentsim calibrate LOG --json FILE -o MODEL [--prior MODEL] [--truth MODEL] [--plots DIR]
//     fits the inertial and friction parameters (calibration/calibrate.h: the options' checks, the
//     velocity lag, the fit of calibration/fit.h, the report), writes the fitted device model
//     file and the report; with --truth adds each identifiable parameter's true value and
//     max_rel_error. A fit that did not converge writes the JSON (converged: false), no model file,
//     and exits with status 1.
#include <algorithm>
#include <atomic>
#include <csignal>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "device/backend.h"
#include "calibration/calibrate.h"
#include "calibration/excitation.h"
#include "calibration/fit.h"
#include "calibration/log.h"
#include "cli/interrupt.h"
#include "cli/plot.h"
#include "cli/registry.h"
#include "device/fault_injection.h"
#include "device/hdapi/hdapi_device.h"
#include "device/phantom_device.h"
#include "device/safety_chain.h"
#include "device/simulated_phantom.h"
#include "reference/core/io.h"
#include "reference/phantom/phantom_model.h"
#include "reference/phantom/phantom_params.h"

namespace dentsim::cli {
namespace {

struct ExciteOptions {
  std::string device, out;
  std::string hd_library, model;  // --device hdapi: the library; --model: the prior (guarded run)
  double duration = 30.0;
  std::uint64_t seed = 1;
  bool no_friction = false, ideal_sensing = false;
  std::string friction_law = "frictionloss";
  int design_iterations = 40;
  std::string inject_fault;
};

// The excitation: the seeded series, then designed for identification (design_excitation) unless
// --design-iterations 0; prints and returns the condition numbers for the log's comments.
Excitation make_excitation(const PhantomParams& p, const Vec6& q0, const ExciteOptions& o,
                           std::vector<std::string>* comments) {
  ExcitationParams ep;
  ep.seed = o.seed;
  ExcitationDesign d = design_excitation(p, q0, ep, o.design_iterations);
  std::string what = "excitation: Fourier f_base " + std::to_string(ep.base_frequency_hz) +
                     " Hz, " + std::to_string(ep.harmonics) + " harmonics, seed " +
                     std::to_string(o.seed);
  char buf[200];
  std::snprintf(buf, sizeof buf,
                "regressor condition number %.4g (seeded series) -> %.4g (designed: %d "
                "iterations, %d kept), rank %d",
                d.condition_seeded, d.condition_designed, d.iterations, d.accepted, d.rank);
  std::printf("excite: %s\n", buf);
  comments->push_back(" " + what);
  comments->push_back(std::string(" ") + buf);
  return std::move(d.excitation);
}

// SIGINT / SIGTERM while the excitation runs: the run stops cleanly (the excitation faded out,
// the torque ramped down) and the log up to the signal is written, marked incomplete. The
// previous handlers come back when the run ends.
std::atomic<bool> g_excite_stop{false};
std::atomic<int> g_excite_signal{0};
extern "C" void excite_on_signal(int sig) {
  g_excite_signal.store(sig);
  g_excite_stop.store(true);
}
class ExciteSignals {
 public:
  ExciteSignals() {
    g_excite_stop.store(false);
    g_excite_signal.store(0);
    struct sigaction sa {};
    sa.sa_handler = excite_on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &old_int_);
    sigaction(SIGTERM, &sa, &old_term_);
  }
  ~ExciteSignals() {
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
  }
  ExciteSignals(const ExciteSignals&) = delete;
  ExciteSignals& operator=(const ExciteSignals&) = delete;

 private:
  struct sigaction old_int_ {}, old_term_ {};
};

// The guarded run's hard speed stop, from the device's velocity limit (issue #33): at half the
// velocity the Phantom's safety chain trips at (phantom_safety_limits: qd_max 20 rad/s per joint,
// where the hardware reports HD_EXCEEDED_MAX_VELOCITY; docs/hardware.md §5), as a multiple of the
// excitation's own speed limit (2 rad/s): 0.5 x 20 / 2 = 5, i.e. 10 rad/s. The factor 2 covers
// the guard's lag: it acts on |qd| low-passed at 20 Hz (time constant 8 ms), so a speed still
// rising when the stop fires overshoots the filtered value; the stop, zero torque, must come
// before the chain's own fault. The excitation never comes near it on a device it tracks (the
// emulator: <= 4.2 rad/s on the gimbal, low-passed, at load average 10 without catch-up; the
// 3 x 2 = 6 rad/s of the library's default stop was crossed only through the emulator's
// catch-up of skipped scheduler ticks with the torque held, docs/hardware.md §7).
double velocity_stop_from_device_limit(const Excitation& exc, const PhantomParams& p) {
  const SafetyLimits limits = phantom_safety_limits(p.q_min_rad, p.q_max_rad);
  double stop = std::numeric_limits<double>::infinity();
  for (int j = 0; j < 6; ++j) {
    stop = std::min(stop, 0.5 * limits.qd_max(j) / exc.params().qd_max_rad_s(j));
  }
  return stop;
}

// What a guarded run (run_guarded_excitation) did, for the log's comments.
void add_guard_comments(const ExcitationOutcome& r, std::vector<std::string>* comments) {
  char buf[400];
  std::snprintf(buf, sizeof buf,
                " guarded run (prior model unknown to be right): hold, approach, settle, then "
                "the excitation; gravity offset at home (integral action) [N m]: %.4g %.4g %.4g "
                "%.4g %.4g %.4g",
                r.gravity_offset(0), r.gravity_offset(1), r.gravity_offset(2),
                r.gravity_offset(3), r.gravity_offset(4), r.gravity_offset(5));
  comments->push_back(buf);
  std::snprintf(buf, sizeof buf,
                " guards: max |tau_cmd| / tau_max %.3f, %ld of %ld ticks clamped, %ld late, "
                "%ld slowed (min time scale %.3f), max low-passed speed %.3g rad/s",
                r.max_command_ratio, r.clamped_ticks, r.ticks, r.late_ticks, r.guard_ticks,
                r.min_time_scale, r.max_speed_rad_s);
  comments->push_back(buf);
}

// Writes the log (complete or not) and says so; an incomplete run then exits 3 (a device fault
// or a guard: not bad input) or 128 + the signal, with one line naming the reason and the time.
void finish_excite(const ExciteOptions& o, const ExcitationOutcome& r, const std::string& where) {
  write_calibration_log(o.out, r.log);
  if (r.complete) {
    std::printf("excite: %d samples over %.3f s%s -> %s\n", r.log.size(),
                r.log.size() > 0 ? r.log.t.back() - r.log.t.front() : 0.0, where.c_str(),
                o.out.c_str());
    if (r.fault != kFaultNone) {
      std::printf("excite: warning: device fault %s during the stop, after the log\n",
                  fault_string(r.fault).c_str());
    }
    return;
  }
  const std::string msg = "excite: " + r.stop_reason + "; the log up to the stop (" +
                          std::to_string(r.log.size()) + " samples, marked incomplete) -> " +
                          o.out + " (`dentsim calibrate --allow-incomplete` fits it)";
  if (r.interrupted && r.fault == kFaultNone) {
    const int sig = g_excite_signal.load();
    throw ExitStatusError(128 + (sig > 0 ? sig : SIGINT), msg);
  }
  throw ExitStatusError(3, msg);
}

void setup_excite(CLI::App& app) {
  auto opt = std::make_shared<ExciteOptions>();
  CLI::App* sub = app.add_subcommand(
      "excite",
      "Run a safe excitation trajectory (Fourier series within the joint, velocity and torque\n"
      "limits, designed for a low regressor condition number) under joint-space PD tracking on\n"
      "the simulated Phantom or a real one (--device hdapi, guarded) and log t, q, qd (driver\n"
      "estimate) and the applied torque to a CSV calibration log. A device fault, a guard, SIGINT\n"
      "or SIGTERM stops it cleanly: the log up to the stop is written, marked incomplete, and the\n"
      "exit status is 3 (fault or guard) or 130 / 143 (interrupted)");
  sub->add_option("--device", opt->device,
                  "device model file of the simulated Phantom (default: built-in Premium 1.5A),\n"
                  "or 'hdapi': a Phantom through OpenHaptics (or the project's emulator), run as\n"
                  "a device of unknown model (guarded: hold, gravity taken up by integral action,\n"
                  "approach, excitation with torque clamp and velocity guard; docs/hardware.md)");
  sub->add_option("--hd-library", opt->hd_library,
                  "with --device hdapi: the HDAPI library (default: DENTSIM_HD_LIBRARY, then\n"
                  "libHD.so, libHD.so.3.0, ...)");
  sub->add_option("--model", opt->model,
                  "the prior model file the excitation is designed and tracked with (default:\n"
                  "built-in Premium 1.5A); with a simulated --device, runs the guarded procedure\n"
                  "of a new device on it (the device's own model is then not used)");
  sub->add_option("-o,--output", opt->out, "calibration log to write (CSV)")->required();
  sub->add_option("--duration", opt->duration, "length of the excitation [s], 1..3600 (default 30)");
  sub->add_option("--seed", opt->seed, "seed of the Fourier coefficients, 0..2^64-1 (default 1)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--design-iterations", opt->design_iterations,
                  "steps of the search that lowers the regressor's condition number from the\n"
                  "seeded series within the limits (0: the seeded series as drawn; default 40)")
      ->check(CLI::Range(0, 100000));
  sub->add_flag("--no-friction", opt->no_friction,
                "simulate the device without Coulomb friction (MuJoCo frictionloss off)");
  sub->add_option(
      "--friction-law", opt->friction_law,
      "how the simulated device's Coulomb friction acts: 'frictionloss' (MuJoCo's soft\n"
      "constraint, default) or 'tanh' (the model's f_c tanh(qd / v_s) as a torque)");
  sub->add_flag("--ideal-sensing", opt->ideal_sensing,
                "track and log the exact joint angles and velocities (no quantisation, no\n"
                "velocity estimator): a harness for separating sensing from the plant");
  sub->add_option("--inject-fault", opt->inject_fault,
                  "inject a device fault, KIND@T (T [s] on the device clock; kinds as `dentsim run\n"
                  "--inject-fault`): the run stops there, its log kept and marked incomplete");
  sub->callback([opt] {
    if (!(std::isfinite(opt->duration) && opt->duration >= 1.0 && opt->duration <= 3600.0)) {
      throw InputError("--duration: expected 1 <= S <= 3600 s, got " +
                       std::to_string(opt->duration));
    }
    const InjectedFault fault = opt->inject_fault.empty()
                                    ? InjectedFault{}
                                    : parse_injected_fault(opt->inject_fault, "--inject-fault");
    if (find_device_backend(opt->device) == DeviceBackend::kHdapi) {
      check_output_paths({{"-o", opt->out}}, {{"--model", opt->model}});
      const PhantomParams p =
          opt->model.empty() ? default_phantom_params() : load_phantom_params(opt->model);
      // The excitation is designed around the prior's home pose before the device is opened
      // (the design takes a while; a device is never left holding a guessed torque meanwhile).
      std::vector<std::string> exc_comments;
      const Excitation exc = make_excitation(p, Vec6(phantom_home_q(p)), *opt, &exc_comments);
      HdapiConfig hc;
      hc.library = opt->hd_library;
      HdapiDevice dev(hc);
      FaultInjectingDevice injected(dev, fault);
      Device& d = fault.kind == InjectedFault::kNone ? static_cast<Device&>(dev) : injected;
      ExcitationOutcome r;
      {
        ExciteSignals signals;
        GuardedExcitationParams gp;
        gp.velocity_stop = velocity_stop_from_device_limit(exc, p);
        r = run_guarded_excitation(d, p, exc, opt->duration, gp, TrackingParams{}, &g_excite_stop);
      }
      r.log.comments.push_back(" device: hdapi (" + dev.info().library + ", model " +
                               dev.info().model + ", serial " + dev.info().serial + ")");
      r.log.comments.push_back(" prior model (design and feed-forward): " + p.name);
      r.log.comments.insert(r.log.comments.end(), exc_comments.begin(), exc_comments.end());
      add_guard_comments(r, &r.log.comments);
      finish_excite(*opt, r, " on the hdapi device");
      return;
    }
    if (!opt->hd_library.empty()) throw InputError("--hd-library goes with --device hdapi");
    if (opt->ideal_sensing && !opt->model.empty()) {
      throw InputError("--ideal-sensing goes with the simulated device's own model, not --model");
    }
    check_output_paths({{"-o", opt->out}}, {{"--device", opt->device}, {"--model", opt->model}});
    const PhantomParams p =
        opt->device.empty() ? default_phantom_params() : load_phantom_params(opt->device);
    const bool guarded = !opt->model.empty();
    const PhantomParams prior = guarded ? load_phantom_params(opt->model) : p;
    const VecX home = phantom_home_q(p);
    std::vector<std::string> exc_comments;
    const Excitation exc = make_excitation(prior, Vec6(phantom_home_q(prior)), *opt, &exc_comments);
    SimulatedDeviceConfig dc = phantom_device_config(p);
    dc.friction_on = !opt->no_friction;
    if (opt->friction_law == "tanh") {
      dc.friction_law = SimulatedDeviceConfig::FrictionLaw::kTanh;
    } else if (opt->friction_law != "frictionloss") {
      throw InputError("--friction-law: expected 'frictionloss' or 'tanh', got '" +
                       opt->friction_law + "'");
    }
    if (opt->ideal_sensing) dc.quantize = false;
    SimulatedPhantom dev(phantom_plant(p), dc, home);
    FaultInjectingDevice injected(dev, fault);
    Device& d = fault.kind == InjectedFault::kNone ? static_cast<Device&>(dev) : injected;
    ExactState exact;
    if (opt->ideal_sensing) exact = {&dev.true_q(), &dev.true_qd()};
    ExcitationOutcome r;
    {
      ExciteSignals signals;
      GuardedExcitationParams gp;  // the new-device procedure, as on a device through HDAPI
      gp.velocity_stop = velocity_stop_from_device_limit(exc, prior);
      r = guarded ? run_guarded_excitation(d, prior, exc, opt->duration, gp, TrackingParams{},
                                           &g_excite_stop)
                  : run_excitation_until_stop(d, p, exc, opt->duration, TrackingParams{}, exact,
                                              &g_excite_stop);
    }
    CalibrationLog& log = r.log;
    if (opt->no_friction) log.comments.push_back(" device friction (frictionloss) off");
    if (opt->friction_law == "tanh") log.comments.push_back(" device friction law: tanh");
    if (opt->ideal_sensing) log.comments.push_back(" ideal sensing: exact q and qd logged");
    log.comments.push_back(" device: " + p.name +
                           (opt->device.empty() ? "" : " (" + opt->device + ")"));
    if (guarded) log.comments.push_back(" prior model (design and feed-forward): " + prior.name);
    if (fault.kind != InjectedFault::kNone) {
      log.comments.push_back(" injected fault: " + injected_fault_string(fault));
    }
    log.comments.insert(log.comments.end(), exc_comments.begin(), exc_comments.end());
    if (guarded) add_guard_comments(r, &log.comments);
    finish_excite(*opt, r, "");
  });
}
DENTSIM_REGISTER_COMMAND(setup_excite);

// The command's files and flags; the fit's options are the library's (calibration/calibrate.h).
struct CalibrateFlags {
  std::string log, json, out, prior, truth, plots;
  CalibrateOptions fit;
  bool no_model_mismatch = false;
  bool no_law_mismatch = false;
};

void write_plots(const FitResult& r, const std::string& dir) {
  std::filesystem::create_directories(dir);
  std::vector<plot::Figure> panels;
  std::vector<double> all_res;
  for (int j = 0; j < 6; ++j) {
    plot::Figure f{"joint " + std::to_string(j + 1), "time [s]", "torque [N m]", {}};
    plot::Series meas{"measured (rows used)", r.t, {}}, pred{"predicted", r.t, {}};
    // Only the rows the fit used: a dropped slow row (--min-speed) is a gap, not zero torque.
    constexpr double kGap = std::numeric_limits<double>::quiet_NaN();
    for (int k = 0; k < r.samples; ++k) {
      const bool used = r.row_used[k][j];
      meas.y.push_back(used ? r.tau_measured[k](j) : kGap);
      pred.y.push_back(used ? r.tau_predicted[k](j) : kGap);
      if (used) all_res.push_back(r.tau_predicted[k](j) - r.tau_measured[k](j));
    }
    pred.dashed = true;
    f.series.push_back(meas);
    f.series.push_back(pred);
    panels.push_back(f);
  }
  plot::write_png(panels, dir + "/torque_fit.png", 2);
  // Residual histogram: 41 bins over +-4 RMS, drawn as points joined by a line.
  const double h = std::max(4.0 * r.residual_rms, 1e-12);
  const int bins = 41;
  std::vector<double> x(bins), y(bins, 0.0);
  for (int b = 0; b < bins; ++b) x[b] = -h + (2.0 * h) * (b + 0.5) / bins;
  for (double e : all_res) {
    const int b = static_cast<int>(std::floor((e + h) / (2.0 * h) * bins));
    if (b >= 0 && b < bins) y[b] += 1.0;
  }
  plot::Figure hist{"residual histogram (all joints)", "predicted - measured [N m]", "count", {}};
  plot::Series s{"residuals", x, y};
  s.points = true;
  hist.series.push_back(s);
  plot::write_png({hist}, dir + "/residual_histogram.png");
  // The residual against the signed velocity (mean and RMS per bin of equal count), per joint.
  const ResidualDiagnostics& dg = r.diagnostics;
  std::vector<plot::Figure> vel;
  for (int j = 0; j < 6; ++j) {
    const ResidualDiagnostics::VelocityBins& vb = dg.residual_vs_velocity[j];
    plot::Figure f{"joint " + std::to_string(j + 1) + ": residual vs velocity",
                   "low-passed qd [rad/s]",
                   "predicted - measured [N m]",
                   {}};
    plot::Series mean{"mean", vb.qd, vb.mean}, rms{"RMS", vb.qd, vb.rms};
    mean.points = true;
    rms.dashed = true;
    f.series.push_back(mean);
    f.series.push_back(rms);
    vel.push_back(f);
  }
  plot::write_png(vel, dir + "/residual_vs_velocity.png", 2);
  // Autocorrelation per joint with the white-noise band (2 / sqrt(rows)) and the Newey-West window.
  plot::Figure ac{"residual autocorrelation (kept rows)", "lag [samples used]", "rho", {}};
  std::vector<double> lags;
  for (int l = 1; l <= dg.autocorrelation_lags; ++l) lags.push_back(l);
  for (int j = 0; j < 6; ++j) {
    ac.series.push_back({"joint " + std::to_string(j + 1), lags, dg.autocorrelation[j]});
  }
  const double band = 2.0 / std::sqrt(std::max(1, r.rows_used.maxCoeff()));
  const double last = dg.autocorrelation_lags;
  plot::Series hi{"white-noise band", {1.0, last}, {band, band}},
      lo{"", {1.0, last}, {-band, -band}};
  hi.dashed = lo.dashed = true;
  ac.series.push_back(hi);
  lo.color = static_cast<int>(ac.series.size()) - 1;
  ac.series.push_back(lo);
  plot::Series nw{"Newey-West lags",
                  {static_cast<double>(r.hac_lags), static_cast<double>(r.hac_lags)},
                  {-1.0, 1.0}};
  nw.dashed = true;
  ac.series.push_back(nw);
  plot::write_png({ac}, dir + "/residual_autocorrelation.png");
}

void setup_calibrate(CLI::App& app) {
  auto opt = std::make_shared<CalibrateFlags>();
  CLI::App* sub = app.add_subcommand(
      "calibrate",
      "Fit the device's inertial parameters, viscous and Coulomb friction to a calibration log\n"
      "with Ceres; write the fitted device model file and a JSON report (values, std, residual\n"
      "RMS, condition number, parameters not identifiable and left at their prior)");
  sub->add_option("log", opt->log, "calibration log (CSV, from `dentsim excite`)")->required();
  sub->add_option("--json", opt->json, "report to write (JSON)")->required();
  sub->add_option("-o,--output", opt->out, "fitted device model file to write")->required();
  sub->add_option("--prior", opt->prior, "prior device model (default: built-in Premium 1.5A)");
  sub->add_option("--truth", opt->truth,
                  "true device model (simulated data): adds true values and max_rel_error");
  sub->add_option("--plots", opt->plots,
                  "directory for PNG plots (torque fit, residual histogram, residual vs\n"
                  "velocity, residual autocorrelation)");
  sub->add_option("--lowpass", opt->fit.lowpass_hz,
                  "zero-phase low-pass of qd and tau before differentiating [Hz], 0 = off, else\n"
                  "between 4 / (log duration) and 0.45 / (time step) (default 10)");
  sub->add_option("--max-samples", opt->fit.max_samples, "samples used (default 3000)");
  sub->add_option("--torque-shift", opt->fit.torque_shift,
                  "use the torque logged this many more ticks earlier with each sample\n"
                  "(fractional, added to the shift --velocity-lag sets; default 0)");
  sub->add_option(
      "--velocity-lag", opt->fit.velocity_lag,
      "lag d [ticks] of the logged velocity behind the logged angle, or 'auto' (the\n"
      "simulated Phantom's driver: backward difference + 200 Hz low-pass, 0.898 ticks at\n"
      "1 kHz): q is taken d ticks and tau d + 1/2 + --torque-shift ticks earlier (the\n"
      "torque is held over the tick); 0 = no alignment (exact logged velocities);\n"
      "default auto");
  sub->add_option("--lowpass-order", opt->fit.lowpass_order,
                  "1: first-order zero-phase low-pass, 2: second-order Butterworth (zero-phase)\n"
                  "(default 2)");
  sub->add_option("--coulomb-velocity", opt->fit.coulomb_velocity,
                  "velocity of the Coulomb column tanh(v / v_s): 'filtered' (the low-passed qd,\n"
                  "default) or 'raw' (the logged qd)");
  sub->add_flag("--no-model-mismatch", opt->no_model_mismatch,
                "report the statistical std only (the default refits without each joint's slowest\n"
                "quarter of samples and adds the change beyond noise to each parameter's std,\n"
                "flagging a model mismatch: docs/calibration.md)");
  sub->add_flag(
      "--no-law-mismatch", opt->no_law_mismatch,
      "no law term in the std (the default refits with each joint's other smooth sign,\n"
      "tanh <-> erf, and adds how far each parameter moves to its std: docs/calibration.md)");
  sub->add_flag("--allow-incomplete", opt->fit.allow_incomplete,
                "fit a log marked incomplete (an excitation stopped by a device fault, a guard\n"
                "or an interruption; refused by default: it covers less motion than planned)");
  sub->add_option("--max-iterations", opt->fit.max_iterations,
                  "Ceres iteration limit (default 100); a fit that hits it did not converge");
  sub->add_option(
      "--min-speed", opt->fit.min_speed,
      "drop each joint's torque rows where its low-passed speed is below this [rad/s]:\n"
      "near stiction Coulomb friction is any torque within +-f_c, which no law of the\n"
      "velocity predicts; 0 = keep every row (default 0.2)");
  sub->add_option("--coulomb-smoothing", opt->fit.coulomb_smoothing,
                  "v_s of each joint's f_c tanh(qd / v_s): 'fit' (chosen per joint by profile\n"
                  "least squares over 0.001..1 rad/s and written to the fitted model, default) or\n"
                  "'prior' (the prior model's)");
  sub->add_option("--coulomb-sign", opt->fit.coulomb_sign,
                  "the smooth sign s of f_c s(qd / v_s), written to the fitted model: 'erf' (the\n"
                  "sign averaged over a Gaussian velocity dither), 'tanh', 'fit' (either, per\n"
                  "joint, by the profile) or 'prior' (the prior model's; default)");
  sub->callback([opt] {
    opt->fit.model_mismatch_term = !opt->no_model_mismatch;
    opt->fit.law_mismatch_term = !opt->no_law_mismatch;
    check_calibrate_options(opt->fit);
    check_output_paths({{"--json", opt->json}, {"-o", opt->out}},
                       {{"LOG", opt->log}, {"--prior", opt->prior}, {"--truth", opt->truth}});
    const CalibrationLog log = read_calibration_log(opt->log);
    const PhantomParams prior =
        opt->prior.empty() ? default_phantom_params() : load_phantom_params(opt->prior);
    std::optional<PhantomParams> truth;
    if (!opt->truth.empty()) truth = load_phantom_params(opt->truth);
    // The fit cannot stop part way and has nothing partial to keep: Ctrl-C / SIGTERM end it at
    // once, saying so; nothing is written (the outputs are written atomically after the fit).
    const CalibrateOutcome c = [&] {
      const QuitOnSignal quit("calibrate: the fit of " + opt->log +
                              " was not finished; nothing written (" + opt->json + ", " +
                              opt->out + " as they were)");
      std::fprintf(stderr, "calibrate: fitting %s (%d samples logged; Ceres, seconds to a minute)\n",
                   opt->log.c_str(), log.size());
      return calibrate_log(log, opt->log, prior, opt->fit);
    }();
    const FitResult& r = c.fit;
    if (!c.finite()) {
      throw std::runtime_error("calibrate: the fit of " + opt->log +
                               " ended with a non-finite residual or parameter; no file written");
    }
    std::optional<TruthComparison> cmp;
    if (truth) cmp = compare_with_truth(r, prior, *truth);
    write_json(opt->json, calibration_report_json(c, cmp ? &*cmp : nullptr));
    if (!opt->plots.empty()) write_plots(r, opt->plots);
    std::printf(
        "calibrate: %d samples, %d of %d parameters identifiable, condition number %.3g,\n"
        "  residual RMS %.3g N m%s\n",
        r.samples, r.identifiable, kCalibParams, r.condition_number, r.residual_rms,
        cmp ? (", max_rel_error " + std::to_string(cmp->max_rel_error)).c_str() : "");
    if (!c.log_incomplete.empty()) {
      std::printf("  the log is incomplete (%s): fitted as asked (--allow-incomplete)\n",
                  c.log_incomplete.c_str());
    }
    for (const std::string& why : r.model_mismatch_reasons) {
      std::printf("  model mismatch: %s\n", why.c_str());
    }
    if (!r.converged) {
      throw std::runtime_error("calibrate: the fit did not converge (" + r.report +
                               "); no model file written, see " + opt->json);
    }
    validate_phantom_params(r.fitted, "fitted model for " + opt->out);
    write_file_atomic(opt->out, phantom_params_to_text(r.fitted));
    std::printf("  fitted model -> %s, report -> %s\n", opt->out.c_str(), opt->json.c_str());
  });
}
DENTSIM_REGISTER_COMMAND(setup_calibrate);

}  // namespace
}  // namespace dentsim::cli
