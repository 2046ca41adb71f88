#include "reference/decomposition.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <stdexcept>
#include <string>

namespace dentsim {
namespace {

void require_spd(const Mat6& M, const char* what) {
  if (!M.allFinite()) throw std::invalid_argument(std::string(what) + " has non-finite entries");
  if ((M - M.transpose()).norm() > 1e-9 * (1.0 + M.norm())) {
    throw std::invalid_argument(std::string(what) + " is not symmetric");
  }
  Eigen::LLT<Mat6> llt(M);
  if (llt.info() != Eigen::Success) {
    throw std::invalid_argument(std::string(what) + " is not positive definite");
  }
}

void require_rotation(const Mat3& R, const char* what) {
  if (!R.allFinite() || (R.transpose() * R - Mat3::Identity()).norm() > 1e-6 ||
      R.determinant() < 0.0) {
    throw std::invalid_argument(std::string(what) + " is not a rotation matrix");
  }
}

}  // namespace

Mat6 coupling_frame_map(const Mat3& R1, const Mat3& R2) {
  // E^T V2 = [v2; R1^T R2 w2]: the proxy's body-frame angular velocity expressed in the device
  // tip frame (the same map the coupling (4.4) applies to w2). Hence E = diag(I, R2^T R1).
  return block_diag(Mat3::Identity(), R2.transpose() * R1);
}

bool decompose_locked(const Mat6& M1, const Mat6& M2, const Mat3& R1, const Mat3& R2,
                      Decomposition* out) {
  Decomposition& d = *out;
  d.E = coupling_frame_map(R1, R2);
  const Mat6 M2_dev = d.E.transpose() * M2 * d.E;  // E^T M2 E: proxy inertia in device coords
  d.M_L = M1 + M2_dev;                             // (3.3)
  d.M_L = 0.5 * (d.M_L + d.M_L.transpose());
  const Eigen::LLT<Mat6> llt(d.M_L);
  if (llt.info() != Eigen::Success) return false;
  d.phi = llt.solve(M2_dev);  // phi = M_L^-1 E^T M2 E   (3.3)
  return d.phi.allFinite();
}

Decomposition decompose(const Mat6& M1, const Mat6& M2, const Mat3& R1, const Mat3& R2) {
  require_spd(M1, "decompose: M1 (device inertia J1^T M J1)");
  require_spd(M2, "decompose: M2 (proxy inertia)");
  require_rotation(R1, "decompose: R1");
  require_rotation(R2, "decompose: R2");

  const Mat6 I = Mat6::Identity();
  Decomposition d;
  if (!decompose_locked(M1, M2, R1, R2, &d)) {
    throw std::invalid_argument("decompose: the locked inertia M1 + E^T M2 E is not SPD");
  }
  const Mat6 M2_dev = d.E.transpose() * M2 * d.E;
  d.M_shape = d.phi.transpose() * M1 * d.phi + (d.phi - I).transpose() * M2_dev * (d.phi - I);
  d.M_shape = 0.5 * (d.M_shape + d.M_shape.transpose());

  // S = [[I - phi, phi E^T], [I, -E^T]]                                                 (3.3)
  d.S.topLeftCorner<6, 6>() = I - d.phi;
  d.S.topRightCorner<6, 6>() = d.phi * d.E.transpose();
  d.S.bottomLeftCorner<6, 6>() = I;
  d.S.bottomRightCorner<6, 6>() = -d.E.transpose();
  // S^-1 = [[I, phi], [E, E (phi - I)]] (valid because E^T E = I)                        (3.4)
  d.S_inv.topLeftCorner<6, 6>() = I;
  d.S_inv.topRightCorner<6, 6>() = d.phi;
  d.S_inv.bottomLeftCorner<6, 6>() = d.E;
  d.S_inv.bottomRightCorner<6, 6>() = d.E * (d.phi - I);
  return d;
}

Vec6 locked_velocity(const Decomposition& d, const Vec6& V1, const Vec6& V2) {
  return (Mat6::Identity() - d.phi) * V1 + d.phi * (d.E.transpose() * V2);  // (3.3)
}

Vec6 shape_velocity(const Decomposition& d, const Vec6& V1, const Vec6& V2) {
  return V1 - d.E.transpose() * V2;  // (3.3)
}

Vec6 locked_force(const Decomposition& d, const Vec6& F1, const Vec6& F2) {
  return F1 + d.E.transpose() * F2;  // first row of S^-T (3.3)
}

Vec6 shape_force(const Decomposition& d, const Vec6& F1, const Vec6& F2) {
  // second row of S^-T: phi^T F1 + (phi^T - I) E^T F2                                    (3.3)
  return d.phi.transpose() * F1 + (d.phi.transpose() - Mat6::Identity()) * (d.E.transpose() * F2);
}

Mat6 maximal_inertia(const MatX& M_joint, const Mat6& J1) {
  if (M_joint.rows() != 6 || M_joint.cols() != 6) {
    throw std::invalid_argument("maximal_inertia: joint-space M must be 6x6, got " +
                                std::to_string(M_joint.rows()) + "x" +
                                std::to_string(M_joint.cols()));
  }
  const Mat6 Mj = M_joint;
  return J1.transpose() * Mj * J1;  // (2.2): KE = 1/2 qd^T M qd, qd = J1 V1
}

PdFeedforward pd_feedforward(const Decomposition& d, const ToolDynamics& tool, const Vec6& V1,
                             const Vec6& F1_hat, const AffineWrench& F2) {
  const Eigen::LLT<Mat6> Md_llt(tool.M_d);
  if (Md_llt.info() != Eigen::Success || !tool.M_d.allFinite()) {
    throw std::invalid_argument("pd_feedforward: tool '" + tool.name +
                                "' has an M_d that is not positive definite");
  }
  return pd_feedforward(d, Md_llt, tool.D_d, V1, F1_hat, F2);
}

PdFeedforward pd_feedforward(const Decomposition& d, const Eigen::LLT<Mat6>& Md_llt,
                             const Mat6& D_d, const Vec6& V1, const Vec6& F1_hat,
                             const AffineWrench& F2) {
  const Mat6 I = Mat6::Identity();
  const Mat6 Et = d.E.transpose();
  // A = M_L M_d^-1 (M_d SPD: A^T = M_d^-1 M_L solves M_d A^T = M_L).
  const Mat6 A = Md_llt.solve(d.M_L).transpose();
  // X(V) = A (F_L(V) - D_d v_L(V)) = X0 + XG V with                                       (4.7)
  //   F_L(V) = F1_hat + E^T (f0 + G V),  v_L(V) = (I - phi) V1 + phi E^T V.
  const Vec6 X0 = A * (F1_hat + Et * F2.f0 - D_d * ((I - d.phi) * V1));
  const Mat6 XG = A * (Et * F2.G - D_d * d.phi * Et);

  PdFeedforward out;
  const Mat6 P1 = I - d.phi.transpose();    // (I - phi^T)
  const Mat6 P2 = d.E * d.phi.transpose();  // E phi^T
  out.T1.f0 = P1 * X0 - F1_hat;  // T1_pd = (I - phi^T) X - F1_hat                         (4.7)
  out.T1.G = P1 * XG;
  out.T2.f0 = P2 * X0 - F2.f0;  // T2_pd = E phi^T X - F2                                   (4.7)
  out.T2.G = P2 * XG - F2.G;
  return out;
}

}  // namespace dentsim
