// SO(3) helpers (thesis §2.1.2, §2.2): skew/vee, the exponential and logarithm maps, and the
// rotation angle phi with the factor phi / (2 sin phi) used by the SO(3) spring (2.11)-(2.13).
//
// - skew(a) = S(a) is the matrix with S(a) b = a x b; vee(S(a)) = a.
// - exp_so3(w) = exp(S(w)) (Rodrigues); log_so3(R) = w with exp_so3(w) = R, |w| in [0, pi].
// - Small angles use Taylor series (no 0/0); angles near pi recover the axis from the symmetric
//   part of R (the antisymmetric part vanishes there), so neither branch returns NaN.
#pragma once

#include "reference/core/types.h"

namespace dentsim {

// S(a): the skew-symmetric matrix of a, S(a) b = a x b.
Mat3 skew(const Vec3& a);
// vee(S): the vector of the skew-symmetric part, vee(S(a)) = a. For a general M it returns
// vee((M - M^T)/2).
Vec3 vee(const Mat3& m);

// exp(S(w)): rotation by |w| about w/|w| (Rodrigues' formula; Taylor series below 1e-4 rad).
Mat3 exp_so3(const Vec3& w);
// The rotation vector w of R: exp_so3(w) = R, with |w| in [0, pi]. At exactly pi the sign of
// the axis is ambiguous (both are correct); the one returned has its largest component positive.
Vec3 log_so3(const Mat3& R);

// phi = acos((tr(R) - 1) / 2), the rotation angle of R in [0, pi] (2.11), computed with atan2 of
// |vee(R - R^T)|/2 and (tr R - 1)/2 so that it stays accurate near 0 and near pi.
double rotation_angle(const Mat3& R);

// phi / (2 sin phi), the factor in (2.13): -> 1/2 as phi -> 0 (series); finite up to and
// including phi = pi where it is capped (see so3.cc) since w_bar vanishes there.
double half_angle_over_sin(double phi);

// The SO(3) spring direction of (2.11)-(2.13): phi/(2 sin phi) * w_bar with
// S(w_bar) = R_rel - R_rel^T. It equals log_so3(R_rel) for phi < pi; near pi, where w_bar -> 0
// and the ratio blows up, it returns log_so3(R_rel) directly so the torque stays finite and
// correct (magnitude k phi, direction of the axis).
Vec3 so3_spring_vector(const Mat3& R_rel);

// Re-orthonormalise a rotation (nearest rotation via SVD). Used only where a test shows drift.
Mat3 orthonormalize(const Mat3& R);

}  // namespace dentsim
