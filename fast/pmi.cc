#include "fast/pmi.h"

#include "reference/pmi.h"
#include "reference/tick_detail.h"

namespace dentsim::fast {

bool pmi_factor(const Mat6& A, PmiFactor* f) {
  if (!reference::detail::all_finite(A)) return false;
  f->d = pmi_scaling(A);  // the reference's scaling (reference/pmi.h)
  const Mat6 As = f->d.asDiagonal() * A * f->d.asDiagonal();
  if (!lu6(As, &f->lu)) return false;
  const auto U = f->lu.lu.diagonal().cwiseAbs();
  return U.minCoeff() > 1e-13 * U.maxCoeff();
}

bool pmi_try_solve(const PmiSystem& sys, Vec6* V_hat) {
  if (!reference::detail::all_finite(sys.b)) return false;
  PmiFactor f;
  if (!pmi_factor(sys.A, &f)) return false;
  pmi_factor_solve(f, sys.b, V_hat);
  return reference::detail::all_finite(*V_hat);
}

}  // namespace dentsim::fast
