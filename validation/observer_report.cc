#include "validation/observer_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "device/closed_loop.h"
#include "device/phantom_device.h"
#include "reference/core/io.h"
#include "reference/observer.h"
#include "fast/registry.h"
#include "reference/phantom/phantom_model.h"

namespace dentsim {
namespace {

struct Trace {
  std::vector<double> t;
  std::vector<VecX> f_hat, f_true, qd;
};

// Hand profile: hold the start pose; a 1 ms ramp to f_step at t_step; from t_move a triangle wave
// of the reference along x.
std::vector<HandKeyframe> hand_profile(const ObserverReportConfig& c, const Vec3& x0) {
  std::vector<HandKeyframe> k;
  auto add = [&](double t, const Vec3& x, const Vec3& f) {
    HandKeyframe h;
    h.t = t;
    h.x_ref = x;
    h.wrench_ff.head<3>() = f;
    k.push_back(h);
  };
  add(0.0, x0, Vec3::Zero());
  add(c.t_step, x0, Vec3::Zero());
  add(c.t_step + 1e-3, x0, c.f_step);
  add(c.t_move, x0, c.f_step);
  const double P = c.move_period;
  const Vec3 ex = Vec3::UnitX() * c.move_amplitude;
  double t = c.t_move + 0.25 * P;
  int sign = 1;
  while (t < c.t_end + P) {
    add(t, x0 + sign * ex, c.f_step);
    sign = -sign;
    t += 0.5 * P;
  }
  return k;
}

// The report's controller as a Pipeline, so that the loop owner (device/closed_loop.h) runs it
// like every other servo loop: gravity compensation by the model plus a joint hold
// spring-damper, tau = g(q) + K_p (q_hold - q) - K_d qd, and the momentum observer updated on each
// new sample with the torque held over the tick that just ended (as the pipeline's observe stage).
class HoldController : public Pipeline {
 public:
  HoldController(const DeviceModel& model, const ObserverReportConfig& c, VecX q_hold)
      : model_(model),
        obs_(model, VecX::Constant(6, c.gain_L)),
        q_hold_(std::move(q_hold)),
        Kp_(c.K_p),
        Kd_(c.K_d) {}
  TickStatus reset(const DeviceSample& s) override {
    obs_.reset(s.q, s.qd);
    t_prev_ = s.t;
    have_prev_ = false;
    return TickStatus::kOk;
  }
  const TickResult& tick(const DeviceSample& s, double, ContactProvider&) override {
    if (have_prev_) obs_.update(s.q, s.qd, r_.tau, s.t - t_prev_);
    t_prev_ = s.t;
    have_prev_ = true;
    r_.tau = model_.gravity(s.q) + Kp_.cwiseProduct(q_hold_ - s.q) - Kd_.cwiseProduct(s.qd);
    return r_;
  }
  const ProxyState& proxy() const override { return proxy_; }
  const char* name() const override { return "observer-report hold"; }
  const VecX& estimate() const { return obs_.estimate(); }

 private:
  const DeviceModel& model_;
  MomentumObserver obs_;
  VecX q_hold_, Kp_, Kd_;
  double t_prev_ = 0.0;
  bool have_prev_ = false;
  TickResult r_;
  ProxyState proxy_;
};

// Exact sensing: the driver reports the true joint velocity.
class ExactVelocity : public Device {
 public:
  explicit ExactVelocity(SimulatedPhantom& dev) : dev_(dev) {}
  const DeviceCapabilities& capabilities() const override { return dev_.capabilities(); }
  const DeviceLimits& limits() const override { return dev_.limits(); }
  void read(DeviceSample& out) const override {
    dev_.read(out);
    out.qd = dev_.true_qd();
  }
  void write(const VecX& tau) override { dev_.write(tau); }
  void advance() override { dev_.advance(); }
  const VecX& applied_torque() const override { return dev_.applied_torque(); }
  std::uint32_t faults() const override { return dev_.faults(); }
  void clear_faults() override { dev_.clear_faults(); }

 private:
  SimulatedPhantom& dev_;
};

Trace simulate(const PhantomParams& params, const ObserverReportConfig& c,
               const DeviceModel& model) {
  SimulatedDeviceConfig dc = phantom_device_config(params);
  dc.jitter = c.jitter;
  dc.friction_on = c.device_friction;
  if (c.ideal_sensing) dc.quantize = false;
  const VecX q_hold = phantom_home_q(params);
  SimulatedPhantom dev(phantom_plant(params), dc, q_hold);
  const Pose p0 = dev.tip_pose();
  const ScriptedHand hand(c.hand, hand_profile(c, p0.x), p0.R);
  dev.set_hand(&hand);
  ExactVelocity exact(dev);
  HoldController controller(model, c, q_hold);
  NoContacts free_space;
  ClosedLoop loop(c.ideal_sensing ? static_cast<Device&>(exact) : dev, controller, free_space);
  loop.start();
  Trace tr;
  // After each step the device holds sample k+1; its estimate comes with the next tick (the
  // controller updates the observer on a new sample first), so the trace row is completed then.
  bool pending = false;
  while (true) {
    const bool more = loop.sample().t < c.t_end;
    if (pending) {
      if (more) loop.step();  // the tick on the pending sample updates the observer
      else controller.tick(loop.sample(), loop.last_tick_length(), free_space);  // last sample
      tr.f_hat.push_back(controller.estimate());
      pending = false;
      if (!more) break;
    } else {
      if (!more) break;
      loop.step();
    }
    tr.t.push_back(loop.sample().t);
    tr.f_true.push_back(dev.hand_joint_torque());
    tr.qd.push_back(dev.true_qd());
    pending = true;
  }
  if (dev.faults() != kFaultNone) {
    throw std::runtime_error("observer report: the simulated device faulted: " +
                             fault_string(dev.faults()));
  }
  return tr;
}

VecX window_mean(const Trace& tr, const std::vector<VecX>& x, double t0, double t1) {
  VecX m = VecX::Zero(6);
  int n = 0;
  for (std::size_t k = 0; k < tr.t.size(); ++k) {
    if (tr.t[k] >= t0 && tr.t[k] < t1) {
      m += x[k];
      ++n;
    }
  }
  if (n == 0) throw InputError("observer report: empty evaluation window; check the phase times");
  return m / n;
}

// The observer's ideal output for the truth x: the sampled first-order lag with gain L,
// y_k = y_k-1 + L T_k (x_k - y_k-1) (f_hat_k = f (1 - (1 - L T)^k) for a step), started from
// y = f_hat at index k0 - 1.
std::vector<double> first_order_lag(const Trace& tr, const std::vector<VecX>& x, int j,
                                    std::size_t k0, std::size_t k1, double L) {
  std::vector<double> y(k1 - k0);
  double yk = tr.f_hat[k0 - 1][j];
  for (std::size_t k = k0; k < k1; ++k) {
    yk += L * (tr.t[k] - tr.t[k - 1]) * (x[k][j] - yk);
    y[k - k0] = yk;
  }
  return y;
}

std::size_t index_at(const Trace& tr, double t) {
  std::size_t k = 1;
  while (k < tr.t.size() && tr.t[k] < t) ++k;
  return k;
}

// The gain L_fit whose first-order lag of f_true best matches f_hat on joint j over [t0, t1)
// (least squares, log grid over 1..10^4 1/s refined by golden section); the lag is 1/L_fit.
double fit_lag_gain(const Trace& tr, int j, double t0, double t1) {
  const std::size_t k0 = index_at(tr, t0), k1 = index_at(tr, t1);
  auto cost = [&](double logL) {
    const std::vector<double> y = first_order_lag(tr, tr.f_true, j, k0, k1, std::exp(logL));
    double c = 0.0;
    for (std::size_t k = k0; k < k1; ++k) c += std::pow(tr.f_hat[k][j] - y[k - k0], 2);
    return c;
  };
  double best = 0.0, best_c = 1e300;
  for (int i = 0; i <= 400; ++i) {
    const double lg = std::log(1.0) + i * (std::log(1e4) - std::log(1.0)) / 400;
    const double c = cost(lg);
    if (c < best_c) best_c = c, best = lg;
  }
  double a = best - 0.03, b = best + 0.03;
  const double g = (std::sqrt(5.0) - 1.0) / 2.0;
  for (int it = 0; it < 60; ++it) {
    const double x1 = b - g * (b - a), x2 = a + g * (b - a);
    if (cost(x1) < cost(x2)) {
      b = x2;
    } else {
      a = x1;
    }
  }
  return std::exp(0.5 * (a + b));
}

VecX window_median(const Trace& tr, const std::vector<VecX>& x, double t0, double t1) {
  VecX m = VecX::Zero(6);
  std::vector<double> v;
  for (int j = 0; j < 6; ++j) {
    v.clear();
    for (std::size_t k = 0; k < tr.t.size(); ++k) {
      if (tr.t[k] >= t0 && tr.t[k] < t1) v.push_back(x[k][j]);
    }
    if (v.empty()) throw InputError("observer report: empty evaluation window");
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    m[j] = v[v.size() / 2];
  }
  return m;
}

ObserverRun evaluate(const Trace& tr, const ObserverReportConfig& c, const std::string& name) {
  ObserverRun r;
  r.model = name;
  std::vector<VecX> err(tr.t.size());
  for (std::size_t k = 0; k < tr.t.size(); ++k) err[k] = tr.f_hat[k] - tr.f_true[k];
  const double s0 = c.t_move - c.settle_window, s1 = c.t_move;
  r.steady_error = window_median(tr, err, s0, s1);
  r.steady_error_max = r.steady_error.cwiseAbs().maxCoeff();
  // Step and lag.
  const VecX pre_true = window_mean(tr, tr.f_true, c.t_step - 0.1, c.t_step);
  const VecX post_true = window_mean(tr, tr.f_true, s0, s1);
  r.step_size = post_true - pre_true;
  r.step_size.cwiseAbs().maxCoeff(&r.lag_joint);
  const int j = r.lag_joint;
  r.lag_s = 1.0 / fit_lag_gain(tr, j, c.t_step, c.t_step + c.settle_window);
  // Moving phase.
  const double m0 = c.t_move + 0.25 * c.move_period, m1 = c.t_end;
  std::vector<VecX> e2(tr.t.size()), f2(tr.t.size());
  for (std::size_t k = 0; k < tr.t.size(); ++k) {
    e2[k] = err[k].cwiseAbs2();
    f2[k] = tr.f_true[k].cwiseAbs2();
  }
  r.moving_rms = window_mean(tr, e2, m0, m1).cwiseSqrt();
  // Error beyond the observer's own first-order lag: f_hat - LPF_L(f_true).
  const std::size_t k0 = index_at(tr, m0), k1 = index_at(tr, m1);
  r.moving_rms_beyond_lag = VecX::Zero(6);
  r.moving_bias = VecX::Zero(6);
  r.moving_bias_along_motion = VecX::Zero(6);
  for (int jj = 0; jj < 6; ++jj) {
    const std::vector<double> y = first_order_lag(tr, tr.f_true, jj, k0, k1, c.gain_L);
    double acc = 0.0, sum = 0.0, along = 0.0;
    for (std::size_t k = k0; k < k1; ++k) {
      acc += std::pow(tr.f_hat[k][jj] - y[k - k0], 2);
      sum += tr.f_hat[k][jj] - y[k - k0];
      along += (tr.qd[k][jj] > 0   ? 1.0
                : tr.qd[k][jj] < 0 ? -1.0
                                   : 0.0) *
               (tr.f_hat[k][jj] - y[k - k0]);
    }
    r.moving_bias_along_motion[jj] = along / static_cast<double>(k1 - k0);
    r.moving_rms_beyond_lag[jj] = std::sqrt(acc / static_cast<double>(k1 - k0));
    r.moving_bias[jj] = sum / static_cast<double>(k1 - k0);
  }
  r.moving_truth_rms = window_mean(tr, f2, m0, m1).cwiseSqrt();
  return r;
}

nlohmann::json vec_json(const VecX& v) {
  nlohmann::json a = nlohmann::json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) a.push_back(v[i]);
  return a;
}

std::string row(const char* label, const VecX& v, double scale) {
  std::string s = std::string("| ") + label;
  char buf[32];
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    std::snprintf(buf, sizeof(buf), " | %+.3f", v[i] * scale);
    s += buf;
  }
  return s + " |\n";
}

void check_config(const ObserverReportConfig& c) {
  if (!(c.gain_L > 0.0) || !(c.model_error > -1.0) || !(c.t_step > 0.1) ||
      !(c.t_move > c.t_step + c.settle_window) || !(c.t_end > c.t_move + c.move_period * 0.5) ||
      !(c.move_period > 0.0) || !(c.settle_window > 0.0)) {
    throw InputError(
        "observer report: expected gain_L > 0, model_error > -1, t_step > 0.1, "
        "t_move > t_step + settle_window, t_end > t_move + move_period / 2");
  }
}

}  // namespace

PhantomParams observer_true_params(const PhantomParams& params,
                                   const ObserverReportConfig& config) {
  PhantomParams p = params;
  if (!config.device_friction) p.coulomb_n_m.setZero();
  return p;
}

ObserverReport run_observer_models(const PhantomParams& params, const ObserverReportConfig& config,
                                   const std::vector<NamedObserverModel>& models) {
  check_config(config);
  if (models.empty()) throw InputError("observer report: no observer model given");
  for (std::size_t i = 0; i < models.size(); ++i) {
    const NamedObserverModel& m = models[i];
    if (m.name.empty()) throw InputError("observer report: observer model with an empty name");
    if (m.model == nullptr || m.model->dof() != 6) {
      throw InputError("observer report: observer model '" + m.name + "' is not a 6-DoF model");
    }
    for (std::size_t k = 0; k < i; ++k) {
      if (models[k].name == m.name) {
        throw InputError("observer report: observer model name '" + m.name + "' given twice");
      }
    }
  }
  ObserverReport rep;
  rep.config = config;
  rep.expected_lag_s = 1.0 / config.gain_L;
  rep.device_coulomb = config.device_friction ? VecX(params.coulomb_n_m) : VecX(VecX::Zero(6));
  for (const NamedObserverModel& m : models) {
    rep.runs.push_back(evaluate(simulate(params, config, *m.model), config, m.name));
  }
  return rep;
}

std::unique_ptr<DeviceModel> observer_device_model(const PhantomParams& params,
                                                   const std::string& pipeline) {
  if (find_implementation(pipeline) == nullptr) {
    throw InputError("observer report: unknown pipeline '" + pipeline + "' (expected one of: " +
                     stage_table_names() + ")");
  }
  return make_phantom_model(pipeline, params);
}

ObserverReport run_observer_report(const PhantomParams& params,
                                   const ObserverReportConfig& config) {
  check_config(config);
  const std::unique_ptr<DeviceModel> truth =
      observer_device_model(observer_true_params(params, config), config.pipeline);
  const ScaledDeviceModel perturbed(*truth, 1.0 + config.model_error, 1.0 + config.model_error);
  ObserverReport rep =
      run_observer_models(params, config, {{"true", truth.get()}, {"perturbed", &perturbed}});
  rep.scaled_model_run = true;
  return rep;
}

std::string observer_report_json(const ObserverReport& r) {
  nlohmann::json j;
  const ObserverReportConfig& c = r.config;
  j["config"] = {{"gain_L_per_s", c.gain_L},
                 {"device_friction", c.device_friction},
                 {"ideal_sensing", c.ideal_sensing},
                 {"t_step_s", c.t_step},
                 {"t_move_s", c.t_move},
                 {"t_end_s", c.t_end},
                 {"f_step_n", {c.f_step[0], c.f_step[1], c.f_step[2]}},
                 {"move_amplitude_m", c.move_amplitude},
                 {"move_period_s", c.move_period},
                 {"pipeline", c.pipeline}};
  if (r.scaled_model_run) j["config"]["model_error"] = c.model_error;
  j["expected_lag_s"] = r.expected_lag_s;
  j["device_coulomb_n_m"] = vec_json(r.device_coulomb);
  for (const ObserverRun& run : r.runs) {
    j["runs"].push_back({{"model", run.model},
                         {"steady_error_n_m", vec_json(run.steady_error)},
                         {"steady_error_max_n_m", run.steady_error_max},
                         {"step_size_n_m", vec_json(run.step_size)},
                         {"lag_joint", run.lag_joint + 1},
                         {"lag_s", run.lag_s},
                         {"moving_bias_n_m", vec_json(run.moving_bias)},
                         {"moving_bias_along_motion_n_m", vec_json(run.moving_bias_along_motion)},
                         {"moving_rms_n_m", vec_json(run.moving_rms)},
                         {"moving_rms_beyond_lag_n_m", vec_json(run.moving_rms_beyond_lag)},
                         {"moving_truth_rms_n_m", vec_json(run.moving_truth_rms)}});
  }
  return j.dump(2) + "\n";
}

std::string observer_report_table(const ObserverReport& r) {
  char head[200];
  std::snprintf(head, sizeof(head), "Observer L = %g 1/s (expected lag 1/L = %.1f ms), ",
                r.config.gain_L, 1e3 * r.expected_lag_s);
  std::string s = head;
  if (r.scaled_model_run) {
    std::snprintf(head, sizeof(head), "model error %+.0f %% in inertia and damping",
                  100.0 * r.config.model_error);
    s += head;
  } else {
    s += "models:";
    for (const ObserverRun& run : r.runs) s += " " + run.model;
  }
  s += "; values in mN m, joints q1..q6\n\n";
  s += "| quantity | q1 | q2 | q3 | q4 | q5 | q6 |\n|---|---|---|---|---|---|---|\n";
  s += row("device Coulomb f_c", r.device_coulomb, 1e3);
  for (const ObserverRun& run : r.runs) {
    const std::string m = run.model + " model: ";
    s += row((m + "step in f_true").c_str(), run.step_size, 1e3);
    s += row((m + "steady error (median)").c_str(), run.steady_error, 1e3);
    s += row((m + "moving bias beyond the 1/L lag (mean)").c_str(), run.moving_bias, 1e3);
    s += row((m + "moving bias along sign(qd)").c_str(), run.moving_bias_along_motion, 1e3);
    s += row((m + "moving RMS error").c_str(), run.moving_rms, 1e3);
    s += row((m + "moving RMS error beyond the 1/L lag").c_str(), run.moving_rms_beyond_lag, 1e3);
    s += row((m + "moving RMS f_true").c_str(), run.moving_truth_rms, 1e3);
  }
  s += "\n";
  for (const ObserverRun& run : r.runs) {
    char buf[160];
    std::snprintf(
        buf, sizeof(buf), "%s model: lag on q%d = %.1f ms, max |steady error| = %.3f mN m\n",
        run.model.c_str(), run.lag_joint + 1, 1e3 * run.lag_s, 1e3 * run.steady_error_max);
    s += buf;
  }
  return s;
}

}  // namespace dentsim
