// Explicit double instantiation of the Phantom model and the DeviceModel adapter.
#include "reference/phantom/phantom_model.h"

#include <stdexcept>
#include <string>

namespace dentsim {

template class PhantomModelT<double>;
template PhantomTreeT<double> phantom_tree<double>(const PhantomParams&);

const char* phantom_tree_body_name(int body) {
  static const char* const kNames[kPhantomTreeDof] = {"base",         "upper_arm",     "forearm",
                                                      "crank",        "parallel_link", "gimbal_yaw",
                                                      "gimbal_pitch", "gimbal_roll"};
  if (body < 0 || body >= kPhantomTreeDof) throw std::out_of_range("phantom tree body index");
  return kNames[body];
}

int phantom_actuated_tree_joint(int device_joint) {
  static const int kMap[6] = {kBase, kUpperArm, kCrank, kGimbalYaw, kGimbalPitch, kGimbalRoll};
  if (device_joint < 0 || device_joint >= 6) throw std::out_of_range("phantom device joint");
  return kMap[device_joint];
}

Eigen::Matrix<double, kPhantomTreeDof, 6> phantom_tree_map() {
  Eigen::Matrix<double, kPhantomTreeDof, 6> G = Eigen::Matrix<double, kPhantomTreeDof, 6>::Zero();
  G(kBase, 0) = 1.0;      // theta_0 = q1
  G(kUpperArm, 1) = 1.0;  // theta_1 = q2
  G(kForearm, 1) = -1.0;
  G(kForearm, 2) = 1.0;  // theta_2 = q3 - q2 (elbow)
  G(kCrank, 2) = 1.0;    // theta_3 = q3
  G(kParallelLink, 1) = 1.0;
  G(kParallelLink, 2) = -1.0;  // theta_4 = q2 - q3
  G(kGimbalYaw, 3) = 1.0;
  G(kGimbalPitch, 4) = 1.0;
  G(kGimbalRoll, 5) = 1.0;
  return G;
}

Vec6 phantom_vec6(const VecX& v, const char* what) {
  if (v.size() != 6) {
    throw std::invalid_argument(std::string("PhantomModel: ") + what +
                                " must have 6 entries, got " + std::to_string(v.size()));
  }
  return v;
}

PhantomModel::PhantomModel(PhantomParams params) : params_(std::move(params)), model_(params_) {}

MatX PhantomModel::mass_matrix(const VecX& q) const { return model_.M(phantom_vec6(q, "q")); }

MatX PhantomModel::coriolis_matrix(const VecX& q, const VecX& qd) const {
  return model_.C(phantom_vec6(q, "q"), phantom_vec6(qd, "qd"));
}

VecX PhantomModel::gravity(const VecX& q) const { return model_.g(phantom_vec6(q, "q")); }

bool PhantomModel::joint_friction_coefficients(Vec6* b, Vec6* f_c) const {
  *b = model_.tree().damping;
  *f_c = model_.tree().coulomb;
  return true;
}

VecX PhantomModel::friction_torque(const VecX& /*q*/, const VecX& qd) const {
  return model_.friction(phantom_vec6(qd, "qd"));
}

Pose PhantomModel::forward_kinematics(const VecX& q) const {
  Pose pose;
  model_.fk(phantom_vec6(q, "q"), &pose.x, &pose.R);
  return pose;
}

Mat6 PhantomModel::twist_to_joint(const VecX& q) const { return model_.J1(phantom_vec6(q, "q")); }

void PhantomModel::terms(const Vec6& q, const Vec6& qd, bool with_jacobian_rate,
                         DeviceTerms& out) const {
  const PhantomModelD::Kinematics k = model_.kinematics(q, qd);
  Mat6 C;
  model_.joint_terms(k, &out.M, &C, &out.g);
  out.CTqd.noalias() = C.transpose() * qd;
  out.tau_f = model_.friction(qd);
  model_.tool_pose(k, &out.pose.x, &out.pose.R);
  out.J_t = model_.tool_jacobian(k);
  if (with_jacobian_rate) {
    out.J_t_dot = model_.tool_jacobian_rate(k);
  } else {
    out.J_t_dot.setZero();
  }
}

}  // namespace dentsim
