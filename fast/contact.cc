#include "fast/contact.h"

#include <Eigen/Geometry>

#include "reference/anchored_spring.h"
#include "reference/contact.h"

namespace dentsim::fast {

AffineWrench contact_wrench_unchecked(std::span<const Contact> contacts, const Pose& proxy,
                                      double T, Scheme scheme) {
  const ContactWeights w(contacts);
  const double half_T = scheme == Scheme::kMidpoint ? 0.5 * T : 0.0;
  const Mat3 Rt = proxy.R.transpose();
  Vec6 f0 = Vec6::Zero();
  Mat6 G = Mat6::Zero();  // -sum g a a^T, upper triangle accumulated
  for (const Contact& c : contacts) {
    // delta = n^T (x_o - x_c), x_c = x + R r                                              (§2.3)
    const Vec3 x_c = proxy.x + proxy.R * c.r;
    const double delta = c.n.dot(c.x_o - x_c);
    if (!(delta > 0.0)) continue;  // unilateral
    const double wi = w(c);
    const double k = wi * c.stiffness;
    const double g = half_T * k + wi * c.damping;
    Vec6 a;
    a.head<3>() = c.n;
    a.tail<3>() = c.r.cross(Rt * c.n);  // S(r) R^T n
    f0 += (k * delta) * a;              // K delta_k n                                  (2.16)
    for (int j = 0; j < 6; ++j) {
      const double ga = g * a(j);
      for (int i = 0; i <= j; ++i) G(i, j) -= ga * a(i);  // (2.16)-(2.19)
    }
  }
  for (int j = 0; j < 6; ++j) {
    for (int i = j + 1; i < 6; ++i) G(i, j) = G(j, i);
  }
  AffineWrench F;
  F.f0 = f0;
  F.G = G;
  return F;
}

void add_anchored_spring_unchecked(AffineWrench* F, std::span<const Contact> contacts,
                                   const Pose& proxy, double T, Scheme scheme,
                                   const AnchoredSpring& spring, double b_lin, double b_ang) {
  const double k_free = anchored_spring_explicit_stiffness(spring, T, scheme, b_lin, b_ang);
  if (k_free < 0.0) return;
  const Mat3 Rt = proxy.R.transpose();
  const ContactWeights w(contacts);
  for (const Contact& c : contacts) {
    const Vec3 x_c = proxy.x + proxy.R * c.r;
    if (!(c.n.dot(c.x_o - x_c) > 0.0)) continue;  // unilateral, as the part along n
    const double k_imp = spring.held * w(c) * c.stiffness - k_free;
    if (!(k_imp > 0.0)) continue;  // within the explicit bound
    const double g = 0.5 * T * k_imp;
    const Vec3 t1 = c.n.unitOrthogonal();
    const Vec3 t2 = c.n.cross(t1);
    for (const Vec3& t : {t1, t2}) {
      Vec6 b;
      b.head<3>() = t;
      b.tail<3>() = spring.center.cross(Rt * t);  // S(o) R^T t
      for (int j = 0; j < 6; ++j) {  // -g b b^T, symmetric exactly (as G above)
        const double gb = g * b(j);
        for (int i = 0; i < j; ++i) {
          const double v = gb * b(i);
          F->G(i, j) -= v;
          F->G(j, i) -= v;
        }
        F->G(j, j) -= gb * b(j);
      }
    }
  }
}

}  // namespace dentsim::fast
