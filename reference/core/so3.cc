#include "reference/core/so3.h"

#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <numbers>

namespace dentsim {

Mat3 skew(const Vec3& a) {
  Mat3 s;
  // clang-format off
  s <<    0.0, -a.z(),  a.y(),
        a.z(),    0.0, -a.x(),
       -a.y(),  a.x(),    0.0;
  // clang-format on
  return s;
}

Vec3 vee(const Mat3& m) {
  return 0.5 * Vec3(m(2, 1) - m(1, 2), m(0, 2) - m(2, 0), m(1, 0) - m(0, 1));
}

Mat3 exp_so3(const Vec3& w) {
  const double th2 = w.squaredNorm();
  const double th = std::sqrt(th2);
  double a;  // sin(th)/th
  double b;  // (1 - cos(th))/th^2
  if (th < 1e-4) {
    a = 1.0 - th2 / 6.0 + th2 * th2 / 120.0;
    b = 0.5 - th2 / 24.0 + th2 * th2 / 720.0;
  } else {
    a = std::sin(th) / th;
    b = (1.0 - std::cos(th)) / th2;
  }
  const Mat3 S = skew(w);
  return Mat3::Identity() + a * S + b * S * S;
}

double rotation_angle(const Mat3& R) {
  const double s = vee(R).norm();              // sin(phi) (vee takes half of R - R^T)
  const double c = 0.5 * (R.trace() - 1.0);     // cos(phi)
  return std::atan2(s, std::clamp(c, -1.0, 1.0));
}

double half_angle_over_sin(double phi) {
  // phi / (2 sin phi) = 1/2 + phi^2/12 + 7 phi^4/720 + ...
  if (phi < 1e-4) return 0.5 + phi * phi / 12.0;
  const double s = std::sin(phi);
  // Capped where sin(phi) underflows the ratio (phi within ~1e-9 of pi); callers that need the
  // spring vector near pi use so3_spring_vector, which switches to the logarithm there.
  return phi / (2.0 * std::max(s, 1e-12));
}

Vec3 log_so3(const Mat3& R) {
  const double phi = rotation_angle(R);
  if (phi < std::numbers::pi - 1e-3) {
    return half_angle_over_sin(phi) * 2.0 * vee(R);  // vee(R) = sin(phi) * axis
  }
  // Near pi: R + R^T = 2 cos(phi) I + 2 (1 - cos phi) a a^T; take the axis from the column of
  // the symmetric part with the largest diagonal, and its sign from the small antisymmetric part.
  const double c = std::cos(phi);
  const Mat3 B = (0.5 * (R + R.transpose()) - c * Mat3::Identity()) / (1.0 - c);  // = a a^T
  int i = 0;
  B.diagonal().maxCoeff(&i);
  Vec3 axis = B.col(i) / std::sqrt(std::max(B(i, i), 1e-300));
  axis.normalize();
  const Vec3 v = vee(R);  // sin(phi) * a, tiny but carries the sign when phi < pi
  if (v.dot(axis) < 0.0) axis = -axis;
  if (v.norm() < 1e-14) {
    // Exactly pi (to round-off): choose the sign with the largest component positive.
    int j = 0;
    axis.cwiseAbs().maxCoeff(&j);
    if (axis(j) < 0.0) axis = -axis;
  }
  return phi * axis;
}

Vec3 so3_spring_vector(const Mat3& R_rel) {
  const double phi = rotation_angle(R_rel);
  if (phi < std::numbers::pi - 1e-3) {
    return half_angle_over_sin(phi) * (2.0 * vee(R_rel));  // (2.12): w_bar = vee(R - R^T)
  }
  return log_so3(R_rel);
}

Mat3 orthonormalize(const Mat3& R) {
  Eigen::JacobiSVD<Mat3> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 U = svd.matrixU();
  const Mat3 V = svd.matrixV();
  if ((U * V.transpose()).determinant() < 0.0) U.col(2) *= -1.0;
  return U * V.transpose();
}

}  // namespace dentsim
