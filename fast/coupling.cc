// Both coupling wrenches in one pass (what is shared and why it is bitwise: fast/coupling.h).
#include "fast/coupling.h"

#include <cmath>
#include <numbers>

#include "reference/core/so3.h"

namespace dentsim::fast {

void coupling_wrenches_unchecked(const CouplingGains& g, const Pose& device, const Vec6& V1,
                                 const ProxyState& proxy, double T, Scheme scheme,
                                 AffineWrench* T2_vc, Vec6* T1_vc) {
  const Mat3 R21 = proxy.pose.R.transpose() * device.R;  // R2^T R1
  const Mat3 R12 = device.R.transpose() * proxy.pose.R;  // R1^T R2
  // The spring vectors of R21 and R12 (so3_spring_vector, reference/core/so3.h) with one angle
  // when R12 = R21^T exactly and phi is off the logarithm's branch.
  Vec3 s21, s12;
  const double phi = rotation_angle(R21);
  if (phi < std::numbers::pi - 1e-3 && R12 == R21.transpose()) {
    const double h = half_angle_over_sin(phi);  // R12's too: the same |vee| and trace
    s21 = h * (2.0 * vee(R21));
    s12 = h * (2.0 * vee(R12));
  } else {
    s21 = so3_spring_vector(R21);
    s12 = so3_spring_vector(R12);
  }
  const Vec3 w1 = ang(V1);
  // Proxy side (4.5)/(4.6), as coupling_proxy_wrench_unchecked.
  AffineWrench& F = *T2_vc;
  lin(F.f0) = -g.k_lin * (proxy.pose.x - device.x) + g.b_lin * lin(V1);
  ang(F.f0) = g.k_ang * s21 + g.b_ang * (R21 * w1);
  const double half_T = scheme == Scheme::kMidpoint ? 0.5 * T : 0.0;
  F.G.setConstant(-0.0);  // -block_diag(...): its zeros negated
  const double g_lin = -((g.k_lin * half_T + g.b_lin) * 1.0);
  const double g_ang = -((g.k_ang * half_T + g.b_ang) * 1.0);
  for (int i = 0; i < 3; ++i) {
    F.G(i, i) = g_lin;
    F.G(i + 3, i + 3) = g_ang;
  }
  // Device side (4.3)-(4.4), as coupling_device_wrench_unchecked.
  const Vec6& V2 = scheme == Scheme::kMidpoint ? proxy.V_hat_prev : proxy.V;
  Vec6& D = *T1_vc;
  lin(D) = -g.k_lin * (device.x - proxy.pose.x) - g.b_lin * (lin(V1) - lin(V2));
  ang(D) = g.k_ang * s12 - g.b_ang * (w1 - R12 * ang(V2));
  if (scheme == Scheme::kMidpoint) ang(D) -= g.k_ang * 0.5 * T * w1;
}

}  // namespace dentsim::fast
