// Explicit-Euler proxy: the thesis's baseline, the "standard" virtual coupling of §4.2.
//
// Units and frames as in reference/pmi.h: SI; V = [v (world); w (proxy body)], F = [f (world);
// tau (body)]. T is the tick length T_k [s].
//
// The continuous proxy dynamics (2.3)-(2.5), M dV/dt + C(w) w + B V = F with
// C(w) = diag(0, -S(J w)) (so C(w) w = [0; w x J w]), integrated by forward Euler:
//   V_k+1 = V_k + T M^-1 (F_k - B V_k - C(w_k) w_k)
//   x_k+1 = x_k + T v_k,   R_k+1 = R_k exp(S(w_k T))
// F_k is the total applied wrench evaluated at V_k (forces built with Scheme::kExplicit, e.g.
// coupling_proxy_wrench(..., Scheme::kExplicit).at(s.V)). Unlike PMI this map is not passive: an
// undamped mass-spring gains energy by the factor 1 + (w_n T)^2 every tick (explicit_euler_test).
// The gyroscopic term is kept only if p.gyroscopic, as for PMI.
#pragma once

#include "reference/core/params.h"
#include "reference/core/types.h"

namespace dentsim {

// One explicit-Euler tick. V_hat_prev of the result is V_k: what the device side (4.3)-(4.4)
// sees as the proxy's last velocity.
ProxyState explicit_euler_advance(const ProxyParams& p, const ProxyState& s, const Vec6& F,
                                  double T);
// The servo tick's form (p and T validated once, F checked by the caller): never throws.
ProxyState explicit_euler_advance_unchecked(const ProxyParams& p, const ProxyState& s,
                                            const Vec6& F, double T);

}  // namespace dentsim
