#include "reference/grasp_mass_model.h"

#include <Eigen/LU>
#include <cmath>
#include <stdexcept>
#include <string>

namespace dentsim {

GraspMassModel::GraspMassModel(const SixDofDeviceModel& base, double mass_kg,
                               double inertia_kg_m2)
    : base_(base), m_(mass_kg), J_(inertia_kg_m2) {
  if (!(std::isfinite(m_) && m_ >= 0.0) || !(std::isfinite(J_) && J_ >= 0.0)) {
    throw std::invalid_argument("GraspMassModel: mass and inertia must be finite and >= 0, got " +
                                std::to_string(m_) + " kg, " + std::to_string(J_) + " kg m^2");
  }
  Mt_ = block_diag(m_ * Mat3::Identity(), J_ * Mat3::Identity());
}

Mat6 GraspMassModel::joint_to_twist(const VecX& q) const {
  return base_.twist_to_joint(q).partialPivLu().inverse();
}

MatX GraspMassModel::mass_matrix(const VecX& q) const {
  const Mat6 Jinv = joint_to_twist(q);  // V = J1^-1 qd
  return base_.mass_matrix(q) + Jinv.transpose() * Mt_ * Jinv;
}

MatX GraspMassModel::coriolis_matrix(const VecX& q, const VecX& qd) const {
  const double h = 1e-6;
  const VecX dq = h * qd;
  const Mat6 dJinv = (joint_to_twist(q + dq) - joint_to_twist(q - dq)) / (2.0 * h);  // d/dt
  return base_.coriolis_matrix(q, qd) + joint_to_twist(q).transpose() * Mt_ * dJinv;
}

}  // namespace dentsim
