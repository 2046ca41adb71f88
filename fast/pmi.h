// The PMI solve (4.9), fast twin of reference/pmi.h's pmi_try_solve: the same symmetric diagonal
// scaling D = diag(1/sqrt|A_ii|), then a partial-pivoting LU of the scaled 6x6 system instead of
// the reference's full pivoting (about a third of the work). A is non-singular by construction
// (M 2/T dominates), so partial pivoting is stable here; a pivot below 1e-13 of the largest
// (relative to the scaled system, whose diagonal is +-1) is reported as singular. Equal to the
// reference within the tolerance policy (tests/fast/tick_test.cc).
#pragma once

#include "reference/core/affine_wrench.h"

namespace dentsim::fast {

bool pmi_try_solve(const PmiSystem& sys, Vec6* V_hat);

}  // namespace dentsim::fast
