// The decomposition's feed-forward on its block structure (equations: fast/decomposition.h).
#include "fast/decomposition.h"

#include "fast/dense6.h"

namespace dentsim::fast {

bool pd_tool_is_diagonal(const ToolDynamics& tool) {
  for (int c = 0; c < 6; ++c) {
    for (int r = 0; r < 6; ++r) {
      if (r != c && (tool.M_d(r, c) != 0.0 || tool.D_d(r, c) != 0.0)) return false;
    }
  }
  return true;
}

bool pd_feedforward_diagonal(const Mat6& M1, const ProxyParams& proxy, const ToolDynamics& tool,
                             const Mat3& R1, const Mat3& R2, const Vec6& V1, const Vec6& F1_hat,
                             const AffineWrench& F2, PdFeedforward* out) {
  const Mat3 Q = R2.transpose() * R1;  // E = diag(I, Q)
  const Mat3 Qt = Q.transpose();
  // M_L = M1 + E^T M2 E = M1 + diag(m I, Q^T J Q), symmetrised as the reference's   (3.3)
  const Mat3 Jq = Qt * proxy.inertia * Q;
  Mat6 M_L = M1;
  M_L.diagonal().head<3>().array() += proxy.mass;
  M_L.bottomRightCorner<3, 3>() += Jq;
  M_L = (0.5 * (M_L + M_L.transpose())).eval();
  Llt6 L;
  if (!cholesky6(M_L, &L)) return false;  // fast/dense6.h
  Mat6 phi = Mat6::Zero();
  phi.diagonal().head<3>().setConstant(proxy.mass);
  phi.bottomRightCorner<3, 3>() = Jq;
  cholesky6_solve_in_place(L, &phi);  // phi = M_L^-1 E^T M2 E                      (3.3)
  if (!phi.allFinite()) return false;

  const Vec6 md_inv = tool.M_d.diagonal().cwiseInverse();
  const Vec6 dd = tool.D_d.diagonal();
  const Mat6 A = M_L * md_inv.asDiagonal();  // M_L M_d^-1
  // X0 = A (F1_hat + E^T f0 - D_d (I - phi) V1)
  Vec6 b0 = F1_hat;
  b0.head<3>() += F2.f0.head<3>();
  b0.tail<3>().noalias() += Qt * F2.f0.tail<3>();
  b0 -= dd.cwiseProduct(V1 - phi * V1);
  // XG = A (E^T G - D_d phi E^T): E^T G turns G's lower rows, phi E^T phi's right columns.
  Mat6 BG;
  BG.topRows<3>() = F2.G.topRows<3>();
  BG.bottomRows<3>().noalias() = Qt * F2.G.bottomRows<3>();
  Mat6 phiEt;
  phiEt.leftCols<3>() = phi.leftCols<3>();
  phiEt.rightCols<3>().noalias() = phi.rightCols<3>() * Qt;
  BG.noalias() -= dd.asDiagonal() * phiEt;
  const Vec6 X0 = A * b0;
  Mat6 XG;
  XG.noalias() = A * BG;
  // Y = phi^T X, once for both outputs                                                  (4.7)
  const Vec6 Y0 = phi.transpose() * X0;
  Mat6 YG;
  YG.noalias() = phi.transpose() * XG;
  out->T1.f0 = X0 - Y0 - F1_hat;  // (I - phi^T) X - F1_hat
  out->T1.G = XG - YG;
  out->T2.f0.head<3>() = Y0.head<3>() - F2.f0.head<3>();  // E phi^T X - F2
  out->T2.f0.tail<3>() = Q * Y0.tail<3>() - F2.f0.tail<3>();
  out->T2.G.topRows<3>() = YG.topRows<3>() - F2.G.topRows<3>();
  out->T2.G.bottomRows<3>() = Q * YG.bottomRows<3>() - F2.G.bottomRows<3>();
  return true;
}

}  // namespace dentsim::fast
