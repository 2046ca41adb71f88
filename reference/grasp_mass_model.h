// A device model with the grasping hand's nominal mass riding on the tool tip (the hand's inertia
// moves rigidly with the handle while it grips; device/scripted_hand.h merges it into the plant the
// same way). Docs: docs/derivations/decomposition_and_observer.md §8.
//
// Why: the momentum observer (reference/observer.h) attributes everything its model lacks to the
// human force. A hand of mass m_h on the tool therefore appears in f_hat as -m_h a, seen through
// the estimate's lag, and the decomposition's feed-forward (4.7) re-applies it scaled by
// (1 - M1 M_d^-1): a negative damping of up to (1 - M1/M_d) m_h L that grows with the observer
// gain L. Putting a nominal m_h into the model removes that term (to the error of the nominal).
//
// Model: a point mass m at the tip and an isotropic rotational inertia J about it, i.e. in the
// maximal coordinates V = [v (world); w (body)] of (2.2) the constant inertia Mt = diag(m I, J I),
// with no gyroscopic term (isotropic J). With qd = J1 V (J1 = twist_to_joint):
//     M'(q)     = M(q) + J1^-T Mt J1^-1
//     C'(q, qd) = C(q, qd) + J1^-T Mt dJ1^-1/dt,   dJ1^-1/dt along qd (central difference, h = 1e-6)
// which keeps dM'/dt = C' + C'^T. Gravity and friction are the base model's: the hand carries its
// own weight.
#pragma once

#include "reference/core/device_model.h"

namespace dentsim {

// The hand's part of the model at one sample, from the base model's terms (J_t, dJ_t/dt) and
// V1 = J_t qd: M_h = J_t^T Mt J_t and C_h^T qd = dJ_t/dt^T Mt V1, Mt = diag(Mt) (the tick's
// device_terms stage and GraspMassModel::terms share it). Never allocates.
void grasp_mass_terms(const Vec6& Mt, const DeviceTerms& base, const Vec6& V1, Mat6* M_hand,
                      Vec6* CTqd_hand);

class GraspMassModel : public SixDofDeviceModel {
 public:
  // `base` must outlive this model. Throws std::invalid_argument for a negative or non-finite
  // mass [kg] or inertia [kg m^2].
  GraspMassModel(const SixDofDeviceModel& base, double mass_kg, double inertia_kg_m2);

  MatX mass_matrix(const VecX& q) const override;
  MatX coriolis_matrix(const VecX& q, const VecX& qd) const override;
  VecX gravity(const VecX& q) const override { return base_.gravity(q); }
  VecX friction_torque(const VecX& q, const VecX& qd) const override {
    return base_.friction_torque(q, qd);
  }
  bool joint_friction_coefficients(Vec6* b, Vec6* f_c) const override {
    return base_.joint_friction_coefficients(b, f_c);
  }
  Pose forward_kinematics(const VecX& q) const override { return base_.forward_kinematics(q); }
  Mat6 twist_to_joint(const VecX& q) const override { return base_.twist_to_joint(q); }
  // The base model's terms plus the hand's (grasp_mass_terms); J_t_dot always filled.
  void terms(const Vec6& q, const Vec6& qd, bool with_jacobian_rate,
             DeviceTerms& out) const override;

  double mass() const { return m_; }
  double inertia() const { return J_; }
  const SixDofDeviceModel& base() const { return base_; }
  const Mat6& hand_inertia() const { return Mt_; }  // Mt = diag(m I, J I)

 private:
  const SixDofDeviceModel& base_;
  double m_, J_;
  Mat6 Mt_;
};

}  // namespace dentsim
