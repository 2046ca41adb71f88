#include "reference/rigid_body_device.h"

#include <Eigen/LU>
#include <cmath>

#include "reference/core/so3.h"

namespace dentsim {

Mat3 so3_right_jacobian(const Vec3& theta) {
  const double phi2 = theta.squaredNorm();
  const double phi = std::sqrt(phi2);
  double a;  // (1 - cos phi) / phi^2
  double b;  // (phi - sin phi) / phi^3
  if (phi < 1e-4) {
    a = 0.5 - phi2 / 24.0;
    b = 1.0 / 6.0 - phi2 / 120.0;
  } else {
    a = (1.0 - std::cos(phi)) / phi2;
    b = (phi - std::sin(phi)) / (phi2 * phi);
  }
  const Mat3 S = skew(theta);
  return Mat3::Identity() - a * S + b * S * S;
}

MatX RigidBodyDevice::mass_matrix(const VecX& q) const {
  const Mat3 Jr = so3_right_jacobian(q.tail<3>());
  MatX M = MatX::Zero(6, 6);
  M.topLeftCorner<3, 3>() = p_.mass * Mat3::Identity();
  M.bottomRightCorner<3, 3>() = Jr.transpose() * p_.inertia * Jr;
  return M;
}

MatX RigidBodyDevice::coriolis_matrix(const VecX& q, const VecX& qd) const {
  // C_ij = sum_k Gamma_ijk qd_k, Gamma_ijk = 1/2 (dM_ij/dq_k + dM_ik/dq_j - dM_jk/dq_i).
  constexpr double h = 1e-6;
  MatX dM[6];
  for (int k = 0; k < 6; ++k) {
    VecX qp = q, qm = q;
    qp(k) += h;
    qm(k) -= h;
    dM[k] = (mass_matrix(qp) - mass_matrix(qm)) / (2.0 * h);
  }
  MatX C = MatX::Zero(6, 6);
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j) {
      double c = 0.0;
      for (int k = 0; k < 6; ++k) {
        c += 0.5 * (dM[k](i, j) + dM[j](i, k) - dM[i](j, k)) * qd(k);
      }
      C(i, j) = c;
    }
  }
  return C;
}

VecX RigidBodyDevice::gravity(const VecX& /*q*/) const {
  VecX g = VecX::Zero(6);
  g(2) = p_.mass * p_.gravity;
  return g;
}

bool RigidBodyDevice::joint_friction_coefficients(Vec6* b, Vec6* f_c) const {
  for (int i = 0; i < 6; ++i) {
    const bool lin = i < 3;
    (*b)(i) = lin ? p_.damping_lin : p_.damping_ang;
    (*f_c)(i) = lin ? p_.coulomb_lin : p_.coulomb_ang;
  }
  return true;
}

VecX RigidBodyDevice::friction_torque(const VecX& /*q*/, const VecX& qd) const {
  VecX f(6);
  for (int i = 0; i < 6; ++i) {
    const bool lin = i < 3;
    const double b = lin ? p_.damping_lin : p_.damping_ang;
    const double c = lin ? p_.coulomb_lin : p_.coulomb_ang;
    f(i) = b * qd(i) + c * std::tanh(qd(i) / p_.coulomb_velocity);
  }
  return f;
}

Pose RigidBodyDevice::forward_kinematics(const VecX& q) const {
  return Pose{q.head<3>(), exp_so3(q.tail<3>())};
}

Mat6 RigidBodyDevice::twist_to_joint(const VecX& q) const {
  return block_diag(Mat3::Identity(), so3_right_jacobian(q.tail<3>()).inverse());
}

VecX RigidBodyDevice::joint_position(const Pose& pose) const {
  VecX q(6);
  q << pose.x, log_so3(pose.R);
  return q;
}

VecX RigidBodyDevice::joint_velocity(const VecX& q, const Vec6& V) const {
  return twist_to_joint(q) * V;
}

}  // namespace dentsim
