// Coulomb friction with one factorisation of A (fast/friction.h).
#include "fast/friction.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "fast/pmi.h"
#include "reference/contact.h"
#include "reference/tick_detail.h"

namespace dentsim::fast {

bool solve_with_friction_unchecked(const PmiSystem& sys, std::span<const Contact> contacts,
                                   const Pose& proxy, const AffineWrench& normal,
                                   const FrictionParams& fp, FrictionSolution* result) {
  if (!reference::detail::all_finite(sys.b)) return false;
  PmiFactor lu;
  if (!pmi_factor(sys.A, &lu)) return false;
  FrictionSolution& out = *result;
  out = FrictionSolution{};             // no friction force, not active, not sliding
  pmi_factor_solve(lu, sys.b, &out.V);  // the frictionless solution V0
  if (!fp.enabled || fp.mu == 0.0) return true;
  const BlendedContact bc = blended_contact(contacts, proxy);
  if (!bc.active) return true;
  out.active = true;
  const Vec6 V0 = out.V;

  const Vec3& n = bc.n;
  // Normal force at a solution: n^T f(V) = fn0 + g^T V, f the force part of `normal`.
  const double fn0 = n.dot(normal.f0.head<3>());
  const Vec6 g = normal.G.topRows<3>().transpose() * n;

  Vec3 t1, t2;
  tangent_basis(n, t1, t2);
  const Mat3 Rt = proxy.R.transpose();
  Vec6 h1, h2;  // the columns of H = J^T [t1 t2]: [t; r x (R^T t)]   (4.10), (2.21)
  h1 << t1, bc.r.cross(Rt * t1);
  h2 << t2, bc.r.cross(Rt * t2);
  Vec6 a1, a2;  // A^-1 H
  pmi_factor_solve(lu, h1, &a1);
  pmi_factor_solve(lu, h2, &a2);

  // 1. Stick: H^T V = 0 with V = V0 + A^-1 H lambda, W lambda = -H^T V0  (2.22).
  const double w11 = h1.dot(a1), w12 = h1.dot(a2), w21 = h2.dot(a1), w22 = h2.dot(a2);
  const double c1 = -h1.dot(V0), c2 = -h2.dot(V0);
  const double inv_det = 1.0 / (w11 * w22 - w12 * w21);
  const double l1 = (w22 * c1 - w12 * c2) * inv_det;
  const double l2 = (w11 * c2 - w21 * c1) * inv_det;
  const Vec6 V_stick = V0 + l1 * a1 + l2 * a2;
  const double fn_stick = std::max(0.0, fn0 + g.dot(V_stick));
  const double s_stick = std::sqrt(l1 * l1 + l2 * l2);  // |f_stick|
  if (s_stick <= fp.mu * fn_stick) {
    out.V = V_stick;
    out.f_t = l1 * t1 + l2 * t2;
    out.f_n = fn_stick;
    out.F = l1 * h1 + l2 * h2;
    return true;
  }

  // 2-3. Slide: f_t = s d, cone with equality at the final solution V(s) = V0 + s V_d.
  out.sliding = true;
  const double e1 = l1 / s_stick, e2 = l2 / s_stick;  // d = e1 t1 + e2 t2
  const Vec6 Vd = e1 * a1 + e2 * a2;                  // A^-1 J^T d
  const double alpha = fn0 + g.dot(V0);
  const double beta = g.dot(Vd);
  double s = 0.0;
  if (alpha > 0.0) {
    // As the reference: the slope is positive but for round-off at the boundary (then release).
    const double slope = 1.0 - fp.mu * beta;
    s = slope > 0.0 ? std::clamp(fp.mu * alpha / slope, 0.0, s_stick) : 0.0;
  }
  const double m1 = s * e1, m2 = s * e2;
  out.V = V0 + s * Vd;
  out.f_t = m1 * t1 + m2 * t2;
  out.f_n = std::max(0.0, fn0 + g.dot(out.V));
  out.F = m1 * h1 + m2 * h2;
  return true;
}

}  // namespace dentsim::fast
