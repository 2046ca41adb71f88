#include "reference/explicit_euler.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <stdexcept>

#include "reference/core/so3.h"
#include "reference/pmi.h"

namespace dentsim {

ProxyState explicit_euler_advance(const ProxyParams& p, const ProxyState& s, const Vec6& F,
                                  double T) {
  validate_proxy_params(p);
  validate_tick_length(T);
  if (!F.allFinite()) throw std::runtime_error("explicit_euler_advance: wrench F is not finite");
  return explicit_euler_advance_unchecked(p, s, F, T);
}

ProxyState explicit_euler_advance_unchecked(const ProxyParams& p, const ProxyState& s,
                                            const Vec6& F, double T) {
  Vec6 rhs = F - p.B() * s.V;
  if (p.gyroscopic) {
    // C(w_k) w_k = [0; -S(J w_k) w_k] = [0; w_k x J w_k]   (2.5), (2.8)
    const Vec3 w = ang(s.V);
    ang(rhs) -= w.cross(p.inertia * w);
  }
  ProxyState n;
  lin(n.V) = lin(s.V) + (T / p.mass) * lin(rhs);
  ang(n.V) = ang(s.V) + T * p.inertia.inverse() * ang(rhs);
  n.pose.x = s.pose.x + T * lin(s.V);
  n.pose.R = s.pose.R * exp_so3(T * ang(s.V));
  n.V_hat_prev = s.V;
  return n;
}

}  // namespace dentsim
