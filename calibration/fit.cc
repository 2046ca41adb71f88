#include "calibration/fit.h"

#include <ceres/ceres.h>

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <memory>
#include <stdexcept>

#include "reference/core/io.h"
#include "reference/phantom/phantom_model.h"

namespace dentsim {
namespace {

constexpr int kBodies = kPhantomTreeDof;  // 8 bodies x (mass, Ix, Iy, Iz), then 3 x 6 per joint
constexpr int kArmature = 4 * kBodies;
constexpr int kDamping = kArmature + 6;
constexpr int kCoulomb = kDamping + 6;
static_assert(kCoulomb + 6 == kCalibParams);

PhantomBody& body(PhantomParams& p, int i) {
  PhantomBody* b[kBodies] = {&p.base,          &p.upper_arm,  &p.forearm,      &p.crank,
                             &p.parallel_link, &p.gimbal_yaw, &p.gimbal_pitch, &p.gimbal_roll};
  return *b[i];
}

// Residual r_k = A_k x - tau_k (A_k = Y_k diag(s)): linear, Jacobian A_k.
class TorqueResidual : public ceres::SizedCostFunction<6, kCalibParams> {
 public:
  TorqueResidual(const Regressor& A, const Vec6& tau) : A_(A), tau_(tau) {}
  bool Evaluate(double const* const* x, double* r, double** J) const override {
    const Eigen::Map<const CalibVec> xv(x[0]);
    Eigen::Map<Vec6> rv(r);
    rv = A_ * xv - tau_;
    if (J && J[0]) {
      Eigen::Map<Eigen::Matrix<double, 6, kCalibParams, Eigen::RowMajor>> Jm(J[0]);
      Jm = A_;
    }
    return true;
  }

 private:
  Regressor A_;
  Vec6 tau_;
};

// Weak prior r = w (x - x0).
class PriorResidual : public ceres::SizedCostFunction<kCalibParams, kCalibParams> {
 public:
  PriorResidual(const CalibVec& x0, double w) : x0_(x0), w_(w) {}
  bool Evaluate(double const* const* x, double* r, double** J) const override {
    Eigen::Map<CalibVec> rv(r);
    rv = w_ * (Eigen::Map<const CalibVec>(x[0]) - x0_);
    if (J && J[0]) {
      Eigen::Map<Eigen::Matrix<double, kCalibParams, kCalibParams, Eigen::RowMajor>> Jm(J[0]);
      Jm.setIdentity();
      Jm *= w_;
    }
    return true;
  }

 private:
  CalibVec x0_;
  double w_;
};

// Zero-phase low-pass (forward then backward pass) of a sequence, each pass started in the steady
// state of the sequence's end value. order 1: first order, magnitude 1 / (1 + (f/fc)^2);
// order 2: second-order Butterworth (bilinear transform, cut-off prewarped), magnitude
// 1 / (1 + (f/fc)^4): flat in the excitation band (1e-4 at f = fc/10 instead of 1e-2).
void zero_phase_lowpass(std::vector<Vec6>& y, double dt, double fc, int order) {
  if (fc <= 0.0 || y.size() < 2) return;
  const double pi = 3.14159265358979323846;
  if (order == 1) {
    const double rc = 1.0 / (2.0 * pi * fc);
    const double a = dt / (rc + dt);
    for (std::size_t k = 1; k < y.size(); ++k) y[k] = y[k - 1] + a * (y[k] - y[k - 1]);
    for (std::size_t k = y.size() - 1; k-- > 0;) y[k] = y[k + 1] + a * (y[k] - y[k + 1]);
    return;
  }
  const double K = std::tan(pi * fc * dt), r2 = std::sqrt(2.0);
  const double norm = 1.0 / (1.0 + r2 * K + K * K);
  const double b0 = K * K * norm, b1 = 2.0 * b0, b2 = b0;
  const double a1 = 2.0 * (K * K - 1.0) * norm, a2 = (1.0 - r2 * K + K * K) * norm;
  const auto pass = [&](auto begin, auto end) {
    Vec6 x1 = *begin, x2 = *begin, y1 = *begin, y2 = *begin;
    for (auto it = begin; it != end; ++it) {
      const Vec6 x = *it;
      const Vec6 out = b0 * x + b1 * x1 + b2 * x2 - a1 * y1 - a2 * y2;
      x2 = x1;
      x1 = x;
      y2 = y1;
      y1 = out;
      *it = out;
    }
  };
  pass(y.begin(), y.end());
  pass(y.rbegin(), y.rend());
}

// x at fractional index k - shift (linear interpolation, clamped at the ends).
std::vector<Vec6> shifted(const std::vector<Vec6>& x, double shift) {
  const int n = static_cast<int>(x.size());
  std::vector<Vec6> y(x.size());
  for (int k = 0; k < n; ++k) {
    const double u = std::clamp(k - shift, 0.0, n - 1.0);
    const int i0 = std::min(static_cast<int>(std::floor(u)), n - 2);
    const double a = u - i0;
    y[k] = (1.0 - a) * x[i0] + a * x[i0 + 1];
  }
  return y;
}

using RowMask = Eigen::Matrix<bool, 6, 1>;

using ColumnsFn = std::function<std::vector<Vec6>(const Vec6&, const std::array<CoulombSign, 6>&)>;

// The candidate laws of profile_coulomb_smoothing: (v_s, smooth sign) pairs.
struct CoulombCandidates {
  std::vector<double> v_s;
  std::vector<CoulombSign> sign;
};

CoulombCandidates coulomb_candidates(const Vec6& vs_prior, bool fit_sign,
                                     const std::array<CoulombSign, 6>& sign) {
  std::vector<double> grid;
  for (int i = 0; i <= 20; ++i) grid.push_back(1e-3 * std::pow(10.0, 3.0 * i / 20.0));
  for (int j = 0; j < 6; ++j) grid.push_back(vs_prior(j));
  std::sort(grid.begin(), grid.end());
  grid.erase(std::unique(grid.begin(), grid.end()), grid.end());
  CoulombCandidates cands;
  for (CoulombSign sh : {CoulombSign::kTanh, CoulombSign::kErf}) {
    if (!fit_sign && std::find(sign.begin(), sign.end(), sh) == sign.end()) continue;
    for (double v : grid) {
      cands.v_s.push_back(v);
      cands.sign.push_back(sh);
    }
  }
  return cands;
}

// The profile's least-squares problem: the normal equations of the rows without their Coulomb
// columns (N0, r0, with the targets b), and per joint and candidate the Coulomb column's cross
// terms with the other columns (u), with itself (c2) and with the targets (cb).
struct CoulombProfileSystem {
  using Mat = Eigen::Matrix<double, kCalibParams, kCalibParams>;

  // col[c][i](j): the (scaled) Coulomb column of joint j at used sample i for candidate c.
  std::vector<std::vector<Vec6>> col;
  Mat N0 = Mat::Zero();
  CalibVec r0 = CalibVec::Zero();
  std::vector<Vec6> b;
  std::vector<std::vector<CalibVec>> u;
  std::vector<std::vector<double>> c2, cb;

  void candidate_columns(const CoulombCandidates& cands, const std::vector<RowMask>& kept,
                         const std::vector<int>& at_sample, const CalibVec& s,
                         const ColumnsFn& columns) {
    const int nc = static_cast<int>(cands.v_s.size()), m = static_cast<int>(kept.size());
    col.assign(nc, std::vector<Vec6>(m));
    for (int c = 0; c < nc; ++c) {
      std::array<CoulombSign, 6> same;
      same.fill(cands.sign[c]);
      const std::vector<Vec6> full = columns(Vec6::Constant(cands.v_s[c]), same);
      for (int i = 0; i < m; ++i) {
        for (int j = 0; j < 6; ++j) {
          col[c][i](j) = kept[i](j) ? full[at_sample[i]](j) * s(kCoulomb + j) : 0.0;
        }
      }
    }
  }

  void normal_equations(const std::vector<Regressor>& A0, const std::vector<RowMask>& kept,
                        const std::vector<int>& at_sample, const std::vector<Vec6>& tau) {
    const int m = static_cast<int>(A0.size()), nc = static_cast<int>(col.size());
    b.resize(m);
    for (int i = 0; i < m; ++i) {
      for (int j = 0; j < 6; ++j) b[i](j) = kept[i](j) ? tau[at_sample[i]](j) : 0.0;
      N0.noalias() += A0[i].transpose() * A0[i];
      r0.noalias() += A0[i].transpose() * b[i];
    }
    // Per joint and candidate: the cross terms of the Coulomb column with the other columns.
    u.assign(6, std::vector<CalibVec>(nc, CalibVec::Zero()));
    c2.assign(6, std::vector<double>(nc, 0.0));
    cb = c2;
    for (int j = 0; j < 6; ++j) {
      for (int c = 0; c < nc; ++c) {
        for (int i = 0; i < m; ++i) {
          const double v = col[c][i](j);
          u[j][c].noalias() += v * A0[i].row(j).transpose();
          c2[j][c] += v * v;
          cb[j][c] += v * b[i](j);
        }
      }
    }
  }

  // The residual sum of squares with joint j on candidate ch[j], the prior's ridge included.
  double cost(const std::array<int, 6>& ch, const std::vector<Regressor>& A0, const CalibVec& x0,
              double prior_weight) const {
    const double w2 = prior_weight * prior_weight;
    const int m = static_cast<int>(A0.size());
    Mat N = N0;
    CalibVec r = r0;
    for (int j = 0; j < 6; ++j) {
      const int cj = kCoulomb + j;
      N.col(cj) += u[j][ch[j]];
      N.row(cj) += u[j][ch[j]].transpose();
      N(cj, cj) += c2[j][ch[j]];
      r(cj) += cb[j][ch[j]];
    }
    N.diagonal().array() += w2;
    r += w2 * x0;
    const CalibVec x = N.ldlt().solve(r);
    double rss = 0.0;
    for (int i = 0; i < m; ++i) {
      Vec6 e = A0[i] * x - b[i];
      for (int j = 0; j < 6; ++j) e(j) += col[ch[j]][i](j) * x(kCoulomb + j);
      rss += e.squaredNorm();
    }
    return rss;
  }
};

// FitOptions::fit_coulomb_smoothing: v_s (and with fit_coulomb_sign the smooth sign) per joint by
// profile least squares. For a fixed law the model is linear in p, so each candidate is one
// linear solve: the normal equations of the kept rows (A0: the regressor without its Coulomb
// columns, scaled; the Coulomb column of joint j enters only joint j's rows) with the ridge of the
// weak prior, the cost the residual sum of squares over the kept rows. Candidates: each smooth
// sign times a log grid 0.001..1 rad/s (21 values) and the prior's v_s; joint j takes only its
// own sign `(*sign)[j]` unless `fit_sign` (then either). Coordinate descent over the joints until
// no joint changes (at most 4 passes), from the prior's v_s and `*sign`.
Vec6 profile_coulomb_smoothing(const std::vector<Regressor>& A0, const std::vector<RowMask>& kept,
                               const std::vector<int>& at_sample, const std::vector<Vec6>& tau,
                               const CalibVec& s, const CalibVec& x0, double prior_weight,
                               const Vec6& vs_prior, bool fit_sign,
                               std::array<CoulombSign, 6>* sign, const ColumnsFn& columns,
                               CoulombSmoothingProfile* profile) {
  const CoulombCandidates cands = coulomb_candidates(vs_prior, fit_sign, *sign);
  const std::vector<double>& cand = cands.v_s;
  const std::vector<CoulombSign>& cand_sign = cands.sign;
  const int nc = static_cast<int>(cand.size());
  CoulombProfileSystem sys;
  sys.candidate_columns(cands, kept, at_sample, s, columns);
  sys.normal_equations(A0, kept, at_sample, tau);
  std::array<int, 6> ch{};
  for (int j = 0; j < 6; ++j) {
    ch[j] = 0;
    for (int c = 0; c < nc; ++c) {
      if (cand[c] == vs_prior(j) && cand_sign[c] == (*sign)[j]) ch[j] = c;
    }
  }
  std::array<std::vector<double>, 6> curve;
  for (int pass = 0; pass < 4; ++pass) {
    bool changed = false;
    for (int j = 0; j < 6; ++j) {
      std::array<int, 6> t = ch;
      curve[j].assign(nc, 0.0);
      int best = ch[j];
      for (int c = 0; c < nc; ++c) {
        if (!fit_sign && cand_sign[c] != (*sign)[j]) continue;
        t[j] = c;
        curve[j][c] = sys.cost(t, A0, x0, prior_weight);
        if (curve[j][c] < curve[j][best]) best = c;
      }
      changed = changed || best != ch[j];
      ch[j] = best;
    }
    if (!changed) break;
  }
  Vec6 vs;
  for (int j = 0; j < 6; ++j) {
    vs(j) = cand[ch[j]];
    (*sign)[j] = cand_sign[ch[j]];
  }
  if (profile != nullptr) {
    profile->v_s_rad_s = cand;
    profile->sign = cand_sign;
    profile->rss = curve;
  }
  return vs;
}

}  // namespace

double driver_velocity_lag_ticks(bool lowpass, double cutoff_hz, double T) {
  if (!lowpass) return 0.5;
  const double a = 1.0 - std::exp(-2.0 * 3.14159265358979323846 * cutoff_hz * T);
  return 0.5 + (1.0 - a) / a;
}

Vec3 second_moments(const Vec3& I) {
  return 0.5 * Vec3(I(1) + I(2) - I(0), I(0) + I(2) - I(1), I(0) + I(1) - I(2));
}

std::vector<std::string> calib_param_names() {
  std::vector<std::string> n;
  for (int i = 0; i < kBodies; ++i) {
    const std::string b = phantom_tree_body_name(i);
    n.push_back(b + ".mass_kg");
    n.push_back(b + ".second_moment_x_kg_m2");
    n.push_back(b + ".second_moment_y_kg_m2");
    n.push_back(b + ".second_moment_z_kg_m2");
  }
  for (int j = 1; j <= 6; ++j) n.push_back("armature_kg_m2." + std::to_string(j));
  for (int j = 1; j <= 6; ++j) n.push_back("damping_n_m_s_per_rad." + std::to_string(j));
  for (int j = 1; j <= 6; ++j) n.push_back("coulomb_n_m." + std::to_string(j));
  return n;
}

CalibVec pack_calib_params(const PhantomParams& p) {
  PhantomParams c = p;
  CalibVec x;
  for (int i = 0; i < kBodies; ++i) {
    x(4 * i) = body(c, i).mass_kg;
    x.segment<3>(4 * i + 1) = second_moments(body(c, i).inertia_kg_m2);
  }
  x.segment<6>(kArmature) = p.armature_kg_m2;
  x.segment<6>(kDamping) = p.damping_n_m_s_per_rad;
  x.segment<6>(kCoulomb) = p.coulomb_n_m;
  return x;
}

PhantomParams unpack_calib_params(const PhantomParams& prior, const CalibVec& x) {
  PhantomParams p = prior;
  for (int i = 0; i < kBodies; ++i) {
    body(p, i).mass_kg = x(4 * i);
    body(p, i).inertia_kg_m2 = principal_inertia(x.segment<3>(4 * i + 1));
  }
  p.armature_kg_m2 = x.segment<6>(kArmature);
  p.damping_n_m_s_per_rad = x.segment<6>(kDamping);
  p.coulomb_n_m = x.segment<6>(kCoulomb);
  return p;
}

Regressor calib_regressor(const PhantomParams& prior, const Vec6& q, const Vec6& qd,
                          const Vec6& qdd) {
  using J = ceres::Jet<double, kCalibParams>;
  using V6J = Eigen::Matrix<J, 6, 1>;
  PhantomTreeT<J> tree = phantom_tree<J>(prior);
  const CalibVec x0 = pack_calib_params(prior);
  for (int i = 0; i < kBodies; ++i) {
    tree.mass[i] = J(x0(4 * i), 4 * i);
    Eigen::Matrix<J, 3, 1> d;
    for (int a = 0; a < 3; ++a) d(a) = J(x0(4 * i + 1 + a), 4 * i + 1 + a);
    tree.inertia[i] = principal_inertia(d);
  }
  for (int j = 0; j < 6; ++j) {
    tree.armature(j) = J(x0(kArmature + j), kArmature + j);
    tree.damping(j) = J(x0(kDamping + j), kDamping + j);
    tree.coulomb(j) = J(x0(kCoulomb + j), kCoulomb + j);
  }
  const PhantomModelT<J> model(tree);
  const V6J qj = q.cast<J>(), qdj = qd.cast<J>(), qddj = qdd.cast<J>();
  const V6J tau = model.M(qj) * qddj + model.bias(qj, qdj) + model.g(qj) + model.friction(qdj);
  Regressor Y;
  for (int j = 0; j < 6; ++j) Y.row(j) = tau(j).v.transpose();  // tau = Y p (linear in p)
  return Y;
}

Regressor calib_regressor_by_columns(const PhantomParams& prior, const Vec6& q, const Vec6& qd,
                                     const Vec6& qdd) {
  Regressor Y;
  for (int i = 0; i < kCalibParams; ++i) {
    const PhantomModelD model(unpack_calib_params(prior, CalibVec::Unit(i)));
    Y.col(i) = model.M(q) * qdd + model.bias(q, qd) + model.g(q) + model.friction(qd);
  }
  return Y;
}

namespace {

FitResult fit_impl(const CalibrationLog& log, const PhantomParams& prior, const FitOptions& opt,
                   const std::array<CoulombSign, 6>* sign_override,
                   std::vector<Regressor>* regressors);

// The log as the fit sees it: shifted and low-passed signals, the smooth sign of each joint's
// Coulomb law, and the stride between used samples.
struct FitSignals {
  FitSignals(const CalibrationLog& log_in, const FitOptions& opt_in) : log(log_in), opt(opt_in) {}

  const CalibrationLog& log;
  const FitOptions& opt;
  int n = 0;
  double dt = 0.0;
  std::vector<Vec6> qd, tau, q;
  std::array<CoulombSign, 6> sign{};
  int stride = 1;

  // Parallel filtering of the Coulomb regressor column: the filter of tanh(v / v_s), not tanh of
  // the filtered velocity (they differ around every velocity reversal, and the difference would
  // be absorbed by the viscous damping); v the low-passed qd by default (its sign is right where
  // the logged qd's noise flips it, options.coulomb_from_filtered_velocity).
  std::vector<Vec6> coulomb_columns(const Vec6& vs, const std::array<CoulombSign, 6>& law) const {
    std::vector<Vec6> col(n);
    for (int k = 0; k < n; ++k) {
      for (int j = 0; j < 6; ++j) {
        const double v = opt.coulomb_from_filtered_velocity ? qd[k](j) : log.qd[k](j);
        col[k](j) = phantom_joint_friction(0.0, 1.0, vs(j), v, law[static_cast<std::size_t>(j)]);
      }
    }
    zero_phase_lowpass(col, dt, opt.lowpass_hz, opt.lowpass_order);
    return col;
  }
};

FitSignals prepare_signals(const CalibrationLog& log, const PhantomParams& prior,
                           const FitOptions& opt, const std::array<CoulombSign, 6>* sign_override) {
  FitSignals sig(log, opt);
  const int n = log.size();
  if (n < 3) throw InputError("calibrate: log too short (fewer than 3 samples)");
  sig.n = n;
  sig.dt = (log.t.back() - log.t.front()) / (n - 1);
  sig.qd = log.qd;
  sig.tau = opt.torque_shift_samples != 0.0 ? shifted(log.tau, opt.torque_shift_samples) : log.tau;
  sig.q = opt.position_shift_samples != 0.0 ? shifted(log.q, opt.position_shift_samples) : log.q;
  zero_phase_lowpass(sig.qd, sig.dt, opt.lowpass_hz, opt.lowpass_order);
  zero_phase_lowpass(sig.tau, sig.dt, opt.lowpass_hz, opt.lowpass_order);
  sig.sign = prior.coulomb_sign;
  if (opt.coulomb_sign) sig.sign.fill(*opt.coulomb_sign);
  if (sign_override != nullptr) sig.sign = *sign_override;
  sig.stride = std::max(1, (n - 2) / std::max(1, opt.max_samples));  // before trimming
  return sig;
}

// The prior's parameters p0 and the scale s of each (x = p / s is what Ceres solves for).
struct FitScaling {
  CalibVec p0, s;
};

FitScaling scale_by_prior(const PhantomParams& prior) {
  FitScaling sc;
  sc.p0 = pack_calib_params(prior);
  for (int i = 0; i < kCalibParams; ++i) {
    if (sc.p0(i) < 0.0) {
      throw InputError("calibrate: prior parameter " + calib_param_names()[i] +
                       " is negative: expected a physically consistent prior model");
    }
    sc.s(i) = sc.p0(i) > 0.0 ? sc.p0(i) : 1e-9;
  }
  return sc;
}

// FitOptions::min_speed_rad_s, then exclude_slow_fraction of the rows left: per joint, the
// speed below which its rows are dropped. The filters' start and end transients: samples within
// `trim` (one cut-off period) of either end of the log are not used.
Vec6 slow_row_speeds(const FitSignals& sig, const FitOptions& opt, int trim) {
  Vec6 slow_below = Vec6::Constant(opt.min_speed_rad_s);
  if (opt.exclude_slow_fraction > 0.0) {
    for (int j = 0; j < 6; ++j) {
      std::vector<double> speeds;
      for (int k = std::max(1, trim); k + 1 < sig.n - trim; k += sig.stride) {
        if (std::abs(sig.qd[k](j)) >= opt.min_speed_rad_s) speeds.push_back(std::abs(sig.qd[k](j)));
      }
      if (speeds.empty()) continue;
      const std::size_t at = std::min(
          speeds.size() - 1, static_cast<std::size_t>(opt.exclude_slow_fraction * speeds.size()));
      std::nth_element(speeds.begin(), speeds.begin() + at, speeds.end());
      slow_below(j) = speeds[at];
    }
  }
  return slow_below;
}

// The used samples: each one's log index, its scaled regressor without its Coulomb columns (they
// depend on v_s) and the rows kept.
struct FitRows {
  std::vector<int> at_sample;
  std::vector<Regressor> A0;
  std::vector<RowMask> kept;
};

FitRows select_rows(const FitSignals& sig, const PhantomParams& prior, const CalibVec& s,
                    const FitOptions& opt, std::vector<Regressor>* regressors) {
  if (!(opt.exclude_slow_fraction >= 0.0 && opt.exclude_slow_fraction < 1.0)) {
    throw InputError("calibrate: exclude_slow_fraction must be in [0, 1)");
  }
  const int n = sig.n;
  const int trim =
      opt.lowpass_hz > 0.0
          ? static_cast<int>(std::min(n / 4.0, std::ceil(1.0 / (opt.lowpass_hz * sig.dt))))
          : 0;
  if (!(opt.min_speed_rad_s >= 0.0 && std::isfinite(opt.min_speed_rad_s))) {
    throw InputError("calibrate: min_speed_rad_s must be a finite number >= 0");
  }
  const Vec6 slow_below = slow_row_speeds(sig, opt, trim);
  FitRows rows;
  const bool reuse = !regressors->empty();
  std::size_t used = 0;
  for (int k = std::max(1, trim); k + 1 < n - trim; k += sig.stride, ++used) {
    if (!reuse) {
      const Vec6 qdd = (sig.qd[k + 1] - sig.qd[k - 1]) / (sig.log.t[k + 1] - sig.log.t[k - 1]);
      regressors->push_back(calib_regressor(prior, sig.q[k], sig.qd[k], qdd));
      for (int j = 0; j < 6; ++j) regressors->back()(j, kCoulomb + j) = 0.0;
    } else if (used >= regressors->size()) {
      throw std::logic_error("fit_calibration: a refit used more samples than the fit");
    }
    Regressor Y = (*regressors)[used];
    RowMask keep;
    for (int j = 0; j < 6; ++j) {
      keep(j) = !(std::abs(sig.qd[k](j)) < slow_below(j));
      if (!keep(j)) Y.row(j).setZero();  // a dropped row: no residual
    }
    rows.A0.push_back(Y * s.asDiagonal());
    rows.kept.push_back(keep);
    rows.at_sample.push_back(k);
  }
  return rows;
}

// The fit's linear least-squares rows A_k x = b_k (Coulomb columns of the chosen law filled in,
// dropped rows zero) and the low-passed qd of each used sample (diagnostics).
struct FitSystem {
  std::vector<Regressor> A;
  std::vector<Vec6> b;
  std::vector<Vec6> used_qd;
};

FitSystem stack_rows(const FitSignals& sig, FitRows& rows, const CalibVec& s, const Vec6& vs,
                     FitResult& res) {
  FitSystem sys;
  const std::vector<Vec6> coulomb_col = sig.coulomb_columns(vs, sig.sign);
  for (std::size_t i = 0; i < rows.A0.size(); ++i) {
    const int k = rows.at_sample[i];
    Regressor Ai = rows.A0[i];
    Vec6 tk = sig.tau[k];
    for (int j = 0; j < 6; ++j) {
      if (rows.kept[i](j)) {
        Ai(j, kCoulomb + j) = coulomb_col[k](j) * s(kCoulomb + j);
      } else {
        tk(j) = 0.0;
      }
    }
    sys.A.push_back(Ai);
    sys.b.push_back(tk);
    res.t.push_back(sig.log.t[k]);
    sys.used_qd.push_back(sig.qd[k]);
  }
  rows.A0.clear();
  return sys;
}

// The torque residuals (Huber-robust if asked), the weak prior and the lower bounds, solved by
// Ceres from x.
void solve_fit(const FitSystem& sys, const FitScaling& sc, const CalibVec& x0,
               const FitOptions& opt, ceres::Problem& problem, CalibVec& x, FitResult& res) {
  const int m = static_cast<int>(sys.A.size());
  for (int k = 0; k < m; ++k) {
    problem.AddResidualBlock(new TorqueResidual(sys.A[k], sys.b[k]),
                             opt.huber_n_m > 0 ? new ceres::HuberLoss(opt.huber_n_m) : nullptr,
                             x.data());
  }
  problem.AddResidualBlock(new PriorResidual(x0, opt.prior_weight), nullptr, x.data());
  // Physical consistency: every parameter at least min_fraction of its prior (masses, second
  // moments, armature, damping and Coulomb friction are non-negative; the model file wants them
  // positive).
  for (int i = 0; i < kCalibParams; ++i) {
    problem.SetParameterLowerBound(x.data(), i, sc.p0(i) > 0.0 ? opt.min_fraction : 0.0);
  }
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = opt.max_iterations;
  so.function_tolerance = 1e-12;
  so.gradient_tolerance = 1e-14;
  so.parameter_tolerance = 1e-12;
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  res.converged = summary.termination_type == ceres::CONVERGENCE && summary.IsSolutionUsable();
  res.report = summary.BriefReport();
  res.iterations = static_cast<int>(summary.iterations.size());
}

// Residuals at the solution: per-sample measured and predicted torques, the RMS (overall and per
// joint over the kept rows), the rows used. Returns the residual sum of squares.
double fit_residuals(const FitSystem& sys, const std::vector<RowMask>& kept, const CalibVec& x,
                     FitResult& res) {
  const int m = static_cast<int>(sys.A.size());
  double rss = 0.0;
  for (int k = 0; k < m; ++k) {
    const Vec6 pred = sys.A[k] * x;
    const Vec6 r = pred - sys.b[k];
    rss += r.squaredNorm();
    res.residual_rms_joint += r.cwiseAbs2();
    res.rows_used += kept[k].cast<int>();
    res.tau_measured.push_back(sys.b[k]);
    res.tau_predicted.push_back(pred);
    res.row_used.push_back({});
    for (int j = 0; j < 6; ++j) res.row_used.back()[j] = kept[k](j);
  }
  res.samples = m;
  const int rows = std::max(1, res.rows_used.sum());
  res.residual_rms = std::sqrt(rss / rows);
  res.residual_rms_joint =
      res.residual_rms_joint.cwiseQuotient(res.rows_used.cwiseMax(1).cast<double>()).cwiseSqrt();
  return rss;
}

// Identifiability: near-null space of the column-normalised stacked Jacobian. Sets the condition
// number; returns the column norms `*cn` and the near-null basis.
Eigen::MatrixXd near_null_space(const FitSystem& sys, const FitOptions& opt, CalibVec* cn,
                                FitResult& res) {
  const int m = static_cast<int>(sys.A.size());
  Eigen::MatrixXd Js(6 * m, kCalibParams);
  for (int k = 0; k < m; ++k) Js.middleRows<6>(6 * k) = sys.A[k];
  for (int i = 0; i < kCalibParams; ++i) (*cn)(i) = Js.col(i).norm();
  Eigen::MatrixXd Jn = Js;
  for (int i = 0; i < kCalibParams; ++i) Jn.col(i) /= (*cn)(i) > 0 ? (*cn)(i) : 1.0;
  Eigen::BDCSVD<Eigen::MatrixXd> svd(Jn, Eigen::ComputeThinV);
  const Eigen::VectorXd sv = svd.singularValues();
  const double smax = sv(0);
  int kept = 0;
  while (kept < sv.size() && sv(kept) >= opt.null_tol * smax) ++kept;
  res.condition_number = kept > 0 ? smax / sv(kept - 1) : 0.0;
  return svd.matrixV().rightCols(kCalibParams - kept);
}

using CalibMat = Eigen::Matrix<double, kCalibParams, kCalibParams>;

// Covariance of x (prior included, so the information matrix is regular); NaN where Ceres cannot.
CalibMat solution_covariance(ceres::Problem& problem, CalibVec& x) {
  Eigen::Matrix<double, kCalibParams, kCalibParams, Eigen::RowMajor> cov;
  cov.setConstant(std::numeric_limits<double>::quiet_NaN());
  ceres::Covariance::Options co;
  co.algorithm_type = ceres::DENSE_SVD;
  co.null_space_rank = -1;
  ceres::Covariance covariance(co);
  std::vector<std::pair<const double*, const double*>> blocks{{x.data(), x.data()}};
  if (covariance.Compute(blocks, &problem))
    covariance.GetCovarianceBlock(x.data(), x.data(), cov.data());
  return cov;
}

// The fitted model and one FitParameter per parameter (value, prior, structural identifiability).
void fitted_parameters(const PhantomParams& prior, const FitScaling& sc, const CalibVec& x,
                       const Vec6& vs, const std::array<CoulombSign, 6>& sign, const CalibVec& cn,
                       const Eigen::MatrixXd& Vnull, const FitOptions& opt, FitResult& res) {
  const CalibVec p = x.cwiseProduct(sc.s);
  res.fitted = unpack_calib_params(prior, p);
  res.fitted.coulomb_smoothing_rad_s = vs;
  res.fitted.coulomb_sign = sign;
  const auto names = calib_param_names();
  for (int i = 0; i < kCalibParams; ++i) {
    FitParameter fp;
    fp.name = names[i];
    fp.prior = sc.p0(i);
    fp.value = p(i);
    fp.identifiable = cn(i) > 0 && Vnull.row(i).norm() < opt.null_component;
    fp.structurally_identifiable = fp.identifiable;
    res.identifiable += fp.identifiable;
    res.params.push_back(fp);
  }
}

// Standard deviations. The textbook estimate C sigma^2 (C = (J^T J)^-1 from Ceres, sigma^2 =
// RSS / dof) assumes independent residuals; after the zero-phase low-pass, and with encoder
// quantisation (a slowly varying error), neighbouring samples' residuals are correlated and it
// is too small. Reported instead: the heteroscedasticity- and autocorrelation-consistent
// (Newey-West) sandwich C S C, S = sum_{|l| <= L} w_l sum_k g_k g_{k+l}^T with g_k = A_k^T r_k
// (the per-sample score) and Bartlett weights w_l = 1 - |l| / (L + 1); L covers three cut-off
// periods of the low-pass (in used samples) and at least the usual 4 (m/100)^(2/9).
void parameter_stds(const FitSystem& sys, const CalibVec& x, const CalibVec& s, const CalibMat& cov,
                    double rss, double dt, const FitOptions& opt, FitResult& res) {
  const int m = static_cast<int>(sys.A.size());
  const std::vector<Regressor>& A = sys.A;
  const std::vector<Vec6>& b = sys.b;
  const int rows = std::max(1, res.rows_used.sum());
  const double dof = std::max(1, rows - res.identifiable);
  const double sigma2 = rss / dof;
  const double corr_s = opt.lowpass_hz > 0.0 ? 3.0 / opt.lowpass_hz : 0.0;
  const double used_dt = m > 1 ? (res.t.back() - res.t.front()) / (m - 1) : dt;
  res.hac_lags =
      std::min(m - 1, std::max(static_cast<int>(std::ceil(corr_s / used_dt)),
                               static_cast<int>(std::floor(4.0 * std::pow(m / 100.0, 2.0 / 9.0)))));
  std::vector<CalibVec> g(m);
  for (int k = 0; k < m; ++k) g[k] = A[k].transpose() * (A[k] * x - b[k]);
  CalibMat S = CalibMat::Zero();
  for (int k = 0; k < m; ++k) S.noalias() += g[k] * g[k].transpose();
  for (int l = 1; l <= res.hac_lags; ++l) {
    const double w = 1.0 - static_cast<double>(l) / (res.hac_lags + 1);
    CalibMat Sl = CalibMat::Zero();
    for (int k = 0; k + l < m; ++k) Sl.noalias() += g[k] * g[k + l].transpose();
    S += w * (Sl + Sl.transpose());
  }
  const CalibMat C = cov;
  // Named steps, not one expression: GCC's -O1 (the sanitizer build) warns maybe-uninitialized
  // inside Eigen's product of a scaled product.
  CalibMat CS, cov_hac;
  CS.noalias() = C * S;
  cov_hac.noalias() = CS * C;
  cov_hac *= rows / dof;
  for (int i = 0; i < kCalibParams; ++i) {
    FitParameter& fp = res.params[i];
    fp.std_white = s(i) * std::sqrt(std::max(0.0, cov(i, i)) * sigma2);
    fp.std_statistical = s(i) * std::sqrt(std::max(0.0, cov_hac(i, i)));
    fp.std = fp.std_statistical;
  }
}

// Whiteness of joint j's residual e over its kept rows: the autocorrelation, its lag-1 value,
// Ljung-Box, the correlation length.
void residual_whiteness(int j, const std::vector<double>& e, const std::vector<RowMask>& kept,
                        int nj, double c0, ResidualDiagnostics& dg) {
  const int m = static_cast<int>(e.size());
  const int K = dg.autocorrelation_lags;
  std::vector<double>& rho = dg.autocorrelation[j];
  rho.assign(K, 0.0);
  dg.correlation_length[j] = K + 1;
  double lb_sum = 0.0;
  for (int l = 1; l <= K; ++l) {
    double c = 0.0;
    int pairs = 0;
    for (int k = 0; k + l < m; ++k) {
      if (!kept[k](j) || !kept[k + l](j)) continue;
      c += e[k] * e[k + l];
      ++pairs;
    }
    rho[l - 1] = pairs > 0 && c0 > 0.0 ? (c / pairs) / (c0 / nj) : 0.0;
    if (nj > l) lb_sum += rho[l - 1] * rho[l - 1] / (nj - l);
    if (dg.correlation_length[j] == K + 1 && nj > 0 &&
        std::abs(rho[l - 1]) < 2.0 / std::sqrt(static_cast<double>(nj))) {
      dg.correlation_length[j] = l;
    }
  }
  dg.lag1_autocorrelation(j) = rho[0];
  dg.ljung_box_q(j) = static_cast<double>(nj) * (nj + 2.0) * lb_sum;
  dg.white[j] = dg.ljung_box_q(j) <= dg.ljung_box_threshold;
}

// Joint j's residual in the slowest and the fastest quarter of |qd_j| (vr: (signed qd, residual)
// of the kept rows); a slow residual over twice the fast one is a model-mismatch reason.
void residual_by_speed(int j, const std::vector<std::pair<double, double>>& vr, FitResult& res) {
  ResidualDiagnostics& dg = res.diagnostics;
  std::vector<std::pair<double, double>> by_speed = vr;
  for (auto& [v, r] : by_speed) v = std::abs(v);
  std::sort(by_speed.begin(), by_speed.end());
  const int mj = static_cast<int>(by_speed.size());
  const int quarter = std::max(1, mj / 4);
  double slow = 0.0, fast = 0.0;
  for (int k = 0; k < quarter && k < mj; ++k) {
    slow += by_speed[k].second * by_speed[k].second;
    fast += by_speed[mj - 1 - k].second * by_speed[mj - 1 - k].second;
  }
  dg.rms_slow(j) = std::sqrt(slow / quarter);
  dg.rms_fast(j) = std::sqrt(fast / quarter);
  if (dg.rms_slow(j) > 2.0 * dg.rms_fast(j)) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "joint %d: residual %.3g N m at low speed, %.3g at high", j + 1,
                  dg.rms_slow(j), dg.rms_fast(j));
    res.model_mismatch_reasons.emplace_back(buf);
  }
}

// Joint j's residual against the signed velocity: 5 bins of equal count on each side of 0.
void residual_vs_velocity(std::vector<std::pair<double, double>>& vr,
                          ResidualDiagnostics::VelocityBins& vb) {
  std::sort(vr.begin(), vr.end());
  const std::size_t zero = static_cast<std::size_t>(
      std::lower_bound(vr.begin(), vr.end(), std::make_pair(0.0, -HUGE_VAL)) - vr.begin());
  for (const auto& [first, last] : {std::pair{std::size_t{0}, zero}, {zero, vr.size()}}) {
    const std::size_t n_side = last - first, nb = std::min<std::size_t>(5, n_side);
    for (std::size_t bin = 0; bin < nb; ++bin) {
      const std::size_t lo = first + n_side * bin / nb, hi = first + n_side * (bin + 1) / nb;
      double sq = 0.0, se = 0.0, se2 = 0.0;
      for (std::size_t i = lo; i < hi; ++i) {
        sq += vr[i].first;
        se += vr[i].second;
        se2 += vr[i].second * vr[i].second;
      }
      const double cnt = static_cast<double>(hi - lo);
      vb.qd.push_back(sq / cnt);
      vb.mean.push_back(se / cnt);
      vb.rms.push_back(std::sqrt(se2 / cnt));
      vb.rows.push_back(static_cast<int>(hi - lo));
    }
  }
}

// Residual diagnostics (ResidualDiagnostics), per joint over its kept rows: whiteness (the
// autocorrelation, its lag-1 value, Ljung-Box, the correlation length), the residual at low vs
// high speed, and the residual against the signed velocity.
void residual_diagnostics(const std::vector<RowMask>& kept, const std::vector<Vec6>& used_qd,
                          FitResult& res) {
  const int m = static_cast<int>(kept.size());
  ResidualDiagnostics& dg = res.diagnostics;
  const int K = std::max(1, std::min(std::max(10, 2 * res.hac_lags), m / 4));
  dg.autocorrelation_lags = K;
  // chi^2_K 99 % point, Wilson-Hilferty: K (1 - 2 / (9K) + z sqrt(2 / (9K)))^3, z = 2.3263.
  const double a = 2.0 / (9.0 * K);
  dg.ljung_box_threshold = K * std::pow(1.0 - a + 2.3263478740408408 * std::sqrt(a), 3);
  std::vector<double> e(m);
  for (int j = 0; j < 6; ++j) {
    int nj = 0;
    double c0 = 0.0;
    // (signed low-passed qd, residual) of the kept rows.
    std::vector<std::pair<double, double>> vr;
    for (int k = 0; k < m; ++k) {
      e[k] = kept[k](j) ? res.tau_predicted[k](j) - res.tau_measured[k](j) : 0.0;
      if (!kept[k](j)) continue;
      ++nj;
      c0 += e[k] * e[k];
      vr.emplace_back(used_qd[k](j), e[k]);
    }
    residual_whiteness(j, e, kept, nj, c0, dg);
    if (vr.empty()) continue;
    residual_by_speed(j, vr, res);
    residual_vs_velocity(vr, dg.residual_vs_velocity[j]);
  }
}

// The model-mismatch term (FitOptions::model_mismatch_term): the fit again without the slowest
// quarter of the rows.
void model_mismatch_term(const CalibrationLog& log, const PhantomParams& prior,
                         const FitOptions& opt, const CalibVec& s,
                         std::vector<Regressor>* regressors, FitResult& res) {
  FitOptions reduced = opt;
  reduced.exclude_slow_fraction = 0.25;
  reduced.model_mismatch_term = false;
  // v_s is chosen again on the reduced rows: how much the choice moves the parameters is part
  // of what the rows near reversal say about the law.
  const FitResult alt = fit_impl(log, prior, reduced, &res.coulomb_sign, regressors);
  for (int i = 0; i < kCalibParams; ++i) {
    FitParameter& fp = res.params[i];
    const double d = alt.params[i].value - fp.value;
    const double var_d =
        std::max(0.0, alt.params[i].std_statistical * alt.params[i].std_statistical -
                          fp.std_statistical * fp.std_statistical);
    fp.std_model = std::sqrt(std::max(0.0, d * d - var_d));
    fp.std = std::hypot(fp.std_statistical, fp.std_model);
    const double z = var_d > 0.0 ? std::abs(d) / std::sqrt(var_d) : 0.0;
    if (fp.identifiable && fp.std_statistical <= opt.max_rel_std * s(i) && z > 3.0) {
      char buf[160];
      std::snprintf(buf, sizeof buf,
                    "%s: moves %.3g (%.1f std of the difference) without the slow rows",
                    fp.name.c_str(), d, z);
      res.model_mismatch_reasons.emplace_back(buf);
    }
  }
}

// The law term (FitOptions::law_mismatch_term): the same rows, each joint's other smooth sign.
void law_mismatch_term(const CalibrationLog& log, const PhantomParams& prior, const FitOptions& opt,
                       const CalibVec& s, std::vector<Regressor>* regressors, FitResult& res) {
  FitOptions other = opt;
  other.model_mismatch_term = false;
  std::array<CoulombSign, 6> flipped = res.coulomb_sign;
  for (CoulombSign& c : flipped) {
    c = c == CoulombSign::kTanh ? CoulombSign::kErf : CoulombSign::kTanh;
  }
  const FitResult alt = fit_impl(log, prior, other, &flipped, regressors);
  for (int i = 0; i < kCalibParams; ++i) {
    FitParameter& fp = res.params[i];
    const double d = alt.params[i].value - fp.value;
    fp.std_law = std::abs(d);
    fp.std =
        std::sqrt(fp.std_statistical * fp.std_statistical + fp.std_model * fp.std_model + d * d);
    if (fp.identifiable && fp.std_statistical <= opt.max_rel_std * s(i) &&
        std::abs(d) > 3.0 * fp.std_statistical) {
      char buf[160];
      std::snprintf(buf, sizeof buf, "%s: moves %.3g (%.1f std) with the other smooth sign",
                    fp.name.c_str(), d, std::abs(d) / fp.std_statistical);
      res.model_mismatch_reasons.emplace_back(buf);
    }
  }
}

// Practically identifiable: the data pin it to better than max_rel_std of its prior (the
// statistical std: what the data say; the model terms say how far the law may move it, which
// the reported std carries and the bar checks against).
void practical_identifiability(const CalibVec& s, const FitOptions& opt, FitResult& res) {
  for (int i = 0; i < kCalibParams; ++i) {
    FitParameter& fp = res.params[i];
    if (fp.identifiable && !(fp.std_statistical <= opt.max_rel_std * s(i))) {
      fp.identifiable = false;
      --res.identifiable;
    }
  }
}

// fit_calibration, with each joint's smooth sign `*sign_override` instead of the options' (the
// law term's refit). `*regressors`: Y of each used sample without its Coulomb columns, computed
// here when empty, else reused (the refits use the log's samples as the fit does: the autodiff
// regressor is most of a fit's time).
FitResult fit_impl(const CalibrationLog& log, const PhantomParams& prior, const FitOptions& opt,
                   const std::array<CoulombSign, 6>* sign_override,
                   std::vector<Regressor>* regressors) {
  FitSignals sig = prepare_signals(log, prior, opt, sign_override);
  const FitScaling sc = scale_by_prior(prior);
  const CalibVec& s = sc.s;
  CalibVec x = sc.p0.cwiseQuotient(s);
  const CalibVec x0 = x;

  FitResult res;
  FitRows rows = select_rows(sig, prior, s, opt, regressors);
  // v_s per joint: the prior's, or chosen by profile least squares (FitOptions).
  Vec6 vs = prior.coulomb_smoothing_rad_s;
  if (opt.fit_coulomb_smoothing) {
    const ColumnsFn columns = [&sig](const Vec6& v, const std::array<CoulombSign, 6>& law) {
      return sig.coulomb_columns(v, law);
    };
    vs = profile_coulomb_smoothing(rows.A0, rows.kept, rows.at_sample, sig.tau, s, x0,
                                   opt.prior_weight, vs, opt.fit_coulomb_sign && !sign_override,
                                   &sig.sign, columns, &res.coulomb_smoothing_profile);
  }
  res.coulomb_smoothing_rad_s = vs;
  res.coulomb_sign = sig.sign;
  const FitSystem sys = stack_rows(sig, rows, s, vs, res);

  ceres::Problem problem;
  solve_fit(sys, sc, x0, opt, problem, x, res);
  const double rss = fit_residuals(sys, rows.kept, x, res);
  CalibVec cn;
  const Eigen::MatrixXd Vnull = near_null_space(sys, opt, &cn, res);
  const CalibMat cov = solution_covariance(problem, x);
  fitted_parameters(prior, sc, x, vs, sig.sign, cn, Vnull, opt, res);
  parameter_stds(sys, x, s, cov, rss, sig.dt, opt, res);
  residual_diagnostics(rows.kept, sys.used_qd, res);
  if (opt.model_mismatch_term) model_mismatch_term(log, prior, opt, s, regressors, res);
  if (opt.model_mismatch_term && opt.law_mismatch_term) {
    law_mismatch_term(log, prior, opt, s, regressors, res);
  }
  res.model_mismatch = !res.model_mismatch_reasons.empty();
  practical_identifiability(s, opt, res);
  return res;
}

}  // namespace

FitResult fit_calibration(const CalibrationLog& log, const PhantomParams& prior,
                          const FitOptions& options) {
  std::vector<Regressor> regressors;
  return fit_impl(log, prior, options, nullptr, &regressors);
}

}  // namespace dentsim
