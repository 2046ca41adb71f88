#include "fast/pmi.h"

#include <cmath>

#include "fast/dense6.h"

#include "reference/pmi.h"
#include "reference/tick_detail.h"

namespace dentsim::fast {

bool pmi_try_solve(const PmiSystem& sys, Vec6* V_hat) {
  if (!reference::detail::all_finite(sys.A, sys.b)) return false;
  const Vec6 d = pmi_scaling(sys.A);  // the reference's scaling (reference/pmi.h)
  const Mat6 As = d.asDiagonal() * sys.A * d.asDiagonal();
  Lu6 lu;  // fast/dense6.h
  if (!lu6(As, &lu)) return false;
  const auto U = lu.lu.diagonal().cwiseAbs();
  if (!(U.minCoeff() > 1e-13 * U.maxCoeff())) return false;
  Vec6 x;
  lu6_solve(lu, d.cwiseProduct(sys.b), &x);
  *V_hat = d.cwiseProduct(x);
  return reference::detail::all_finite(*V_hat);
}

}  // namespace dentsim::fast
