// Constraint-based Coulomb friction, fast twin of reference/friction.h's
// solve_with_friction_unchecked (issue #30): the same model (thesis (2.20)-(2.22), (4.10);
// docs/derivations/contact_and_friction.md §5), the same tests in the same order, with one
// factorisation of A where the reference solves its full-pivoting LU four times.
//
//  - A is factored once as the PMI solve factors it (fast/pmi.h: the scaled system, partial
//    pivoting) and solved for three right-hand sides: b (the frictionless V0) and the two columns
//    h1, h2 of H = J^T [t1 t2]. The sliding direction d = f_stick / |f_stick| = [t1 t2] e with
//    e = lambda / |lambda| (t1, t2 orthonormal, so |f_stick| = |lambda|), hence
//        V_d = A^-1 J^T d = (A^-1 H) e      (no fourth solve),
//    and the friction wrench J^T f_t = H m for the final multipliers m (lambda sticking, s e
//    sliding).
//  - H from J = [I, -R S(r)]: J^T t = [t; r x (R^T t)], no 6x3 product.
//  - f_n(V) = n^T (f0 + G V)_force = n^T f0_force + g^T V with g = (G's force rows)^T n, formed
//    once: one 6-vector dot an evaluation instead of a 6x6 product.
//  - W = H^T A^-1 H (2x2) by Cramer's rule, which is forward stable for n = 2 (Higham, Accuracy
//    and Stability of Numerical Algorithms, 2nd ed., §1.10.1). W is nonsingular when sym(A) is
//    positive definite (then so is sym(A^-1), and H has full column rank), as it is for the
//    PMI system (4.9). For an A outside that class det W may vanish: the multipliers and V are
//    then not finite (the tick fails in command, kNonFiniteOutput) where the reference's
//    full-pivoting 2x2 LU returns one of the solutions.
//
// Not bitwise with the reference (another factorisation, other orders of the sums): equal within
// the bound derived in tests/fast/friction_test.cc. At the stick/slide boundary (|f_stick| =
// mu f_n(V_stick)) the two may decide differently by round-off; the sliding solution equals the
// sticking one there (s = |f_stick|), so either result is within the bound. Failure (false): as
// the reference when A or b is not finite, and for an exactly singular A; for a nearly singular A
// the pivot test is fast/pmi.h's (on the scaled system), the reference's rank test is on the
// unscaled one. Nothing here allocates or throws.
#pragma once

#include <span>

#include "reference/friction.h"

namespace dentsim::fast {

// The contract of reference/friction.h's solve_with_friction_unchecked (a FrictionSolve).
bool solve_with_friction_unchecked(const PmiSystem& sys, std::span<const Contact> contacts,
                                   const Pose& proxy, const AffineWrench& normal,
                                   const FrictionParams& fp, FrictionSolution* out);

}  // namespace dentsim::fast
