// The decomposition's feed-forward on its block structure (equations: fast/decomposition.h).
#include "fast/decomposition.h"

#include "fast/dense6.h"

namespace dentsim::fast {

void inertia_at_tool(const Mat6& J1, const Mat6& M, Mat6* M1) {
  Mat6 MJ;
  MJ.noalias() = M * J1;
  for (int j = 0; j < 6; ++j) {
    for (int i = 0; i <= j; ++i) {
      const double v = J1.col(i).dot(MJ.col(j));
      (*M1)(i, j) = v;
      (*M1)(j, i) = v;
    }
  }
}

bool pd_tool_is_diagonal(const ToolDynamics& tool) {
  for (int c = 0; c < 6; ++c) {
    for (int r = 0; r < 6; ++r) {
      if (r != c && (tool.M_d(r, c) != 0.0 || tool.D_d(r, c) != 0.0)) return false;
    }
  }
  return true;
}

namespace {

// The feed-forward with T1 formed (T1 set) or kept factored (W set: T1(V) = M1 W(V) - F1_hat).
bool feedforward(const Mat6& M1, const ProxyParams& proxy, const ToolDynamics& tool, const Mat3& R1,
                 const Mat3& R2, const Vec6& V1, const Vec6& F1_hat, const AffineWrench& F2,
                 AffineWrench* T1, AffineWrench* W_out, AffineWrench* T2, FeedforwardKnown known) {
  using Mat37 = Eigen::Matrix<double, 3, 7>;
  using Mat67 = Eigen::Matrix<double, 6, 7>;
  const double m = proxy.mass;
  const Mat3& J = proxy.inertia;
  const Mat3 Q = R2.transpose() * R1;  // E = diag(I, Q)
  const Mat3 Qt = Q.transpose();
  // N = E^T M2 E = diag(m I, Q^T J Q), symmetrised as the reference symmetrises M_L   (3.3)
  // J = j I: Q^T J Q = j I exactly (the general path's product carries round-off off it), and
  // Q^T J = j Q^T, J (Q W) = j (Q W) (bitwise the general path's: the zeros add nothing).
  const bool isotropic = J(0, 1) == 0.0 && J(0, 2) == 0.0 && J(1, 0) == 0.0 && J(1, 2) == 0.0 &&
                         J(2, 0) == 0.0 && J(2, 1) == 0.0 && J(1, 1) == J(0, 0) &&
                         J(2, 2) == J(0, 0);
  const double j = J(0, 0);
  Mat3 QtJ;  // E^T M2 = diag(m I, Q^T J)
  Mat6 M1_symmetrised;
  if (!known.symmetric_M1) M1_symmetrised = 0.5 * (M1 + M1.transpose());
  const Mat6& M1s = known.symmetric_M1 ? M1 : M1_symmetrised;
  Mat6 M_L = M1s;  // M_L = M1 + N
  M_L.diagonal().head<3>().array() += m;
  if (isotropic) {
    QtJ = j * Qt;
    M_L.diagonal().tail<3>().array() += j;
  } else {
    QtJ.noalias() = Qt * J;
    const Mat3 Jq = QtJ * Q;
    M_L.bottomRightCorner<3, 3>() += 0.5 * (Jq + Jq.transpose());
  }
  Llt6 L;
  if (!cholesky6(M_L, &L)) return false;  // fast/dense6.h
  // P = phi E^T = M_L^-1 N E^T = M_L^-1 diag(m I, Q^T J)
  Mat6 P = Mat6::Zero();
  P.diagonal().head<3>().setConstant(m);
  P.bottomRightCorner<3, 3>() = QtJ;
  cholesky6_solve_in_place(L, &P);
  if (!P.allFinite()) return false;
  // phi V1 = phi E^T (E V1)
  Vec6 EV1;
  EV1.head<3>() = V1.head<3>();
  EV1.tail<3>().noalias() = Q * V1.tail<3>();
  Vec6 phiV1;
  phiV1.noalias() = P * EV1;
  // B = [b0 BG]: b0 = F1_hat + E^T f0 - D_d (V1 - phi V1),  BG = E^T G - D_d phi E^T
  const Vec6 dd = tool.D_d.diagonal();
  Mat67 B;
  B.col(0) = F1_hat - dd.cwiseProduct(V1 - phiV1);
  if (known.contact_free) {  // E^T f0 = 0, E^T G = 0
    B.rightCols<6>().setZero();
  } else {
    B.col(0).head<3>() += F2.f0.head<3>();
    B.col(0).tail<3>().noalias() += Qt * F2.f0.tail<3>();
    B.topRightCorner<3, 6>() = F2.G.topRows<3>();
    B.bottomRightCorner<3, 6>().noalias() = Qt * F2.G.bottomRows<3>();
  }
  B.rightCols<6>().noalias() -= dd.asDiagonal() * P;
  // W = M_d^-1 B = M_L^-1 X
  const Mat67 W = tool.M_d.diagonal().cwiseInverse().asDiagonal() * B;
  // T1 + F1_hat = (I - phi^T) X = M1 M_L^-1 X = M1 W: formed (T1.G = M1 WG, 216
  // multiplications) or kept as its factor W
  if (T1 != nullptr) {
    Mat67 T1w;
    T1w.noalias() = M1s * W;
    T1->f0 = T1w.col(0) - F1_hat;
    T1->G = T1w.rightCols<6>();
  } else {
    W_out->f0 = W.col(0);
    W_out->G = W.rightCols<6>();
  }
  // T2 + F2 = E phi^T X = E N M_L^-1 X = diag(m I, J Q) W
  const Mat37 QW = Q * W.bottomRows<3>();
  Mat37 T2w;
  if (isotropic) {
    T2w = j * QW;
  } else {
    T2w.noalias() = J * QW;
  }
  if (known.contact_free) {
    T2->f0.head<3>() = m * W.col(0).head<3>();
    T2->f0.tail<3>() = T2w.col(0);
    T2->G.topRows<3>() = m * W.topRightCorner<3, 6>();
    T2->G.bottomRows<3>() = T2w.rightCols<6>();
    return true;
  }
  T2->f0.head<3>() = m * W.col(0).head<3>() - F2.f0.head<3>();
  T2->f0.tail<3>() = T2w.col(0) - F2.f0.tail<3>();
  T2->G.topRows<3>() = m * W.topRightCorner<3, 6>() - F2.G.topRows<3>();
  T2->G.bottomRows<3>() = T2w.rightCols<6>() - F2.G.bottomRows<3>();
  return true;
}

}  // namespace

bool pd_feedforward_diagonal(const Mat6& M1, const ProxyParams& proxy, const ToolDynamics& tool,
                             const Mat3& R1, const Mat3& R2, const Vec6& V1, const Vec6& F1_hat,
                             const AffineWrench& F2, AffineWrench* T1, AffineWrench* T2,
                             FeedforwardKnown known) {
  return feedforward(M1, proxy, tool, R1, R2, V1, F1_hat, F2, T1, nullptr, T2, known);
}

bool pd_feedforward_diagonal_factored(const Mat6& M1, const ProxyParams& proxy,
                                      const ToolDynamics& tool, const Mat3& R1, const Mat3& R2,
                                      const Vec6& V1, const Vec6& F1_hat, const AffineWrench& F2,
                                      AffineWrench* W, AffineWrench* T2, FeedforwardKnown known) {
  known.symmetric_M1 = true;
  return feedforward(M1, proxy, tool, R1, R2, V1, F1_hat, F2, nullptr, W, T2, known);
}

}  // namespace dentsim::fast
