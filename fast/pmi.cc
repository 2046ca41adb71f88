#include "fast/pmi.h"

#include <Eigen/LU>
#include <cmath>

#include "reference/pmi.h"

namespace dentsim::fast {

bool pmi_try_solve(const PmiSystem& sys, Vec6* V_hat) {
  if (!sys.A.allFinite() || !sys.b.allFinite()) return false;
  const Vec6 d = pmi_scaling(sys.A);  // the reference's scaling (reference/pmi.h)
  const Mat6 As = d.asDiagonal() * sys.A * d.asDiagonal();
  const Eigen::PartialPivLU<Mat6> lu(As);
  const auto U = lu.matrixLU().diagonal().cwiseAbs();
  if (!(U.minCoeff() > 1e-13 * U.maxCoeff())) return false;
  *V_hat = d.cwiseProduct(lu.solve(d.cwiseProduct(sys.b)));
  return V_hat->allFinite();
}

}  // namespace dentsim::fast
