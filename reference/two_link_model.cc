#include "reference/two_link_model.h"

#include <Eigen/Cholesky>
#include <cmath>
#include <stdexcept>
#include <string>

namespace dentsim {
namespace {

void require_size(const VecX& v, int n, const char* what) {
  if (v.size() != n) {
    throw std::invalid_argument(std::string(what) + ": expected " + std::to_string(n) +
                                " entries, got " + std::to_string(v.size()));
  }
}

}  // namespace

MatX TwoLinkArm::mass_matrix(const VecX& q) const {
  require_size(q, 2, "TwoLinkArm::mass_matrix q");
  const double a =
      p_.I1 + p_.I2 + p_.m1 * p_.lc1 * p_.lc1 + p_.m2 * (p_.l1 * p_.l1 + p_.lc2 * p_.lc2);
  const double b = p_.m2 * p_.l1 * p_.lc2;
  const double d = p_.I2 + p_.m2 * p_.lc2 * p_.lc2;
  const double c2 = std::cos(q(1));
  MatX M(2, 2);
  // clang-format off
  M << a + 2.0 * b * c2, d + b * c2,
       d + b * c2, d;
  // clang-format on
  return M;
}

MatX TwoLinkArm::coriolis_matrix(const VecX& q, const VecX& qd) const {
  require_size(q, 2, "TwoLinkArm::coriolis_matrix q");
  require_size(qd, 2, "TwoLinkArm::coriolis_matrix qd");
  const double h = p_.m2 * p_.l1 * p_.lc2 * std::sin(q(1));
  MatX C(2, 2);
  // clang-format off
  C << -h * qd(1), -h * (qd(0) + qd(1)),
       h * qd(0), 0.0;
  // clang-format on
  return C;
}

VecX TwoLinkArm::gravity(const VecX& q) const {
  require_size(q, 2, "TwoLinkArm::gravity q");
  const double c12 = std::cos(q(0) + q(1));
  VecX g(2);
  g(0) = p_.g0 * ((p_.m1 * p_.lc1 + p_.m2 * p_.l1) * std::cos(q(0)) + p_.m2 * p_.lc2 * c12);
  g(1) = p_.g0 * p_.m2 * p_.lc2 * c12;
  return g;
}

VecX TwoLinkArm::friction_torque(const VecX& q, const VecX& qd) const {
  require_size(q, 2, "TwoLinkArm::friction_torque q");
  require_size(qd, 2, "TwoLinkArm::friction_torque qd");
  VecX f(2);
  f(0) = p_.b1 * qd(0) + p_.c1 * std::tanh(qd(0) / p_.v_coulomb);
  f(1) = p_.b2 * qd(1) + p_.c2 * std::tanh(qd(1) / p_.v_coulomb);
  return f;
}

double TwoLinkArm::potential_energy(const VecX& q) const {
  require_size(q, 2, "TwoLinkArm::potential_energy q");
  return p_.g0 * ((p_.m1 * p_.lc1 + p_.m2 * p_.l1) * std::sin(q(0)) +
                  p_.m2 * p_.lc2 * std::sin(q(0) + q(1)));
}

double TwoLinkArm::kinetic_energy(const VecX& q, const VecX& qd) const {
  return 0.5 * qd.dot(mass_matrix(q) * qd);
}

VecX joint_acceleration(const DeviceModel& model, const VecX& q, const VecX& qd,
                        const VecX& tau_total) {
  const VecX rhs = tau_total - model.coriolis_matrix(q, qd) * qd - model.gravity(q) -
                   model.friction_torque(q, qd);
  return model.mass_matrix(q).llt().solve(rhs);
}

void rk4_step(const DeviceModel& model, const VecX& tau_total, double h, VecX& q, VecX& qd) {
  const VecX k1q = qd;
  const VecX k1v = joint_acceleration(model, q, qd, tau_total);
  const VecX k2q = qd + 0.5 * h * k1v;
  const VecX k2v = joint_acceleration(model, q + 0.5 * h * k1q, k2q, tau_total);
  const VecX k3q = qd + 0.5 * h * k2v;
  const VecX k3v = joint_acceleration(model, q + 0.5 * h * k2q, k3q, tau_total);
  const VecX k4q = qd + h * k3v;
  const VecX k4v = joint_acceleration(model, q + h * k3q, k4q, tau_total);
  q += h / 6.0 * (k1q + 2.0 * k2q + 2.0 * k3q + k4q);
  qd += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
}

}  // namespace dentsim
