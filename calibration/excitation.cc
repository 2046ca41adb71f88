#include "calibration/excitation.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <string>

#include "calibration/fit.h"
#include "reference/core/io.h"
#include "reference/phantom/phantom_model.h"

namespace dentsim {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Raised-cosine fade-in s(t) and its first two derivatives.
void window(double t, double Tr, double* s, double* ds, double* dds) {
  if (Tr <= 0.0 || t >= Tr) {
    *s = 1.0;
    *ds = *dds = 0.0;
    return;
  }
  const double w = kPi / Tr;
  *s = 0.5 * (1.0 - std::cos(w * t));
  *ds = 0.5 * w * std::sin(w * t);
  *dds = 0.5 * w * w * std::cos(w * t);
}

// "2.301 s"
std::string seconds_text(double t) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.3f s", t);
  return buf;
}

void check_params(const PhantomParams& p, const Vec6& q0, const ExcitationParams& e) {
  if (e.harmonics < 1 || !(e.base_frequency_hz > 0.0) || e.ramp_s < 0.0) {
    throw InputError("excitation: harmonics >= 1, base_frequency_hz > 0 and ramp_s >= 0 expected");
  }
  for (int j = 0; j < 6; ++j) {
    if (!(q0(j) > p.q_min_rad(j) + e.limit_margin_rad &&
          q0(j) < p.q_max_rad(j) - e.limit_margin_rad)) {
      throw InputError("excitation: home pose q" + std::to_string(j + 1) +
                       " is not inside the joint limits minus the margin");
    }
  }
}

}  // namespace

Excitation::Excitation(const PhantomParams& p, const Vec6& q0, const ExcitationParams& e)
    : e_(e), q0_(q0) {
  check_params(p, q0, e);
  std::mt19937_64 rng(e.seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  a_.resize(6, e.harmonics);
  b_.resize(6, e.harmonics);
  for (int j = 0; j < 6; ++j) {
    for (int l = 0; l < e.harmonics; ++l) {
      a_(j, l) = u(rng) / (l + 1);  // 1/l roll-off keeps accelerations moderate
      b_(j, l) = u(rng) / (l + 1);
    }
  }
  fit_to_limits(p);
}

Excitation::Excitation(const PhantomParams& p, const Vec6& q0, const ExcitationParams& e,
                       const CoefficientMatrix& a, const CoefficientMatrix& b)
    : e_(e), q0_(q0), a_(a), b_(b) {
  check_params(p, q0, e);
  if (a.cols() != e.harmonics || b.cols() != e.harmonics || !a.allFinite() || !b.allFinite()) {
    throw InputError("excitation: coefficients must be finite, 6 x harmonics");
  }
  fit_to_limits(p);
}

void Excitation::fit_to_limits(const PhantomParams& p) {
  const ExcitationParams& e = e_;
  const Vec6& q0 = q0_;
  // Position and velocity bounds over the ramp and one period after it, with the window applied
  // (q - q0 and qd are linear in the per-joint scale), on a 0.5 ms grid, with a 2 % safety factor
  // for what the grid misses.
  const double horizon = e.ramp_s + 1.0 / e.base_frequency_hz;
  const int n = static_cast<int>(std::ceil(horizon / 5e-4));
  Vec6 d_hi = Vec6::Constant(1e-12), d_lo = Vec6::Constant(-1e-12), v_max = Vec6::Constant(1e-12);
  for (int k = 0; k <= n; ++k) {
    const double t = horizon * k / n;
    Vec6 d, dd, ddd;
    eval_unscaled(t, &d, &dd, &ddd);
    double w, dw, ddw;
    window(t, e.ramp_s, &w, &dw, &ddw);
    d_hi = d_hi.cwiseMax(w * d);
    d_lo = d_lo.cwiseMin(w * d);
    v_max = v_max.cwiseMax((dw * d + w * dd).cwiseAbs());
  }
  for (int j = 0; j < 6; ++j) {
    const double room_hi = p.q_max_rad(j) - e.limit_margin_rad - q0(j);
    const double room_lo = q0(j) - (p.q_min_rad(j) + e.limit_margin_rad);
    scale_(j) =
        0.98 * std::min({room_hi / d_hi(j), room_lo / -d_lo(j), e.qd_max_rad_s(j) / v_max(j)});
  }
  // Torque: shrink all amplitudes until the model's inverse dynamics fits the limit.
  const PhantomModelD model(p);
  for (int iter = 0;; ++iter) {
    bool ok = true;
    for (int k = 0; k <= n / 4 && ok; ++k) {  // 2 ms grid
      Vec6 q, qd, qdd;
      eval(horizon * k / (n / 4), &q, &qd, &qdd);
      const Vec6 tau = model.M(q) * qdd + model.bias(q, qd) + model.g(q) + model.friction(qd);
      for (int j = 0; j < 6; ++j) {
        if (std::abs(tau(j)) > e.torque_fraction * p.torque_limit_n_m(j)) ok = false;
      }
    }
    if (ok) break;
    if (iter == 40) {
      throw InputError("excitation: no amplitude keeps the model torque within " +
                       std::to_string(e.torque_fraction) + " tau_max (gravity alone exceeds it?)");
    }
    scale_ *= 0.85;
  }
}

void Excitation::eval_unscaled(double t, Vec6* d, Vec6* dd, Vec6* ddd) const {
  const double wf = 2.0 * kPi * e_.base_frequency_hz;
  d->setZero();
  dd->setZero();
  ddd->setZero();
  for (int l = 0; l < e_.harmonics; ++l) {
    const double w = wf * (l + 1);
    const double s = std::sin(w * t), c = std::cos(w * t);
    *d += a_.col(l) * s + b_.col(l) * (c - 1.0);
    *dd += (a_.col(l) * c - b_.col(l) * s) * w;
    *ddd += (-a_.col(l) * s - b_.col(l) * c) * (w * w);
  }
}

void Excitation::eval(double t, Vec6* q, Vec6* qd, Vec6* qdd) const {
  Vec6 d, dd, ddd;
  eval_unscaled(t, &d, &dd, &ddd);
  d = d.cwiseProduct(scale_);
  dd = dd.cwiseProduct(scale_);
  ddd = ddd.cwiseProduct(scale_);
  double s, ds, dds;
  window(t, e_.ramp_s, &s, &ds, &dds);
  *q = q0_ + s * d;
  *qd = ds * d + s * dd;
  *qdd = dds * d + 2.0 * ds * dd + s * ddd;
}

ExcitationOutcome run_excitation_until_stop(Device& device, const PhantomParams& p,
                                            const Excitation& exc, double duration,
                                            const TrackingParams& tracking,
                                            ExactState exact_state,
                                            const std::atomic<bool>* stop_request) {
  if ((exact_state.q == nullptr) != (exact_state.qd == nullptr)) {
    throw InputError("excite: exact state needs both q and qd");
  }
  if (device.dof() != 6) throw InputError("excite: the device must have 6 joints");
  const PhantomModelD model(p);
  const Mat6 M0 = model.M(exc.q0());
  const Vec6 kp = M0.diagonal() * tracking.bandwidth_rad_s * tracking.bandwidth_rad_s;
  const Vec6 kd = M0.diagonal() * 2.0 * tracking.bandwidth_rad_s;
  ExcitationOutcome out;
  CalibrationLog& log = out.log;
  DeviceSample s = device.make_sample();
  device.read(s);
  const double t0 = s.t;
  VecX tau(6);
  while (true) {
    device.read(s);
    const double t = s.t - t0;
    if (t > duration) break;
    if (stop_request != nullptr && stop_request->load()) {
      out.interrupted = true;
      out.stop_t = t;
      out.stop_reason = "interrupted at t = " + seconds_text(t);
      break;
    }
    Vec6 qr, qdr, qddr;
    exc.eval(t, &qr, &qdr, &qddr);
    const Vec6 q = exact_state.q ? Vec6(*exact_state.q) : Vec6(s.q);
    const Vec6 qd = exact_state.qd ? Vec6(*exact_state.qd) : Vec6(s.qd);
    tau = model.M(q) * qddr + model.bias(q, qd) + model.g(q) + model.friction(qdr) +
          kp.cwiseProduct(qr - q) + kd.cwiseProduct(qdr - qd);
    device.write(tau);
    if (device.faults() != kFaultNone) {
      out.fault = device.faults();
      out.stop_t = t;
      out.stop_reason = "device fault " + fault_string(out.fault) + " at t = " + seconds_text(t);
      break;
    }
    log.t.push_back(t);
    log.q.push_back(q);
    log.qd.push_back(qd);
    log.tau.push_back(device.applied_torque());
    device.advance();
  }
  if (out.stop_reason.empty()) {
    out.complete = true;
  } else {
    device.write(VecX::Zero(6));
    log.incomplete = out.stop_reason;
  }
  return out;
}

CalibrationLog run_excitation(Device& device, const PhantomParams& p, const Excitation& exc,
                              double duration, const TrackingParams& tracking,
                              ExactState exact_state) {
  ExcitationOutcome o = run_excitation_until_stop(device, p, exc, duration, tracking, exact_state);
  if (!o.complete) throw InputError("excite: " + o.stop_reason);
  return std::move(o.log);
}

ExcitationOutcome run_guarded_excitation(Device& device, const PhantomParams& prior,
                                         const Excitation& exc, double duration,
                                         const GuardedExcitationParams& g,
                                         const TrackingParams& tracking,
                                         const std::atomic<bool>* stop_request) {
  if (device.dof() != 6) throw InputError("excite: the device must have 6 joints");
  if (!(duration > 0.0)) throw InputError("excite: the duration must be > 0");
  const PhantomModelD model(prior);
  const double wc = tracking.bandwidth_rad_s;
  const Mat6 M0 = model.M(exc.q0());
  const Vec6 kp = M0.diagonal() * wc * wc;
  const Vec6 kd = M0.diagonal() * 2.0 * wc;
  const Vec6 ki = kp * (g.integral_corner * wc);
  const Vec6 tau_max = Vec6(device.limits().tau_max);
  const Vec6 tau_lim = tau_max * g.torque_fraction;
  const Vec6 qd_guard = exc.params().qd_max_rad_s * g.velocity_guard;
  const Vec6 qd_stop = exc.params().qd_max_rad_s * g.velocity_stop;

  ExcitationOutcome out;
  CalibrationLog& log = out.log;
  DeviceSample s = device.make_sample();
  device.read(s);
  const Vec6 q_start = s.q;
  for (int j = 0; j < 6; ++j) {
    if (!(std::isfinite(q_start(j)) && q_start(j) >= prior.q_min_rad(j) &&
          q_start(j) <= prior.q_max_rad(j))) {
      throw InputError("excite: the arm stands outside the model's joint range (joint " +
                       std::to_string(j + 1) + " at " + std::to_string(q_start(j)) +
                       " rad, range [" + std::to_string(prior.q_min_rad(j)) + ", " +
                       std::to_string(prior.q_max_rad(j)) +
                       "]): move it towards the middle, or check the model file and the joint "
                       "convention (docs/hardware.md)");
    }
  }
  // The approach: minimum jerk, peak speed 1.875 |dq| / T_a.
  const Vec6 dq_approach = exc.q0() - q_start;
  double T_a = 1.875 * dq_approach.cwiseAbs().maxCoeff() / g.approach_speed_rad_s;
  if (T_a > 0.0) T_a = std::max(T_a, 0.5);

  enum class Phase { kHold, kApproach, kSettle, kExcite, kFadeOut, kStopHold, kRampDown };
  Phase phase = Phase::kHold;
  double t_ref = 0.0, phase_t = 0.0;  // reference clock since the start, and in the phase [s]
  double t_exc0 = 0.0;                // device time of the excitation's start
  bool started = false;
  double exc_t = 0.0, kappa = 1.0;  // the excitation's own time and its time scale
  Vec6 integ = Vec6::Zero(), speed = Vec6::Zero(), q_hold = q_start;
  double t_prev = s.t;
  const double t_dev0 = s.t;
  VecX tau_cmd = VecX::Zero(6);
  const auto stop_now = [&](const std::string& why) {
    out.stop_reason = why;
    device.write(VecX::Zero(6));
  };
  const auto when = [&](double t_dev) {
    return started ? "at t = " + seconds_text(t_dev - t_exc0)
                   : "at " + seconds_text(t_dev - t_dev0) +
                         " after the start, before the excitation (no sample logged)";
  };
  const auto next = [&](Phase p) {
    phase = p;
    phase_t = 0.0;
  };
  while (true) {
    device.read(s);
    // The time of the stop: the last sample before a fault, a guard or the stop request.
    if (!out.interrupted && !out.complete) out.stop_t = started ? s.t - t_exc0 : s.t - t_dev0;
    if (device.faults() != kFaultNone) {
      out.fault = device.faults();
      if (!out.complete) stop_now("device fault " + fault_string(out.fault) + " " + when(s.t));
      break;
    }
    if (!(s.q.allFinite() && s.qd.allFinite() && std::isfinite(s.t))) {
      if (!out.complete) stop_now("non-finite sample from the device " + when(s.t));
      break;
    }
    const Vec6 q = s.q, qd = s.qd;
    const double dt_dev = std::max(0.0, s.t - t_prev);
    t_prev = s.t;
    // Late ticks ridden through: the reference advances by at most max_reference_step_s.
    const double dt = std::min(dt_dev, g.max_reference_step_s);
    if (dt_dev > g.max_reference_step_s) ++out.late_ticks;
    ++out.ticks;
    const double a = 1.0 - std::exp(-2.0 * kPi * g.guard_lowpass_hz * dt);
    speed += a * (qd.cwiseAbs() - speed);
    out.max_speed_rad_s = std::max(out.max_speed_rad_s, speed.maxCoeff());
    // Hard stops: zero torque at once.
    std::string hard;
    for (int j = 0; j < 6 && hard.empty(); ++j) {
      char buf[200];
      // The speed and range stops guard the excitation; before it, an arm that moves while the
      // torque ramps in (a gimbal falling onto its stop under gravity) is held by the PD.
      const bool exciting = phase == Phase::kExcite || phase == Phase::kFadeOut;
      if (exciting && speed(j) > qd_stop(j)) {
        std::snprintf(buf, sizeof buf, "velocity guard: joint %d at %.3g rad/s, beyond %.3g rad/s",
                      j + 1, speed(j), qd_stop(j));
        hard = buf;
      } else if (exciting && (q(j) < prior.q_min_rad(j) - g.range_tolerance_rad ||
                              q(j) > prior.q_max_rad(j) + g.range_tolerance_rad)) {
        std::snprintf(buf, sizeof buf, "workspace guard: joint %d at %.4g rad, outside [%.4g, %.4g]",
                      j + 1, q(j), prior.q_min_rad(j), prior.q_max_rad(j));
        hard = buf;
      }
    }
    if (!hard.empty()) {
      if (!out.complete) stop_now(hard + " " + when(s.t));
      break;
    }
    if (stop_request != nullptr && stop_request->load() && !out.interrupted) {
      out.interrupted = true;
      if (!out.complete) {
        out.stop_reason = "interrupted " + when(s.t);
        if (phase == Phase::kExcite) {
          next(Phase::kFadeOut);
        } else {
          next(Phase::kStopHold);
        }
      }
    }
    if (phase == Phase::kExcite && s.t - t_exc0 > duration) {
      out.complete = true;
      next(Phase::kFadeOut);
    }
    t_ref += dt;
    phase_t += dt;
    // The reference of the phase.
    Vec6 qr = q_hold, qdr = Vec6::Zero(), qddr = Vec6::Zero();
    double down = 1.0;
    const bool moving = phase == Phase::kExcite || phase == Phase::kFadeOut;
    if (moving) exc_t += kappa * dt;
    switch (phase) {
      case Phase::kHold:
        qr = q_start;
        if (phase_t >= g.hold_s) next(T_a > 0.0 ? Phase::kApproach : Phase::kSettle);
        break;
      case Phase::kApproach: {
        const double u = std::min(1.0, phase_t / T_a);
        const double pos = u * u * u * (10.0 - 15.0 * u + 6.0 * u * u);
        const double vel = 30.0 * u * u * (1.0 - u) * (1.0 - u) / T_a;
        const double acc = 60.0 * u * (1.0 - u) * (1.0 - 2.0 * u) / (T_a * T_a);
        qr = q_start + pos * dq_approach;
        qdr = vel * dq_approach;
        qddr = acc * dq_approach;
        if (u >= 1.0) next(Phase::kSettle);
        break;
      }
      case Phase::kSettle:
        qr = exc.q0();
        if (phase_t >= g.settle_s) {
          out.gravity_offset = integ;
          started = true;
          t_exc0 = s.t;
          exc_t = 0.0;
          next(Phase::kExcite);
          out.stop_t = 0.0;
        }
        break;
      case Phase::kExcite:
      case Phase::kFadeOut: {
        Vec6 xq, xqd, xqdd;
        exc.eval(exc_t, &xq, &xqd, &xqdd);
        xqd *= kappa;
        xqdd *= kappa * kappa;
        double f = 1.0, df = 0.0, ddf = 0.0;
        if (phase == Phase::kFadeOut) {
          const double T = g.fade_out_s, u = std::min(1.0, phase_t / T);
          f = 0.5 * (1.0 + std::cos(kPi * u));
          df = u < 1.0 ? -0.5 * kPi / T * std::sin(kPi * u) : 0.0;
          ddf = u < 1.0 ? -0.5 * kPi * kPi / (T * T) * std::cos(kPi * u) : 0.0;
        }
        const Vec6 d = xq - exc.q0();
        qr = exc.q0() + f * d;
        qdr = f * xqd + df * d;
        qddr = f * xqdd + 2.0 * df * xqd + ddf * d;
        if (phase == Phase::kFadeOut && phase_t >= g.fade_out_s) {
          q_hold = exc.q0();
          next(Phase::kStopHold);
        }
        break;
      }
      case Phase::kStopHold:
        if (phase_t >= g.stop_hold_s) next(Phase::kRampDown);
        break;
      case Phase::kRampDown:
        down = 0.5 * (1.0 + std::cos(kPi * std::min(1.0, phase_t / g.stop_ramp_s)));
        break;
    }
    if (phase == Phase::kRampDown && phase_t >= g.stop_ramp_s) {
      device.write(VecX::Zero(6));
      break;
    }
    if (phase == Phase::kHold || phase == Phase::kApproach || phase == Phase::kSettle) {
      q_hold = qr;  // where an interruption before the excitation holds the arm
    }
    // The command: the prior's model, PD, the integral action; ramped in, clamped.
    const Vec6 e = qr - q, ed = qdr - qd;
    const double ramp_in = 0.5 * (1.0 - std::cos(kPi * std::min(1.0, t_ref / g.torque_ramp_s)));
    const double ki_ramp = 0.5 * (1.0 - std::cos(kPi * std::min(1.0, t_ref / g.hold_s)));
    const Vec6 ff = model.M(q) * qddr + model.bias(q, qd) + model.g(q) + model.friction(qdr);
    const Vec6 tau_u = down * (ramp_in * (ff + kp.cwiseProduct(e) + kd.cwiseProduct(ed)) + integ);
    bool clamped = false;
    for (int j = 0; j < 6; ++j) {
      const bool cj = std::abs(tau_u(j)) > tau_lim(j);
      clamped = clamped || cj;
      tau_cmd(j) = std::clamp(tau_u(j), -tau_lim(j), tau_lim(j));
      out.max_command_ratio = std::max(out.max_command_ratio, std::abs(tau_cmd(j)) / tau_max(j));
      // Anti-windup: no integration that pushes a clamped command further.
      if (phase != Phase::kRampDown && (!cj || (e(j) > 0.0) != (tau_u(j) > 0.0))) {
        integ(j) = std::clamp(integ(j) + ki_ramp * ki(j) * e(j) * dt, -tau_lim(j), tau_lim(j));
      }
    }
    if (clamped) ++out.clamped_ticks;
    // Velocity and torque guard: the excitation slows down (same path) and recovers.
    if (moving) {
      bool over = clamped;
      for (int j = 0; j < 6; ++j) over = over || speed(j) > qd_guard(j);
      if (over) {
        ++out.guard_ticks;
        kappa = std::max(g.min_time_scale, kappa - g.time_scale_down_per_s * dt);
      } else {
        kappa = std::min(1.0, kappa + g.time_scale_up_per_s * dt);
      }
      out.min_time_scale = std::min(out.min_time_scale, kappa);
    }
    device.write(tau_cmd);
    if (device.faults() != kFaultNone) {
      out.fault = device.faults();
      if (!out.complete) stop_now("device fault " + fault_string(out.fault) + " " + when(s.t));
      break;
    }
    if (phase == Phase::kExcite) {
      log.t.push_back(s.t - t_exc0);
      log.q.push_back(q);
      log.qd.push_back(qd);
      log.tau.push_back(device.applied_torque());
    }
    device.advance();
  }
  if (!out.complete) log.incomplete = out.stop_reason;
  return out;
}

CalibrationLog synthesize_log(const PhantomParams& truth, const Excitation& exc, double duration,
                              double dt) {
  const PhantomModelD model(truth);
  CalibrationLog log;
  const int n = static_cast<int>(std::floor(duration / dt + 1e-9));
  for (int k = 0; k <= n; ++k) {
    const double t = k * dt;
    Vec6 q, qd, qdd;
    exc.eval(t, &q, &qd, &qdd);
    log.t.push_back(t);
    log.q.push_back(q);
    log.qd.push_back(qd);
    log.tau.push_back(model.M(q) * qdd + model.bias(q, qd) + model.g(q) + model.friction(qd));
  }
  return log;
}

ExcitationCondition excitation_condition(const PhantomParams& p, const Excitation& exc, int samples,
                                         int rank, double null_tol) {
  if (samples < 10) throw InputError("excitation_condition: at least 10 samples");
  const ExcitationParams& e = exc.params();
  const double period = 1.0 / e.base_frequency_hz;
  Eigen::MatrixXd Y(6 * samples, kCalibParams);
  for (int k = 0; k < samples; ++k) {
    Vec6 q, qd, qdd;
    exc.eval(e.ramp_s + period * k / samples, &q, &qd, &qdd);
    Y.middleRows<6>(6 * k) = calib_regressor(p, q, qd, qdd);
  }
  for (int i = 0; i < kCalibParams; ++i) {  // column-normalised, as the fit does (fit.cc)
    const double c = Y.col(i).norm();
    if (c > 0.0) Y.col(i) /= c;
  }
  const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(Y).singularValues();
  ExcitationCondition out;
  out.rank = rank;
  if (out.rank <= 0) {
    while (out.rank < sv.size() && sv(out.rank) >= null_tol * sv(0)) ++out.rank;
  }
  out.rank = std::min<int>(out.rank, static_cast<int>(sv.size()));
  out.condition_number = out.rank > 0 && sv(out.rank - 1) > 0.0
                             ? sv(0) / sv(out.rank - 1)
                             : std::numeric_limits<double>::infinity();
  return out;
}

ExcitationDesign design_excitation(const PhantomParams& p, const Vec6& q0,
                                   const ExcitationParams& e, int iterations,
                                   const std::function<void(int, double)>& progress) {
  // 100 points over the period: 20 per period of the highest harmonic (5), enough for the
  // condition number to rank candidates at half the cost of 200.
  constexpr int kDesignSamples = 100;
  if (iterations < 0) throw InputError("excitation design: iterations must be >= 0");
  ExcitationDesign d{Excitation(p, q0, e)};
  const ExcitationCondition c0 = excitation_condition(p, d.excitation, kDesignSamples);
  d.rank = c0.rank;
  d.condition_seeded = d.condition_designed = c0.condition_number;
  // The search's own stream, derived from the excitation's seed (reproducible, independent).
  std::mt19937_64 rng(e.seed ^ 0x9e3779b97f4a7c15ULL);
  std::normal_distribution<double> gauss(0.0, 1.0);
  double sigma = 0.3;
  for (int it = 0; it < iterations; ++it) {
    CoefficientMatrix a = d.excitation.a(), b = d.excitation.b();
    for (int j = 0; j < 6; ++j) {
      for (int l = 0; l < e.harmonics; ++l) {
        a(j, l) += sigma * gauss(rng) / (l + 1);
        b(j, l) += sigma * gauss(rng) / (l + 1);
      }
    }
    ++d.iterations;
    bool better = false;
    try {
      Excitation candidate(p, q0, e, a, b);
      const double c = excitation_condition(p, candidate, kDesignSamples, d.rank).condition_number;
      if (c < d.condition_designed) {
        d.excitation = std::move(candidate);
        d.condition_designed = c;
        ++d.accepted;
        better = true;
      }
    } catch (const InputError&) {
      // No amplitude fits the torque limit: not a candidate.
    }
    sigma = better ? std::min(1.0, sigma * 1.5) : std::max(0.02, sigma * 0.85);
    if (progress) progress(it + 1, d.condition_designed);
  }
  return d;
}

}  // namespace dentsim
