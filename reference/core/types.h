// Shared value types of dentsim: used by reference/, fast/, device/, validation/ and calibration/.
//
// Conventions (docs/conventions.md):
// - SI units everywhere (m, kg, s, N, N·m); names say the unit where it is not SI.
// - A twist V = [v; w] (6x1): v is the linear velocity in the world frame {O}, w the angular
//   velocity in the body frame {B} (thesis §2.1.2). A wrench F = [f; tau] is dual to it: f in {O},
//   tau in {B}, so that V^T F is power.
// - Index 1 = device (master), 2 = proxy (slave).
#pragma once

#include <Eigen/Core>

namespace dentsim {

using Vec3 = Eigen::Vector3d;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat3 = Eigen::Matrix3d;
using Mat6 = Eigen::Matrix<double, 6, 6>;
using Mat63 = Eigen::Matrix<double, 6, 3>;
using Mat36 = Eigen::Matrix<double, 3, 6>;
using VecX = Eigen::VectorXd;
using MatX = Eigen::MatrixXd;

// A pose in SE(3): position x in {O}, orientation R of {B} w.r.t. {O}.
struct Pose {
  Vec3 x = Vec3::Zero();
  Mat3 R = Mat3::Identity();
};

// Linear and angular halves of a twist or wrench.
inline auto lin(Vec6& v) { return v.head<3>(); }
inline auto ang(Vec6& v) { return v.tail<3>(); }
inline auto lin(const Vec6& v) { return v.head<3>(); }
inline auto ang(const Vec6& v) { return v.tail<3>(); }

inline Vec6 stack(const Vec3& a, const Vec3& b) {
  Vec6 v;
  v << a, b;
  return v;
}

// Block-diagonal 6x6 from two 3x3 blocks.
inline Mat6 block_diag(const Mat3& a, const Mat3& b) {
  Mat6 m = Mat6::Zero();
  m.topLeftCorner<3, 3>() = a;
  m.bottomRightCorner<3, 3>() = b;
  return m;
}

}  // namespace dentsim
