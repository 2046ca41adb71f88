// Passive decomposition of the device-proxy pair into a locked (coordinated) system and a shape
// (coordination-error) system, with the dynamics-augmentation feed-forward of the locked system
// (thesis §3.1, eqs (3.1)-(3.6); implemented form (4.7)). Derivation and conventions:
// docs/derivations/decomposition_and_observer.md.
//
// Units and frames: SI. Twists V = [v (world {O}); w (body)], wrenches F = [f (world); tau (body)]
// (docs/conventions.md). Index 1 = device (master), in maximal coordinates: V1 = [v1; w1], w1 in
// the device tip frame {B1}; index 2 = proxy: V2 = [v2; w2] with w2 in the proxy frame {B2}.
//
// Frame reading of E (docs/derivations/decomposition_and_observer.md "1. The frame reading of E"):
// the proxy twist seen in the device's coordinates is E^T V2 = [v2; R1^T R2 w2], so
//     E = diag(I, R2^T R1),   E^T E = I                                         (3.3)-(3.4)
// — the transpose of the block printed in the thesis. With this reading
//     v_E = V1 - E^T V2 = [v1 - v2; w1 - R1^T R2 w2]
// vanishes exactly when the two bodies translate and turn as one rigid body (R1 w1 = R2 w2).
//
// Decomposition (3.3)-(3.4), with M1 = J1^T M(q) J1 (2.2) and M2 the proxy inertia (4.2):
//     phi   = (M1 + E^T M2 E)^-1 E^T M2 E
//     S     = [[I - phi, phi E^T], [I, -E^T]],   [v_L; v_E] = S [V1; V2]
//     S^-1  = [[I, phi], [E, E (phi - I)]]
//     S^-T diag(M1, M2) S^-1 = diag(M_L, M_E),  M_L = M1 + E^T M2 E,
//     M_E = phi^T M1 phi + (phi - I)^T E^T M2 E (phi - I)
//     [F_L; F_E] = S^-T [F1; F2] = [F1 + E^T F2; phi^T F1 + (phi^T - I) E^T F2]
//
// Dynamics augmentation (§3.1.2): the locked system is made to follow the tool's desired
// dynamics M_d dv_L/dt + D_d v_L = F_L. With the Coriolis terms C_L, C_LE, C_EL, C_L,d dropped
// (slow operation, thesis §4.1.1) and the shape control T_E = -F_E (its PD part is the virtual
// coupling, added by the caller), decoding [T1; T2] = S^T [T_L; T_E] gives (4.7):
//     T1_pd = (I - phi^T) M_L M_d^-1 (F_L - D_d v_L) - F1_hat
//     T2_pd = E phi^T M_L M_d^-1 (F_L - D_d v_L) - F2
// with F_L = F1_hat + E^T F2 and v_L = (I - phi) V1 + phi E^T V2.
#pragma once

#include <Eigen/Cholesky>

#include "reference/core/affine_wrench.h"
#include "reference/core/params.h"
#include "reference/core/types.h"

namespace dentsim {

// The decomposition matrix is 12x12 (it maps [V1; V2] to [v_L; v_E]); the API sketch listed S and
// S_inv among the 6x6 members, here they are Mat12.
using Mat12 = Eigen::Matrix<double, 12, 12>;

struct Decomposition {
  Mat6 E;       // diag(I, R2^T R1): E^T maps proxy twists/wrenches to device coordinates
  Mat6 phi;     // (M1 + E^T M2 E)^-1 E^T M2 E                                    (3.3)
  Mat12 S;      // [[I - phi, phi E^T], [I, -E^T]]                                (3.3)
  Mat12 S_inv;  // [[I, phi], [E, E (phi - I)]]                                   (3.4)
  Mat6 M_L;     // locked inertia M1 + E^T M2 E                                   (3.3)
  // Shape inertia M_E = phi^T M1 phi + (phi - I)^T E^T M2 E (phi - I) (3.3). Named M_shape:
  // `M_E` is the libc macro for Euler's number (<cmath>), so it cannot be a member name.
  Mat6 M_shape;
};

// Builds the decomposition at the current poses. M1, M2 must be symmetric positive definite and
// R1, R2 rotations; throws std::invalid_argument otherwise (M_L not SPD or non-finite input).
Decomposition decompose(const Mat6& M1, const Mat6& M2, const Mat3& R1, const Mat3& R2);

// The part of the decomposition the servo tick needs (E, phi, M_L; S, S^-1 and M_shape are left
// untouched): no validation, never throws; returns false when M_L is not positive definite.
bool decompose_locked(const Mat6& M1, const Mat6& M2, const Mat3& R1, const Mat3& R2,
                      Decomposition* d);

// E = diag(I, R2^T R1).
Mat6 coupling_frame_map(const Mat3& R1, const Mat3& R2);

// v_L = (I - phi) V1 + phi E^T V2 and v_E = V1 - E^T V2 (3.3).
Vec6 locked_velocity(const Decomposition& d, const Vec6& V1, const Vec6& V2);
Vec6 shape_velocity(const Decomposition& d, const Vec6& V1, const Vec6& V2);
// F_L = F1 + E^T F2 and F_E = phi^T F1 + (phi^T - I) E^T F2 (the rows of S^-T, (3.3)).
Vec6 locked_force(const Decomposition& d, const Vec6& F1, const Vec6& F2);
Vec6 shape_force(const Decomposition& d, const Vec6& F1, const Vec6& F2);

// The device inertia in maximal coordinates, J1^T M(q) J1 (2.2), with qd = J1 V1.
Mat6 maximal_inertia(const MatX& M_joint, const Mat6& J1);

// The dynamics-augmentation feed-forward (4.7). F2 is the environment wrench on the proxy, affine
// in the proxy velocity V the solver evaluates at (V_hat_2,k for PMI); v_L and F_L are evaluated
// at the same V, so both outputs are affine in V:
//     T1(V) = (I - phi^T) X(V) - F1_hat,   T2(V) = E phi^T X(V) - F2(V),
//     X(V)  = M_L M_d^-1 (F1_hat + E^T F2(V) - D_d ((I - phi) V1 + phi E^T V)).
// Identities (tested): T1 + F1_hat = M1 M_L^-1 X, T2 + F2 = M2 E M_L^-1 X, so the locked system
// receives T_L + F_L = X and the shape system T_E + F_E = 0 when F1_hat = F1.
struct PdFeedforward {
  AffineWrench T1;
  AffineWrench T2;
};
PdFeedforward pd_feedforward(const Decomposition& d, const ToolDynamics& tool, const Vec6& V1,
                             const Vec6& F1_hat, const AffineWrench& F2);
// The same with M_d factorised once (the servo tick's model holds the factorisation); needs only
// d.E, d.phi and d.M_L. Never throws.
PdFeedforward pd_feedforward(const Decomposition& d, const Eigen::LLT<Mat6>& Md_llt,
                             const Mat6& D_d, const Vec6& V1, const Vec6& F1_hat,
                             const AffineWrench& F2);

}  // namespace dentsim
