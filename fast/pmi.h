// The PMI solve (4.9), fast twin of reference/pmi.h's pmi_try_solve: the same symmetric diagonal
// scaling D = diag(1/sqrt|A_ii|), then a partial-pivoting LU of the scaled 6x6 system instead of
// the reference's full pivoting (about a third of the work). A is non-singular by construction
// (M 2/T dominates), so partial pivoting is stable here; a pivot below 1e-13 of the largest
// (relative to the scaled system, whose diagonal is +-1) is reported as singular. Equal to the
// reference within the tolerance policy (tests/fast/tick_test.cc).
//
// The factorisation is its own step (pmi_factor) so that a caller with several right-hand sides
// for one A factors it once: the friction solve (fast/friction.h) solves b and the two tangent
// wrenches with one factor.
#pragma once

#include "fast/dense6.h"
#include "reference/core/affine_wrench.h"

namespace dentsim::fast {

// A = D^-1 (P^-1 L U) D^-1: the LU of the scaled system D A D and the scaling D.
struct PmiFactor {
  Vec6 d;  // D's diagonal (reference/pmi.h pmi_scaling)
  Lu6 lu;  // fast/dense6.h
};

// Factors A; false when A is not finite or singular (the pivot test above). Never throws.
bool pmi_factor(const Mat6& A, PmiFactor* f);

// x = A^-1 b from A's factor: y = (D A D)^-1 (D b), x = D y (x may not alias b).
inline void pmi_factor_solve(const PmiFactor& f, const Vec6& b, Vec6* x) {
  Vec6 y;
  lu6_solve(f.lu, f.d.cwiseProduct(b), &y);
  *x = f.d.cwiseProduct(y);
}

bool pmi_try_solve(const PmiSystem& sys, Vec6* V_hat);

}  // namespace dentsim::fast
