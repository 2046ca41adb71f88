// The default one-pass device terms: the SixDofDeviceModel functions evaluated one by one.
#include "reference/core/device_model.h"

#include <Eigen/LU>

namespace dentsim {

void SixDofDeviceModel::terms(const Vec6& q, const Vec6& qd, bool with_jacobian_rate,
                              DeviceTerms& out) const {
  const VecX qx = q, qdx = qd;
  out.pose = forward_kinematics(qx);
  out.J_t = twist_to_joint(qx).partialPivLu().inverse();  // V1 = J_t qd, J_t = J1^-1 (2.2)
  out.M = mass_matrix(qx);
  out.CTqd = coriolis_matrix(qx, qdx).transpose() * qdx;
  out.g = gravity(qx);
  out.tau_f = friction_torque(qx, qdx);
  if (with_jacobian_rate) {
    // dJ_t/dt = dJ_t/dq [qd]: central difference along qd over h seconds.
    const double h = 1e-6;
    const VecX qp = q + h * qd, qm = q - h * qd;
    const Mat6 Jp = twist_to_joint(qp).partialPivLu().inverse();
    const Mat6 Jm = twist_to_joint(qm).partialPivLu().inverse();
    out.J_t_dot = (Jp - Jm) / (2.0 * h);
  } else {
    out.J_t_dot.setZero();
  }
}

}  // namespace dentsim
