// A planar two-link arm in a vertical plane: the smallest DeviceModel (reference/core/
// device_model.h) with a configuration-dependent, coupled inertia, Coriolis terms, gravity and
// friction. Used by the momentum-observer tests and examples (thesis §3.2).
//
// Coordinates: q = [q1; q2] [rad], q1 the angle of link 1 from the horizontal x axis, q2 the angle
// of link 2 relative to link 1; gravity g0 [m/s^2] acts along -y. Link i: mass m_i [kg], length
// l_i [m], centre of mass at lc_i [m] from its joint, inertia I_i [kg m^2] about its centre of
// mass.
//
//     M(q)  = [[a + 2 b cos q2, d + b cos q2], [d + b cos q2, d]]
//             a = I1 + I2 + m1 lc1^2 + m2 (l1^2 + lc2^2),  b = m2 l1 lc2,  d = I2 + m2 lc2^2
//     C(q, qd) = h [[-qd2, -(qd1 + qd2)], [qd1, 0]],  h = b sin q2   (Christoffel: dM/dt = C + C^T)
//     g(q)  = dU/dq, U = g0 ((m1 lc1 + m2 l1) sin q1 + m2 lc2 sin(q1 + q2))
//     tau_f = B qd + F_c tanh(qd / v_c)   (viscous B = diag(b1, b2) [N m s/rad] plus smooth
//                                          Coulomb F_c = diag(c1, c2) [N m], v_c [rad/s])
// Equation of motion (device_model.h): M qdd + C qd + g + tau_f = tau + f.
#pragma once

#include "reference/core/device_model.h"

namespace dentsim {

struct TwoLinkParams {
  double m1 = 1.0, m2 = 0.6;      // [kg]
  double l1 = 0.3, l2 = 0.25;     // [m]
  double lc1 = 0.15, lc2 = 0.12;  // [m]
  double I1 = 8e-3, I2 = 3e-3;    // [kg m^2] about the centre of mass
  double b1 = 0.05, b2 = 0.03;    // viscous [N m s/rad]
  double c1 = 0.02, c2 = 0.01;    // Coulomb [N m]
  double v_coulomb = 0.05;        // tanh smoothing velocity [rad/s]
  double g0 = 9.81;               // [m/s^2]
};

class TwoLinkArm : public DeviceModel {
 public:
  explicit TwoLinkArm(TwoLinkParams p = {}) : p_(p) {}
  const TwoLinkParams& params() const { return p_; }

  int dof() const override { return 2; }
  MatX mass_matrix(const VecX& q) const override;
  MatX coriolis_matrix(const VecX& q, const VecX& qd) const override;
  VecX gravity(const VecX& q) const override;
  VecX friction_torque(const VecX& q, const VecX& qd) const override;

  double potential_energy(const VecX& q) const;                // U(q) [J]
  double kinetic_energy(const VecX& q, const VecX& qd) const;  // qd^T M qd / 2 [J]

 private:
  TwoLinkParams p_;
};

// qdd of M qdd + C qd + g + tau_f = tau_total, for any DeviceModel (tau_total = tau + f).
VecX joint_acceleration(const DeviceModel& model, const VecX& q, const VecX& qd,
                        const VecX& tau_total);

// One classical RK4 step of length h of the state (q, qd) under a torque held constant over the
// step (zero-order hold). Used as the "continuous" plant in tests.
void rk4_step(const DeviceModel& model, const VecX& tau_total, double h, VecX& q, VecX& qd);

}  // namespace dentsim
