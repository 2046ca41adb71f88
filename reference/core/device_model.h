// The device-model interface the observer and the tick use (thesis (2.1)-(2.2), (3.7)).
//
// Joint-space dynamics, generalised coordinates q (n = dof()):
//     M(q) qdd + C(q, qd) qd + g(q) + tau_f(q, qd) = tau + f_h
// with M symmetric positive definite, C any factorisation with dM/dt = C + C^T (Christoffel),
// g(q) the generalised gravity force, tau_f the joint friction (viscous B_d qd plus Coulomb),
// tau the motor torques and f_h the human's joint torques. Gravity and friction are what the
// device would need compensated; the thesis assumes them compensated (2.1) — the observer
// includes them explicitly so that an uncompensated device gives no bias.
#pragma once

#include "reference/core/types.h"

namespace dentsim {

// One device sample at the start of a tick, as the driver reports it (device/ and the pipeline
// share it).
struct DeviceSample {
  VecX q;          // joint angles [rad] as the encoders report them (quantised)
  VecX qd;         // joint velocities [rad/s] as the driver estimates them from q
  double t = 0.0;  // device clock [s]
};

class DeviceModel {
 public:
  virtual ~DeviceModel() = default;
  virtual int dof() const = 0;
  virtual MatX mass_matrix(const VecX& q) const = 0;                        // M(q)
  virtual MatX coriolis_matrix(const VecX& q, const VecX& qd) const = 0;     // C(q, qd)
  virtual VecX gravity(const VecX& q) const = 0;                             // g(q)
  virtual VecX friction_torque(const VecX& q, const VecX& qd) const = 0;     // tau_f(q, qd)
};

// Everything the servo tick needs from a 6-DoF device model at one sample (q, qd), evaluated in
// one pass (the tick's `device_terms` stage): the observer, the grip detector, the decomposition
// and the command all read these instead of calling the model again.
struct DeviceTerms {
  Pose pose;                     // x1, R1: forward kinematics
  Mat6 J_t = Mat6::Zero();       // tool Jacobian: V1 = J_t qd, V1 = [v1 (world); w1 (body)]
  Mat6 J_t_dot = Mat6::Zero();   // dJ_t/dt along qd (only filled when asked for)
  Mat6 M = Mat6::Zero();         // M(q)
  Vec6 CTqd = Vec6::Zero();      // C(q, qd)^T qd
  Vec6 g = Vec6::Zero();         // g(q)
  Vec6 tau_f = Vec6::Zero();     // tau_f(q, qd)
};

// A 6-DoF device with a tool-tip frame: forward kinematics (x1, R1) and the modified Jacobian
// J1 of (2.2), qd = J1 V1 with V1 = [v1 (world); w1 (body)].
class SixDofDeviceModel : public DeviceModel {
 public:
  int dof() const override { return 6; }
  virtual Pose forward_kinematics(const VecX& q) const = 0;
  virtual Mat6 twist_to_joint(const VecX& q) const = 0;  // J1(q)

  // All of DeviceTerms at (q, qd); J_t_dot only when with_jacobian_rate. The default evaluates
  // the functions above one by one (J_t = J1^-1, J_t_dot by a central difference of J_t along qd,
  // h = 1e-6 s) and allocates; models used inside a servo loop override it with one pass that
  // does not allocate (PhantomModel). Never throws for finite input of the right size.
  virtual void terms(const Vec6& q, const Vec6& qd, bool with_jacobian_rate,
                     DeviceTerms& out) const;

  // The joint friction's coefficients when tau_f is b qd + f_c s(qd) per joint with s a sign
  // (smoothed or not): viscous b [N m s/rad or N s/m] and Coulomb f_c [N m or N], true. false
  // (the default) when the model's friction is not of that form. The encoder Kalman filter's
  // stick-slip prediction reads them (reference/encoder_kalman.h).
  virtual bool joint_friction_coefficients(Vec6* /*b*/, Vec6* /*f_c*/) const { return false; }
};

}  // namespace dentsim
