#include "calibration/excitation.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
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

CalibrationLog run_excitation(Device& device, const PhantomParams& p, const Excitation& exc,
                              double duration, const TrackingParams& tracking,
                              ExactState exact_state) {
  if ((exact_state.q == nullptr) != (exact_state.qd == nullptr)) {
    throw InputError("excite: exact state needs both q and qd");
  }
  if (device.dof() != 6) throw InputError("excite: the device must have 6 joints");
  const PhantomModelD model(p);
  const Mat6 M0 = model.M(exc.q0());
  const Vec6 kp = M0.diagonal() * tracking.bandwidth_rad_s * tracking.bandwidth_rad_s;
  const Vec6 kd = M0.diagonal() * 2.0 * tracking.bandwidth_rad_s;
  CalibrationLog log;
  DeviceSample s = device.make_sample();
  device.read(s);
  const double t0 = s.t;
  VecX tau(6);
  while (true) {
    device.read(s);
    const double t = s.t - t0;
    if (t > duration) break;
    Vec6 qr, qdr, qddr;
    exc.eval(t, &qr, &qdr, &qddr);
    const Vec6 q = exact_state.q ? Vec6(*exact_state.q) : Vec6(s.q);
    const Vec6 qd = exact_state.qd ? Vec6(*exact_state.qd) : Vec6(s.qd);
    tau = model.M(q) * qddr + model.bias(q, qd) + model.g(q) + model.friction(qdr) +
          kp.cwiseProduct(qr - q) + kd.cwiseProduct(qdr - qd);
    device.write(tau);
    if (device.faults() != kFaultNone) {
      throw InputError("excite: device fault " + fault_string(device.faults()) +
                       " at t = " + std::to_string(t) + " s");
    }
    log.t.push_back(t);
    log.q.push_back(q);
    log.qd.push_back(qd);
    log.tau.push_back(device.applied_torque());
    device.advance();
  }
  return log;
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
