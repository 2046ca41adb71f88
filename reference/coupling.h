// Virtual coupling between the device (index 1) and the proxy (index 2): thesis §2.2 and §4.1.1,
// (2.9)-(2.14), (4.3)-(4.6).
//
// Units and frames: SI. Device twist V1 = [v1 (world); w1 (device body {B1})], proxy twist
// V2 = [v2 (world); w2 (proxy body {B2})]. Wrenches [f (world); tau (body of the body acted
// on)]. Gains K_vc = diag(k_lin I, k_ang I) [N/m, N m/rad], B_vc = diag(b_lin I, b_ang I)
// [N s/m, N m s/rad]. T = T_k [s].
//
// SO(3) spring (2.11)-(2.13): potential psi = 1/2 k_ang phi^2 with phi = phi_12 = phi_21 the angle
// of R1^T R2 (the traces of R1^T R2 and R2^T R1 are equal, so phi_12 = phi_21; the mix in (4.6)
// is harmless). With S(w_bar_12) = R1^T R2 - R2^T R1 (2.12), phi/(2 sin phi) w_bar_12 is the
// rotation vector log(R1^T R2) (so3_spring_vector: finite at phi -> 0 and phi -> pi), and
// log(R2^T R1) = -log(R1^T R2). The spring torque pulls each body towards the other:
//   device, frame {B1}:  +k_ang phi_12/(2 sin phi_12) w_bar_12 = k_ang log(R1^T R2)
//   proxy,  frame {B2}:  +k_ang phi_21/(2 sin phi_21) w_bar_21 = k_ang log(R2^T R1)
// (the signs inside (4.4)/(4.5): -k(-phi/(2 sin phi) w_bar + ...)). In the world the two are
// equal and opposite: R2 log(R1^T R2) = R1 log(R1^T R2) since the axis is fixed by R1^T R2.
//
// Proxy side (4.5), PMI form (Scheme::kMidpoint), affine in the proxy midpoint velocity V_hat:
//   f2   = -k_lin (x_2,k + T/2 v_hat - x_1,k) - b_lin (v_hat - v_1,k)
//   tau2 = k_ang log(R2^T R1) - k_ang T/2 w_hat - b_ang (w_hat - R2^T R1 w_1,k)
// i.e. f0 = [-k_lin (x2 - x1) + b_lin v1; k_ang log(R2^T R1) + b_ang R2^T R1 w1],
//      G  = -diag((k_lin T/2 + b_lin) I, (k_ang T/2 + b_ang) I)                  -> (4.6)
// Scheme::kExplicit: the standard spring-damper at t_k, to be evaluated at V_k:
//      f0 as above, G = -diag(b_lin I, b_ang I).
// Device side (4.3)-(4.4), maximal coordinates of the device:
//   kMidpoint: f1   = -k_lin (x1 - x2) - b_lin (v1 - v_hat_2,k-1)
//              tau1 = k_ang log(R1^T R2) - k_ang T/2 w1 - b_ang (w1 - R1^T R2 w_hat_2,k-1)
//   kExplicit: the same with V_2,k in place of V_hat_2,k-1 and without the T/2 w1 term.
// The midpoint terms make the proxy side exactly passive for the translational spring and
// passive to O(T^2) per tick for the SO(3) spring (docs/derivations/pmi_and_coupling.md,
// coupling_test).
#pragma once

#include "reference/core/affine_wrench.h"
#include "reference/core/params.h"
#include "reference/core/types.h"

namespace dentsim {

// Throws InputError naming the field unless every gain is finite and >= 0.
void validate_coupling_gains(const CouplingGains& g);

// Proxy side T2_vc (4.5) as an affine wrench in the proxy velocity (see above).
AffineWrench coupling_proxy_wrench(const CouplingGains& g, const Pose& device, const Vec6& V1,
                                   const ProxyState& proxy, double T, Scheme scheme);

// Device side T1_vc (4.3)-(4.4): f1 in the world, tau1 in the device body frame.
Vec6 coupling_device_wrench(const CouplingGains& g, const Pose& device, const Vec6& V1,
                            const ProxyState& proxy, double T, Scheme scheme);

// The same without validating g and T (the servo tick validates them once, when its model is
// built): never throws.
AffineWrench coupling_proxy_wrench_unchecked(const CouplingGains& g, const Pose& device,
                                             const Vec6& V1, const ProxyState& proxy, double T,
                                             Scheme scheme);
Vec6 coupling_device_wrench_unchecked(const CouplingGains& g, const Pose& device, const Vec6& V1,
                                      const ProxyState& proxy, double T, Scheme scheme);

// Coupling potential 1/2 k_lin |x1 - x2|^2 + 1/2 k_ang phi_12^2 [J], phi_12 of (2.11).
double coupling_potential(const CouplingGains& g, const Pose& device, const Pose& proxy);

}  // namespace dentsim
