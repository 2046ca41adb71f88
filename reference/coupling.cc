#include "reference/coupling.h"

#include <cmath>
#include <string>

#include "reference/core/io.h"
#include "reference/core/so3.h"
#include "reference/pmi.h"

namespace dentsim {

namespace {

void require_gain(double v, const char* field, const char* unit) {
  if (!(std::isfinite(v) && v >= 0.0)) {
    throw InputError(std::string("CouplingGains.") + field + " must be finite and >= 0 " + unit +
                     ", got " + std::to_string(v));
  }
}

}  // namespace

void validate_coupling_gains(const CouplingGains& g) {
  require_gain(g.k_lin, "k_lin", "N/m");
  require_gain(g.k_ang, "k_ang", "N m/rad");
  require_gain(g.b_lin, "b_lin", "N s/m");
  require_gain(g.b_ang, "b_ang", "N m s/rad");
}

AffineWrench coupling_proxy_wrench(const CouplingGains& g, const Pose& device, const Vec6& V1,
                                   const ProxyState& proxy, double T, Scheme scheme) {
  validate_coupling_gains(g);
  validate_tick_length(T);
  return coupling_proxy_wrench_unchecked(g, device, V1, proxy, T, scheme);
}

AffineWrench coupling_proxy_wrench_unchecked(const CouplingGains& g, const Pose& device,
                                             const Vec6& V1, const ProxyState& proxy, double T,
                                             Scheme scheme) {
  const Mat3 R21 = proxy.pose.R.transpose() * device.R;  // R2^T R1
  AffineWrench F;
  // (4.5)/(4.6): the parts independent of the proxy velocity.
  lin(F.f0) = -g.k_lin * (proxy.pose.x - device.x) + g.b_lin * lin(V1);
  ang(F.f0) = g.k_ang * so3_spring_vector(R21)  // -k(-phi_21/(2 sin phi_21) w_bar_21)
              + g.b_ang * (R21 * ang(V1));      // w1 seen in the proxy frame
  // Velocity-dependent parts: dampers on V, plus the midpoint terms T/2 v_hat (2.7) and
  // T/2 w_hat (2.13) of the springs for PMI.
  const double half_T = scheme == Scheme::kMidpoint ? 0.5 * T : 0.0;
  F.G = -block_diag((g.k_lin * half_T + g.b_lin) * Mat3::Identity(),
                    (g.k_ang * half_T + g.b_ang) * Mat3::Identity());
  return F;
}

Vec6 coupling_device_wrench(const CouplingGains& g, const Pose& device, const Vec6& V1,
                            const ProxyState& proxy, double T, Scheme scheme) {
  validate_coupling_gains(g);
  validate_tick_length(T);
  return coupling_device_wrench_unchecked(g, device, V1, proxy, T, scheme);
}

Vec6 coupling_device_wrench_unchecked(const CouplingGains& g, const Pose& device, const Vec6& V1,
                                      const ProxyState& proxy, double T, Scheme scheme) {
  const Mat3 R12 = device.R.transpose() * proxy.pose.R;  // R1^T R2
  // kMidpoint: the proxy's last representative velocity V_hat_2,k-1 (4.3)-(4.4);
  // kExplicit: its current velocity V_2,k.
  const Vec6& V2 = scheme == Scheme::kMidpoint ? proxy.V_hat_prev : proxy.V;
  const Vec3 w1 = ang(V1);
  Vec6 F;
  lin(F) = -g.k_lin * (device.x - proxy.pose.x) - g.b_lin * (lin(V1) - lin(V2));  // (4.3)
  ang(F) = g.k_ang * so3_spring_vector(R12)   // -k(-phi_12/(2 sin phi_12) w_bar_12)
           - g.b_ang * (w1 - R12 * ang(V2));  // (4.4) damper, w2 seen in frame 1
  if (scheme == Scheme::kMidpoint) ang(F) -= g.k_ang * 0.5 * T * w1;  // (4.4) T/2 w1 term
  return F;
}

double coupling_potential(const CouplingGains& g, const Pose& device, const Pose& proxy) {
  validate_coupling_gains(g);
  const double phi = rotation_angle(device.R.transpose() * proxy.R);  // (2.11)
  return 0.5 * g.k_lin * (device.x - proxy.x).squaredNorm() + 0.5 * g.k_ang * phi * phi;
}

}  // namespace dentsim
