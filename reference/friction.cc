// Constraint-based Coulomb friction (thesis §2.4, (2.20)-(2.22), (4.10)). See reference/friction.h.
#include "reference/friction.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <string>

#include "reference/contact.h"
#include "reference/core/io.h"

namespace dentsim {

void tangent_basis(const Vec3& n, Vec3& t1, Vec3& t2) {
  // Cross n with the world axis least aligned with it: well conditioned for every n.
  Eigen::Index axis = 0;
  n.cwiseAbs().minCoeff(&axis);
  t1 = n.cross(Vec3::Unit(axis)).normalized();
  t2 = n.cross(t1);
}

FrictionSolution solve_with_friction(const PmiSystem& sys, std::span<const Contact> contacts,
                                     const Pose& proxy, const AffineWrench& normal,
                                     const FrictionParams& fp) {
  if (!std::isfinite(fp.mu) || fp.mu < 0.0) {
    throw InputError("solve_with_friction: friction.mu = " + std::to_string(fp.mu) +
                     " (expected a finite coefficient >= 0)");
  }
  FrictionSolution out;
  if (!solve_with_friction_unchecked(sys, contacts, proxy, normal, fp, &out)) {
    throw InputError(
        "solve_with_friction: the proxy system matrix A is singular or the system is not "
        "finite (expected the inertia term M 2/T to make A invertible)");
  }
  return out;
}

bool solve_with_friction_unchecked(const PmiSystem& sys, std::span<const Contact> contacts,
                                   const Pose& proxy, const AffineWrench& normal,
                                   const FrictionParams& fp, FrictionSolution* result) {
  // A system that is not finite fails here, as in pmi_try_solve (Eigen's rank test is not
  // specified for NaN entries, and a NaN in b would only surface as a NaN V).
  if (!sys.A.allFinite() || !sys.b.allFinite()) return false;
  const Eigen::FullPivLU<Mat6> lu(sys.A);
  if (!lu.isInvertible()) return false;
  FrictionSolution& out = *result;
  const Vec6 V0 = lu.solve(sys.b);  // the frictionless solution
  out.V = V0;
  out.f_t.setZero();
  out.f_n = 0.0;
  out.sliding = false;
  out.F.setZero();
  out.active = false;
  if (!fp.enabled || fp.mu == 0.0) return true;
  const BlendedContact bc = blended_contact(contacts, proxy);
  if (!bc.active) return true;
  out.active = true;

  const Vec3& n = bc.n;
  // Normal force at a solution: f_n(V) = max(0, n^T f(V)), f the force part of `normal`.
  const auto normal_force = [&](const Vec6& V) { return n.dot(normal.at(V).head<3>()); };

  Vec3 t1, t2;
  tangent_basis(n, t1, t2);
  Eigen::Matrix<double, 3, 2> Tt;
  Tt << t1, t2;
  const Mat63 Jt = contact_wrench_map(bc.r, proxy.R);  // J^T = [I; S(r) R^T]     (4.10)
  const Eigen::Matrix<double, 6, 2> H = Jt * Tt;       // wrench of lambda        (2.21)

  // 1. Stick: H^T V = 0 with V = V0 + A^-1 H lambda  (2.22).
  const Eigen::Matrix<double, 6, 2> AinvH = lu.solve(H);
  const Eigen::Matrix2d W = H.transpose() * AinvH;
  const Eigen::Vector2d lambda = W.fullPivLu().solve(-H.transpose() * V0);
  const Vec3 f_stick = Tt * lambda;
  const Vec6 V_stick = V0 + AinvH * lambda;
  const double fn_stick = std::max(0.0, normal_force(V_stick));
  const double s_stick = f_stick.norm();
  if (s_stick <= fp.mu * fn_stick) {
    out.V = V_stick;
    out.f_t = f_stick;
    out.f_n = fn_stick;
    out.F = Jt * f_stick;
    return true;
  }

  // 2-3. Slide: f_t = s d, cone with equality at the final solution V(s) = V0 + s A^-1 J^T d.
  out.sliding = true;
  const Vec3 d = f_stick / s_stick;
  const Vec6 Vd = lu.solve(Jt * d);
  const double alpha = normal_force(V0);
  const double beta = n.dot((normal.G * Vd).head<3>());
  double s = 0.0;
  if (alpha > 0.0) {
    // g(s) = s - mu (alpha + beta s) is < 0 at s = 0 and > 0 at s_stick, so its slope
    // 1 - mu beta is positive and the root lies in (0, s_stick); clamp against round-off (a
    // non-positive slope can only come from round-off at the boundary: then release, s = 0).
    const double slope = 1.0 - fp.mu * beta;
    s = slope > 0.0 ? std::clamp(fp.mu * alpha / slope, 0.0, s_stick) : 0.0;
  }
  out.V = V0 + s * Vd;
  out.f_t = s * d;
  out.f_n = std::max(0.0, normal_force(out.V));
  out.F = Jt * out.f_t;
  return true;
}

}  // namespace dentsim
