// Constraint-based Coulomb friction at the blended contact point (thesis §2.4, (2.20)-(2.22),
// (4.10)). Derivations: docs/derivations/contact_and_friction.md.
//
// Units: m, s, N, N m. Frames: V = [v (world); w (body)], F = [f (world); tau (body)].
//
// Given the proxy's linear system A V = b (PMI (4.9): A = M 2/T + B + C_k - sum G, V = V_hat; or
// the explicit-Euler system with V = V_k+1), already holding inertia, coupling and the normal
// contact, friction adds the wrench F_fric = J^T f_t with J = J_c(r, R2) = [I, -R2 S(r)] at the
// blended contact point (r, n) of the set (blended_contact in reference/contact.h), and
//   f_t = t1 lambda_1 + t2 lambda_2                                                     (2.21)
// with t1, t2 an orthonormal tangent basis (n, t1, t2 right-handed; the result does not depend on
// the choice). Note the thesis prints the map as [I; R^T S(r)]; the body-frame torque of f at
// x_c is S(r) R^T f (see reference/contact.h).
//
// 1. Stick (KKT): lambda such that t_i^T J V = 0 (2.22):
//      [A, -H; H^T, 0] [V; lambda] = [b; 0],  H = J^T [t1 t2]  (6x2)
//    solved by the Schur complement W = H^T A^-1 H (2x2): lambda = -W^-1 H^T A^-1 b.
// 2. Cone: f_n(V) = max(0, n^T f(V)) with f(V) the force part of `normal` at V (the thesis writes
//    lambda <= mu delta with K absorbed; here the cone is mu |f_n| in newtons). If |f_stick| <=
//    mu f_n(V_stick) the contact sticks.
// 3. Slide: otherwise f_t = s d with d = f_stick / |f_stick| (opposing the slip the sticking force
//    was preventing) and s chosen so that the cone holds with equality AT THE FINAL SOLUTION:
//    V(s) = A^-1 (b + J^T d s) is affine in s, so is f_n(V(s)) = alpha + beta s, and
//    s = mu alpha / (1 - mu beta) (in (0, |f_stick|)); if alpha <= 0 the normal force vanishes
//    and s = 0. Then V is re-solved with f_t fixed.
// With sym(A) positive definite friction never does positive work on the contact point:
// f_t^T J V = 0 when sticking and = -s (|f_stick| - s) d^T J A^-1 J^T d <= 0 when sliding.
#pragma once

#include <span>

#include "reference/core/affine_wrench.h"
#include "reference/core/params.h"
#include "reference/core/types.h"

namespace dentsim {

struct FrictionSolution {
  Vec6 V = Vec6::Zero();    // the solved velocity (V_hat for PMI, V_{k+1} for explicit)
  Vec3 f_t = Vec3::Zero();  // tangential friction force (world), |f_t| <= mu |f_n|
  double f_n = 0.0;         // normal force magnitude used for the cone, at the solved V [N]
  bool sliding = false;     // true when the cone clamped the sticking force
  Vec6 F = Vec6::Zero();    // friction wrench on the proxy, J^T f_t = [I; S(r) R^T] f_t  (4.10)
  bool active = false;  // true when friction was applied (enabled, mu > 0, a contact penetrates)
};

// An orthonormal tangent basis (t1, t2) of a unit normal n: n, t1, t2 right-handed.
void tangent_basis(const Vec3& n, Vec3& t1, Vec3& t2);

// Solves sys (A V = b, which already contains inertia, coupling and contact) with Coulomb friction
// at the blended contact point of `contacts` (see above). `normal` is the normal contact wrench
// that sys contains (contact_wrench(...)), used to evaluate f_n at the solution. Without friction
// (fp.enabled false, mu = 0, or no penetrating contact) it returns the plain solve of A V = b.
// Throws InputError if mu is negative or not finite, if A is singular or if A or b is not
// finite.
FrictionSolution solve_with_friction(const PmiSystem& sys, std::span<const Contact> contacts,
                                     const Pose& proxy, const AffineWrench& normal,
                                     const FrictionParams& fp);

// The servo tick's form (mu validated once when its model is built): fills `out` and returns
// true, or returns false when A or b is not finite or A is singular. Never throws.
bool solve_with_friction_unchecked(const PmiSystem& sys, std::span<const Contact> contacts,
                                   const Pose& proxy, const AffineWrench& normal,
                                   const FrictionParams& fp, FrictionSolution* out);

// The servo tick's friction solve as a parameter (reference::detail::solve_with): the reference's
// above or its fast twin (fast/friction.h), same contract.
using FrictionSolve = bool (*)(const PmiSystem& sys, std::span<const Contact> contacts,
                               const Pose& proxy, const AffineWrench& normal,
                               const FrictionParams& fp, FrictionSolution* out);

}  // namespace dentsim
