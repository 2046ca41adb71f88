// An ideal 6-DoF haptic device: a free rigid body (mass m, body inertia J) whose generalised
// coordinates are q = [x; theta], x the tool-tip position in {O} and theta the rotation vector of
// R1 = exp(S(theta)). It is the simplest SixDofDeviceModel with non-trivial (q-dependent) M(q) and
// C(q, qd), used by the tick's tests, the 1-DoF Z-width checks and the `demo` command before a
// real device model is chosen.
//
// Kinematics: w1 (body) = Jr(theta) theta_dot, Jr the right Jacobian of SO(3), so the modified
// Jacobian of (2.2) is J1 = diag(I, Jr^-1(theta)) (qd = J1 V1).
// Dynamics: M(q) = J1^-T diag(m I, J) J1^-1 = diag(m I, Jr^T J Jr); C(q, qd) from the Christoffel
// symbols of M (central differences, step 1e-6: this is a test model, accuracy ~1e-9 relative);
// g(q) = [0, 0, m g0, 0, 0, 0] (g0 = 0 by default: gravity compensated, thesis (2.1));
// tau_f = B_q qd + tanh(qd / v_eps) * coulomb (viscous per joint, smooth Coulomb per joint).
#pragma once

#include "reference/core/device_model.h"

namespace dentsim {

struct RigidBodyDeviceParams {
  double mass = 0.1;                        // m [kg]: apparent tip mass (Phantom: < 75 g)
  Mat3 inertia = Mat3::Identity() * 1e-4;   // J [kg m^2]
  double damping_lin = 0.0;                 // viscous damping of x joints [N s/m]
  double damping_ang = 0.0;                 // viscous damping of theta joints [N m s/rad]
  double coulomb_lin = 0.0;                 // Coulomb friction of x joints [N]
  double coulomb_ang = 0.0;                 // Coulomb friction of theta joints [N m]
  double coulomb_velocity = 1e-3;           // smoothing velocity of the Coulomb term
  double gravity = 0.0;                     // g0 [m/s^2] along -z of {O}
};

// Right Jacobian of SO(3): d/dt exp(S(theta)) = exp(S(theta)) S(Jr(theta) theta_dot).
Mat3 so3_right_jacobian(const Vec3& theta);

class RigidBodyDevice : public SixDofDeviceModel {
 public:
  explicit RigidBodyDevice(RigidBodyDeviceParams p = {}) : p_(p) {}
  const RigidBodyDeviceParams& params() const { return p_; }

  MatX mass_matrix(const VecX& q) const override;
  MatX coriolis_matrix(const VecX& q, const VecX& qd) const override;
  VecX gravity(const VecX& q) const override;
  VecX friction_torque(const VecX& q, const VecX& qd) const override;
  // damping_lin/ang and coulomb_lin/ang per joint (x joints, then theta joints); always true.
  bool joint_friction_coefficients(Vec6* b, Vec6* f_c) const override;
  Pose forward_kinematics(const VecX& q) const override;
  Mat6 twist_to_joint(const VecX& q) const override;

  // q of a pose (theta = log R) and qd of a twist: the inverse of forward kinematics.
  VecX joint_position(const Pose& pose) const;
  VecX joint_velocity(const VecX& q, const Vec6& V) const;

 private:
  RigidBodyDeviceParams p_;
};

}  // namespace dentsim
