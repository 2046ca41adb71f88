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

void grasp_mass_terms(const Vec6& Mt, const DeviceTerms& base, const Vec6& V1, Mat6* M_hand,
                      Vec6* CTqd_hand) {
  // M_h = J_t^T Mt J_t; C_h = J_t^T Mt dJ_t/dt, so C_h^T qd = dJ_t/dt^T Mt (J_t qd) = dJ_t/dt^T Mt
  // V1.
  M_hand->noalias() = base.J_t.transpose() * Mt.asDiagonal() * base.J_t;
  CTqd_hand->noalias() = base.J_t_dot.transpose() * Mt.cwiseProduct(V1);
}

MatX GraspMassModel::mass_matrix(const VecX& q) const {
  DeviceTerms t;
  base_.terms(q, Vec6::Zero(), false, t);
  return base_.mass_matrix(q) + t.J_t.transpose() * Mt_ * t.J_t;
}

MatX GraspMassModel::coriolis_matrix(const VecX& q, const VecX& qd) const {
  DeviceTerms t;
  base_.terms(q, qd, true, t);
  return base_.coriolis_matrix(q, qd) + t.J_t.transpose() * Mt_ * t.J_t_dot;
}

void GraspMassModel::terms(const Vec6& q, const Vec6& qd, bool with_jacobian_rate,
                           DeviceTerms& out) const {
  (void)with_jacobian_rate;  // the hand's Coriolis term needs dJ_t/dt
  base_.terms(q, qd, true, out);
  Mat6 M_hand;
  Vec6 CTqd_hand;
  const Vec6 V1 = out.J_t * qd;
  grasp_mass_terms(Mt_.diagonal(), out, V1, &M_hand, &CTqd_hand);
  out.M += M_hand;
  out.CTqd += CTqd_hand;
}

}  // namespace dentsim
