// Penalty contact with PMI terms and damping (thesis §2.3, (2.15)-(2.19), (4.9)).
// See reference/contact.h for units, frames and the equations; derivations in
// docs/derivations/contact_and_friction.md.
#include "reference/contact.h"

#include <cmath>
#include <sstream>
#include <string>

#include "reference/anchored_spring.h"
#include "reference/core/io.h"
#include "reference/core/so3.h"

namespace dentsim {
namespace {

// A normal is accepted as unit if | |n| - 1 | <= this (collision normalises its normals).
constexpr double kUnitNormalTolerance = 1e-9;

[[noreturn]] void bad_member(const char* where, std::size_t i, const std::string& field,
                             const std::string& what) {
  std::ostringstream msg;
  msg << where << ": contacts[" << i << "]." << field << ": " << what;
  throw InputError(msg.str());
}

std::string num(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

}  // namespace

void validate_contacts(std::span<const Contact> contacts, const char* where) {
  for (std::size_t i = 0; i < contacts.size(); ++i) {
    const Contact& c = contacts[i];
    if (!c.x_o.allFinite()) bad_member(where, i, "x_o", "expected a finite point");
    if (!c.r.allFinite()) bad_member(where, i, "r", "expected a finite body-frame offset");
    if (!c.n.allFinite() || std::abs(c.n.norm() - 1.0) > kUnitNormalTolerance) {
      bad_member(where, i, "n", "expected a unit normal, got |n| = " + num(c.n.norm()));
    }
    if (!std::isfinite(c.stiffness) || c.stiffness < 0.0) {
      bad_member(where, i, "stiffness", "expected K_tooth >= 0 N/m, got " + num(c.stiffness));
    }
    if (!std::isfinite(c.damping) || c.damping < 0.0) {
      bad_member(where, i, "damping", "expected B_tooth >= 0 N s/m, got " + num(c.damping));
    }
    if (!std::isfinite(c.weight) || c.weight < 0.0) {
      bad_member(where, i, "weight", "expected a finite weight >= 0, got " + num(c.weight));
    }
  }
}

Vec3 contact_point(const Contact& c, const Pose& proxy) { return proxy.x + proxy.R * c.r; }

double penetration_depth(const Contact& c, const Pose& proxy) {
  return c.n.dot(c.x_o - contact_point(c, proxy));  // delta = n^T (x_o - x_c)  (§2.3)
}

Mat36 contact_point_jacobian(const Vec3& r, const Mat3& R) {
  // xdot_c = v + R S(w) r = v - R S(r) w.
  Mat36 J;
  J << Mat3::Identity(), -R * skew(r);
  return J;
}

Mat63 contact_wrench_map(const Vec3& r, const Mat3& R) {
  // J_c^T = [I; -S(r)^T R^T] = [I; S(r) R^T]  (2.15), torque frame as derived in the header.
  Mat63 Jt;
  Jt << Mat3::Identity(), skew(r) * R.transpose();
  return Jt;
}

std::vector<double> contact_weights(std::span<const Contact> contacts) {
  for (std::size_t i = 0; i < contacts.size(); ++i) {
    const double w = contacts[i].weight;
    if (!std::isfinite(w) || w < 0.0) {
      bad_member("contact_weights", i, "weight", "expected a finite weight >= 0, got " + num(w));
    }
  }
  const ContactWeights cw(contacts);
  std::vector<double> out(contacts.size());
  for (std::size_t i = 0; i < contacts.size(); ++i) out[i] = cw(contacts[i]);
  return out;
}

ContactWeights::ContactWeights(std::span<const Contact> contacts) : n_(contacts.size()) {
  for (const Contact& c : contacts) sum_ += c.weight;
}

bool contacts_well_formed(std::span<const Contact> contacts) {
  for (const Contact& c : contacts) {
    if (!c.x_o.allFinite() || !c.r.allFinite() || !c.n.allFinite() ||
        std::abs(c.n.norm() - 1.0) > kUnitNormalTolerance || !std::isfinite(c.stiffness) ||
        c.stiffness < 0.0 || !std::isfinite(c.damping) || c.damping < 0.0 ||
        !std::isfinite(c.weight) || c.weight < 0.0) {
      return false;
    }
  }
  return true;
}

AffineWrench contact_wrench(std::span<const Contact> contacts, const Pose& proxy, double T,
                            Scheme scheme) {
  if (!std::isfinite(T) || T <= 0.0) {
    throw InputError("contact_wrench: tick length T = " + num(T) + " s (expected finite > 0)");
  }
  validate_contacts(contacts, "contact_wrench");
  return contact_wrench_unchecked(contacts, proxy, T, scheme);
}

AffineWrench contact_wrench_unchecked(std::span<const Contact> contacts, const Pose& proxy,
                                      double T, Scheme scheme) {
  const ContactWeights w(contacts);
  AffineWrench F;
  for (const Contact& c : contacts) {
    const double delta = penetration_depth(c, proxy);
    if (!(delta > 0.0)) continue;  // unilateral: no spring or damper unless penetrating
    const Mat36 J = contact_point_jacobian(c.r, proxy.R);
    const Mat63 Jt = J.transpose();
    const Eigen::Matrix<double, 1, 6> d = -c.n.transpose() * J;  // d(delta)/dt = d V   (2.16)
    const double k = w(c) * c.stiffness;
    const double b = w(c) * c.damping;
    F.f0 += Jt * (k * delta * c.n);  // K delta_k n                                    (2.16)
    // PMI: K T/2 (delta_k+1 - delta_k)/T ~ K T/2 d V_hat ((2.16)-(2.18)); damping B d V (2.19).
    const double g = (scheme == Scheme::kMidpoint ? 0.5 * T * k : 0.0) + b;
    F.G += (Jt * c.n) * (g * d);
  }
  return F;
}

double anchored_spring_damping(const Vec3& center, double b_lin, double b_ang) {
  if (!(b_lin > 0.0)) return 0.0;
  const double o2 = center.squaredNorm();
  if (o2 == 0.0) return b_lin;
  if (!(b_ang > 0.0)) return 0.0;
  return 1.0 / (1.0 / b_lin + o2 / b_ang);
}

double anchored_spring_explicit_stiffness(const AnchoredSpring& spring, double T, Scheme scheme,
                                          double b_lin, double b_ang) {
  if (scheme != Scheme::kMidpoint || !(spring.held > 0.0)) return -1.0;
  return 2.0 * anchored_spring_damping(spring.center, b_lin, b_ang) / T;
}

void add_anchored_spring_unchecked(AffineWrench* F, std::span<const Contact> contacts,
                                   const Pose& proxy, double T, Scheme scheme,
                                   const AnchoredSpring& spring, double b_lin, double b_ang) {
  const double k_free = anchored_spring_explicit_stiffness(spring, T, scheme, b_lin, b_ang);
  if (k_free < 0.0) return;
  const ContactWeights w(contacts);
  const Mat36 Jo = contact_point_jacobian(spring.center, proxy.R);  // the centre's velocity
  for (const Contact& c : contacts) {
    if (!(penetration_depth(c, proxy) > 0.0)) continue;  // unilateral, as the part along n
    const double k_imp = spring.held * w(c) * c.stiffness - k_free;
    if (!(k_imp > 0.0)) continue;  // within the explicit bound
    const Mat3 P = Mat3::Identity() - c.n * c.n.transpose();
    F->G -= (0.5 * T * k_imp) * (Jo.transpose() * P * Jo);
  }
}

double contact_potential(std::span<const Contact> contacts, const Pose& proxy) {
  const std::vector<double> w = contact_weights(contacts);  // validates the weights
  double U = 0.0;
  for (std::size_t i = 0; i < contacts.size(); ++i) {
    const double delta = penetration_depth(contacts[i], proxy);
    if (delta > 0.0) U += w[i] * 0.5 * contacts[i].stiffness * delta * delta;
  }
  return U;
}

BlendedContact blended_contact(std::span<const Contact> contacts, const Pose& proxy) {
  const ContactWeights w(contacts);
  BlendedContact out;
  double a = 0.0;
  Vec3 n = Vec3::Zero(), r = Vec3::Zero();
  double depth = 0.0;
  for (std::size_t i = 0; i < contacts.size(); ++i) {
    const double delta = penetration_depth(contacts[i], proxy);
    if (!(delta > 0.0)) continue;
    const double wi = w(contacts[i]);
    a += wi;
    n += wi * contacts[i].n;
    r += wi * contacts[i].r;
    depth += wi * delta;
  }
  // Active members with zero weight exert no normal force, hence no friction either.
  if (a <= 0.0 || n.norm() <= 1e-12 * a) return out;
  out.active = true;
  out.n = n.normalized();
  out.r = r / a;
  out.depth = depth / a;
  return out;
}

}  // namespace dentsim
