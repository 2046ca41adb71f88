#include "fast/pmi.h"

#include <Eigen/LU>
#include <cmath>

namespace dentsim::fast {

bool pmi_try_solve(const PmiSystem& sys, Vec6* V_hat) {
  if (!sys.A.allFinite() || !sys.b.allFinite()) return false;
  Vec6 d;
  for (int i = 0; i < 6; ++i) {
    const double a = std::abs(sys.A(i, i));
    d(i) = a > 0.0 ? 1.0 / std::sqrt(a) : 1.0;
  }
  const Mat6 As = d.asDiagonal() * sys.A * d.asDiagonal();
  const Eigen::PartialPivLU<Mat6> lu(As);
  const auto U = lu.matrixLU().diagonal().cwiseAbs();
  if (!(U.minCoeff() > 1e-13 * U.maxCoeff())) return false;
  *V_hat = d.cwiseProduct(lu.solve(d.cwiseProduct(sys.b)));
  return V_hat->allFinite();
}

}  // namespace dentsim::fast
