#include "reference/pmi.h"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <cmath>
#include <stdexcept>
#include <string>

#include "reference/core/io.h"
#include "reference/core/so3.h"

namespace dentsim {

namespace {

void require(bool ok, const std::string& what) {
  if (!ok) throw InputError("ProxyParams: " + what);
}

}  // namespace

void validate_proxy_params(const ProxyParams& p) {
  require(std::isfinite(p.mass) && p.mass > 0.0,
          "mass must be finite and > 0 kg, got " + std::to_string(p.mass));
  require(p.inertia.allFinite(), "inertia must be finite");
  require((p.inertia - p.inertia.transpose()).norm() <= 1e-12 * p.inertia.norm(),
          "inertia must be symmetric");
  const Eigen::SelfAdjointEigenSolver<Mat3> eig(p.inertia, Eigen::EigenvaluesOnly);
  require(eig.eigenvalues().minCoeff() > 0.0, "inertia must be positive definite (kg m^2)");
  require(std::isfinite(p.damping_lin) && p.damping_lin >= 0.0,
          "damping_lin must be finite and >= 0 N s/m, got " + std::to_string(p.damping_lin));
  require(std::isfinite(p.damping_ang) && p.damping_ang >= 0.0,
          "damping_ang must be finite and >= 0 N m s/rad, got " + std::to_string(p.damping_ang));
}

void validate_tick_length(double T) {
  if (!(std::isfinite(T) && T > 0.0)) {
    throw InputError("tick length T must be finite and > 0 s, got " + std::to_string(T));
  }
}

PmiSystem pmi_inertia_system(const ProxyParams& p, const ProxyState& s, double T,
                             GyroVelocity gyro) {
  validate_proxy_params(p);
  validate_tick_length(T);
  return pmi_inertia_system_unchecked(p, s, T, gyro);
}

PmiSystem pmi_inertia_system_unchecked(const ProxyParams& p, const ProxyState& s, double T,
                                       GyroVelocity gyro) {
  const Mat6 M = p.M();
  PmiSystem sys;
  sys.A = M * (2.0 / T) + p.B();  // (4.2) left-hand side
  if (p.gyroscopic) {
    // (2.8): C_k = diag(0, -S(J w)), skew, so it does no work on V_hat.
    const Vec3 w =
        gyro == GyroVelocity::kStart ? Vec3(ang(s.V)) : Vec3(2.0 * ang(s.V) - ang(s.V_hat_prev));
    sys.A.bottomRightCorner<3, 3>() -= skew(p.inertia * w);
  }
  sys.b = M * (2.0 / T) * s.V;  // (4.2) right-hand side, inertia part
  return sys;
}

Vec6 pmi_scaling(const Mat6& A) {
  Vec6 d;
  for (int i = 0; i < 6; ++i) {
    const double a = std::abs(A(i, i));
    d(i) = a > 0.0 ? 1.0 / std::sqrt(a) : 1.0;
  }
  return d;
}

namespace {

enum class SolveOutcome { kOk, kSystemNotFinite, kSingular, kResultNotFinite };

SolveOutcome solve_scaled(const PmiSystem& sys, Vec6* V_hat) {
  if (!sys.A.allFinite() || !sys.b.allFinite()) return SolveOutcome::kSystemNotFinite;
  const Vec6 d = pmi_scaling(sys.A);  // solve (D A D) y = D b, V_hat = D y
  const Mat6 As = d.asDiagonal() * sys.A * d.asDiagonal();
  const Eigen::FullPivLU<Mat6> lu(As);
  if (!lu.isInvertible()) return SolveOutcome::kSingular;
  const Vec6 y = lu.solve(d.cwiseProduct(sys.b));
  *V_hat = d.cwiseProduct(y);
  return V_hat->allFinite() ? SolveOutcome::kOk : SolveOutcome::kResultNotFinite;
}

}  // namespace

bool pmi_try_solve(const PmiSystem& sys, Vec6* V_hat) {
  return solve_scaled(sys, V_hat) == SolveOutcome::kOk;
}

Vec6 pmi_solve(const PmiSystem& sys) {
  Vec6 V_hat;
  switch (solve_scaled(sys, &V_hat)) {
    case SolveOutcome::kOk:
      return V_hat;
    case SolveOutcome::kSystemNotFinite:
      throw std::runtime_error("pmi_solve: the PMI system (4.9) is not finite");
    case SolveOutcome::kSingular:
      throw std::runtime_error("pmi_solve: the PMI matrix A of (4.9) is singular");
    case SolveOutcome::kResultNotFinite:
      break;
  }
  throw std::runtime_error("pmi_solve: V_hat is not finite");
}

ProxyState pmi_advance(const ProxyState& s, const Vec6& V_hat, double T) {
  validate_tick_length(T);
  return pmi_advance_unchecked(s, V_hat, T);
}

ProxyState pmi_advance_unchecked(const ProxyState& s, const Vec6& V_hat, double T) {
  ProxyState n;
  n.V = 2.0 * V_hat - s.V;                        // (2.7): V_hat = (V_k + V_k+1)/2
  n.pose.x = s.pose.x + T * lin(V_hat);           // (2.7): v_hat = (x_k+1 - x_k)/T
  n.pose.R = s.pose.R * exp_so3(T * ang(V_hat));  // R_k+1 = R_k exp(S(w_hat T))
  n.V_hat_prev = V_hat;                           // seen by the device side (4.3)-(4.4)
  return n;
}

double proxy_kinetic_energy(const ProxyParams& p, const Vec6& V) { return 0.5 * V.dot(p.M() * V); }

}  // namespace dentsim
