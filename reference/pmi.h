// Passive midpoint integration (PMI) of the virtual proxy (thesis §2.1.2, §4.1.1).
//
// Units and frames: SI (m, kg, s, N, N m). Twist V = [v (world {O}); w (proxy body {B})], wrench
// F = [f (world); tau (body)], so V^T F is power [W]. T is the tick length T_k [s], free to change
// from tick to tick.
//
// Equations:
//   (2.7)  V_hat_k = (V_k + V_k+1)/2,  x_k+1 = x_k + T v_hat_k,  x_hat_k = (x_k + x_k+1)/2
//   (2.8)  M (V_k+1 - V_k)/T + C_k V_hat_k + B V_hat_k = T_k + F_k,  C_k = diag(0, -S(J w_k))
//   (4.1)-(4.2)  (M 2/T + B) V_hat_k = M 2/T V_k + T_k + F_k     (C_k dropped, as the thesis does)
//   R_k+1 = R_k exp(S(w_hat_k T))                                   (discrete attitude kinematics)
// Every force on the proxy is an AffineWrench F(V_hat) = f0 + G V_hat (reference/core/
// affine_wrench.h) added to the system with PmiSystem::add, so one tick is one 6x6 solve (4.9).
//
// Energy (2.6): multiplying (2.8) by T V_hat_k^T gives, exactly,
//   1/2 V_k+1^T M V_k+1 - 1/2 V_k^T M V_k = T V_hat^T (T_k + F_k) - T V_hat^T B V_hat
// (C_k is skew and does no work), which is the discrete passivity relation (2.6); the midpoint
// springs of the force elements turn T V_hat^T F into an exact potential difference
// (docs/derivations/pmi_and_coupling.md).
#pragma once

#include "reference/core/affine_wrench.h"
#include "reference/core/params.h"
#include "reference/core/types.h"

namespace dentsim {

// Throws InputError naming the field unless m > 0, J symmetric positive definite, damping >= 0,
// all finite.
void validate_proxy_params(const ProxyParams& p);
// Throws InputError unless T is finite and > 0.
void validate_tick_length(double T);

// Which angular velocity the gyroscopic matrix C = diag(0, -S(J w)) of (2.8) is evaluated at
// (only used if p.gyroscopic). Both keep C skew, so the energy balance stays exact.
enum class GyroVelocity {
  // w_k, as (2.8) prints it. One tick changes the world angular momentum R J w by
  // -T^2/2 R_k (w_hat x (w_hat x J w_k)) + O(T^3): a drift of O(T) over a fixed horizon.
  kStart,
  // w_e = 2 w_k - w_hat_k-1 = w_k + (w_k - w_k-1)/2 ~ w(t_k + T/2), from s.V_hat_prev: the O(T^2)
  // term above cancels, so the drift is O(T^2) (pmi_test). s.V_hat_prev must be the previous
  // tick's V_hat (set it to s.V when starting or resetting a proxy). Not in the thesis.
  kExtrapolated,
};

// Inertia/damping part of (4.2)/(4.9): A = M 2/T + B (+ C_k = diag(0, -S(J w)) if
// p.gyroscopic, w chosen by `gyro`), b = M 2/T V_k. Other forces are added with
// PmiSystem::add(AffineWrench).
PmiSystem pmi_inertia_system(const ProxyParams& p, const ProxyState& s, double T,
                             GyroVelocity gyro = GyroVelocity::kStart);

// Solves A V_hat = b (one 6x6 linear solve, no iteration). The columns and rows are first scaled
// by 1/sqrt|A_ii| so the singularity test does not depend on the units mixed in A (N s/m against
// N m s). Throws std::runtime_error if A is singular or the system is not finite.
Vec6 pmi_solve(const PmiSystem& sys);

// State update (2.7): V_k+1 = 2 V_hat - V_k, x_k+1 = x_k + T v_hat, R_k+1 = R_k exp(S(w_hat T)),
// V_hat_prev = V_hat. R is not re-orthonormalised (the drift is measured in pmi_test).
ProxyState pmi_advance(const ProxyState& s, const Vec6& V_hat, double T);

// The servo tick's forms (its model validated p and the driver T once): never throw.
// pmi_try_solve returns false (V_hat unspecified) when A is singular or the system not finite.
PmiSystem pmi_inertia_system_unchecked(const ProxyParams& p, const ProxyState& s, double T,
                                       GyroVelocity gyro = GyroVelocity::kStart);
bool pmi_try_solve(const PmiSystem& sys, Vec6* V_hat);
// The solve's symmetric diagonal scaling D = diag(1/sqrt|A_ii|) (1 where A_ii = 0): the system
// solved is (D A D) y = D b, V_hat = D y (pmi_try_solve and its fast twin fast/pmi.h share it).
Vec6 pmi_scaling(const Mat6& A);
ProxyState pmi_advance_unchecked(const ProxyState& s, const Vec6& V_hat, double T);

// Kinetic energy 1/2 V^T M V [J].
double proxy_kinetic_energy(const ProxyParams& p, const Vec6& V);

}  // namespace dentsim
