// The Phantom's device terms in one pass (equations: fast/phantom/phantom_model.h).
#include "fast/phantom/phantom_model.h"

#include <Eigen/LU>
#include <cmath>
#include <limits>

namespace dentsim::fast {

namespace {

// The shipped gimbal's joint axes (yaw +y, pitch +x, roll +z, each body's rot0 = E):
// PhantomDynamics::shipped_gimbal().
constexpr std::array<int, 3> kShippedGimbalAxis = {1, 0, 2};
// The shipped forearm's orientation in {B} at q3 = 0 (perm flip of reference/phantom's tree): its
// columns e_y, -e_z, -e_x (fore_from_, fore_sign_ of the closed form).
constexpr std::array<int, 3> kShippedForearmFrom = {1, 2, 0};
constexpr std::array<double, 3> kShippedForearmSign = {1.0, -1.0, -1.0};

constexpr std::array<int, kPhantomTreeDof> kParent = {-1,     kBase,    kUpperArm,  kBase,
                                                      kCrank, kForearm, kGimbalYaw, kGimbalPitch};

// G^T v for a tree vector v (theta = G q, phantom_tree_map()).
template <typename V8>
auto tree_to_joint(const V8& v) {
  using T = std::decay_t<decltype(v[0])>;
  Eigen::Matrix<T, 6, 1> out;
  out << v[kBase], v[kUpperArm] - v[kForearm] + v[kParallelLink],
      v[kForearm] + v[kCrank] - v[kParallelLink], v[kGimbalYaw], v[kGimbalPitch], v[kGimbalRoll];
  return out;
}

// J = J_tree G from the tree columns of the tip chain (kBase, kUpperArm, kForearm, gimbal yaw,
// pitch, roll): q2 drives tree joints 1 (+1) and 2 (-1), q3 tree joint 2 (+1) (3 and 4 do not
// move the tip).
template <typename T>
void tip_chain_to_joint(const Eigen::Matrix<T, 6, 6>& tc, Mat6& J) {
  J.col(0) = tc.col(0).template cast<double>();
  J.col(1) = (tc.col(1) - tc.col(2)).template cast<double>();
  J.template rightCols<4>() = tc.template rightCols<4>().template cast<double>();
}

// a x b, written out (Eigen's vectorised cross of float 3-vectors trips GCC 12's -Warray-bounds).
template <typename A, typename B>
Eigen::Matrix<typename A::Scalar, 3, 1> cross(const Eigen::MatrixBase<A>& a_in,
                                              const Eigen::MatrixBase<B>& b_in) {
  const Eigen::Matrix<typename A::Scalar, 3, 1> a = a_in, b = b_in;
  return {a(1) * b(2) - a(2) * b(1), a(2) * b(0) - a(0) * b(2), a(0) * b(1) - a(1) * b(0)};
}

// The same for two plain vectors, read in place (no copies).
template <typename T>
Eigen::Matrix<T, 3, 1> cross(const Eigen::Matrix<T, 3, 1>& a, const Eigen::Matrix<T, 3, 1>& b) {
  return {a(1) * b(2) - a(2) * b(1), a(2) * b(0) - a(0) * b(2), a(0) * b(1) - a(1) * b(0)};
}

// A symmetric 3x3 matrix by its 6 distinct entries.
template <typename T>
struct Sym3 {
  T xx, yy, zz, xy, xz, yz;

  // R diag(d) R^T
  static Sym3 rotated(const Eigen::Matrix<T, 3, 3>& R, const Eigen::Matrix<T, 3, 1>& d) {
    T Rd[3][3];  // R diag(d), formed once for the six entries
    for (int a = 0; a < 3; ++a) {
      for (int c = 0; c < 3; ++c) Rd[a][c] = R(a, c) * d(c);
    }
    auto e = [&](int a, int b) {
      return Rd[a][0] * R(b, 0) + Rd[a][1] * R(b, 1) + Rd[a][2] * R(b, 2);
    };
    return {e(0, 0), e(1, 1), e(2, 2), e(0, 1), e(0, 2), e(1, 2)};
  }
  Sym3& operator+=(const Sym3& o) {
    xx += o.xx, yy += o.yy, zz += o.zz, xy += o.xy, xz += o.xz, yz += o.yz;
    return *this;
  }
  // Moves the reference point of a body (or subtree) of mass m and first moment h about the old
  // point by d = old - new point (parallel axes):
  //   += (2 h.d + m |d|^2) E - (h d^T + d h^T + m d d^T) = (h.d + g.d) E - (h d^T + d g^T),
  // g = h + m d. From the CoM (h = 0) with d = r it adds m (|r|^2 E - r r^T).
  void add_shift(T m, const Eigen::Matrix<T, 3, 1>& h, const Eigen::Matrix<T, 3, 1>& d) {
    const Eigen::Matrix<T, 3, 1> g = h + m * d;
    const T tr = h.dot(d) + g.dot(d);
    xx += tr - (h(0) * d(0) + d(0) * g(0));
    yy += tr - (h(1) * d(1) + d(1) * g(1));
    zz += tr - (h(2) * d(2) + d(2) * g(2));
    xy -= h(0) * d(1) + d(0) * g(1);
    xz -= h(0) * d(2) + d(0) * g(2);
    yz -= h(1) * d(2) + d(1) * g(2);
  }
  // add_shift from the CoM (h = 0) to a point at d = r from it: += m (|r|^2 E - r r^T), as
  // (g.r) E - r g^T with g = m r. add_shift(m, 0, r)'s own sums less their products with h's
  // zeros (x + 0 = x, x - 0 = x): the same doubles, a zero's sign aside.
  void add_from_com(T m, const Eigen::Matrix<T, 3, 1>& r) {
    const Eigen::Matrix<T, 3, 1> g = m * r;
    const T tr = g.dot(r);
    xx += tr - r(0) * g(0);
    yy += tr - r(1) * g(1);
    zz += tr - r(2) * g(2);
    xy -= r(0) * g(1);
    xz -= r(0) * g(2);
    yz -= r(1) * g(2);
  }
  Eigen::Matrix<T, 3, 1> operator*(const Eigen::Matrix<T, 3, 1>& v) const {
    return {xx * v(0) + xy * v(1) + xz * v(2), xy * v(0) + yy * v(1) + yz * v(2),
            xz * v(0) + yz * v(1) + zz * v(2)};
  }
};

// True when R is a signed permutation (column c = sign[c] e_from[c]; exact comparisons: the
// shipped tree is built from exact 0 and +-1 entries); from and sign are then filled.
template <typename T>
bool signed_permutation(const Mat3& R, std::array<int, 3>& from, std::array<T, 3>& sign) {
  bool ok = true;
  for (int c = 0; c < 3; ++c) {
    int nonzero = 0;
    for (int rr = 0; rr < 3; ++rr) {
      const double v = R(rr, c);
      if (v == 0.0) continue;
      ++nonzero;
      ok = ok && (v == 1.0 || v == -1.0);
      from[c] = rr;
      sign[c] = T(v);
    }
    ok = ok && nonzero == 1;
  }
  return ok;
}

}  // namespace

template <typename T>
PhantomDynamics<T>::PhantomDynamics(const PhantomParams& params, bool specialise)
    : params_(params), reference_(params) {
  const PhantomTreeT<double>& tree = reference_.tree();
  for (int i = 0; i < kPhantomTreeDof; ++i) {
    const Mat3 S = phantom_detail::skew_t<double>(tree.axis[i]);
    Body& b = body_[i];
    b.A = tree.rot0[i].cast<T>();
    b.B = (tree.rot0[i] * S).cast<T>();
    b.D = (tree.rot0[i] * (S * S)).cast<T>();
    b.s = (tree.rot0[i] * tree.axis[i]).cast<T>();
    b.pos = tree.pos[i].cast<T>();
    b.com = tree.com[i].cast<T>();
    b.inertia = tree.inertia[i].cast<T>();
    b.mass = T(tree.mass[i]);
    // Signed permutation and coordinate axis? (anything else takes the general formula.)
    bool aligned = signed_permutation(tree.rot0[i], b.col_from, b.col_sign);
    int axis_nonzero = 0;
    for (int c = 0; c < 3; ++c) {
      const double v = tree.axis[i](c);
      if (v == 0.0) continue;
      ++axis_nonzero;
      aligned = aligned && (v == 1.0 || v == -1.0);
      b.k = c;
      b.axis_sign = T(v);
    }
    b.axis_aligned = aligned && axis_nonzero == 1;
    b.ci = (b.k + 1) % 3;
    b.cj = (b.k + 2) % 3;
    b.at_parent_origin = tree.pos[i].isZero(0.0);
  }
  tip_ = tree.tip.cast<T>();
  S_tip_ = phantom_detail::skew_t<double>(tree.tip);
  gimbal_at_point_ = tree.pos[kGimbalPitch].isZero(0.0) && tree.pos[kGimbalRoll].isZero(0.0);
  armature_ = tree.armature.cast<T>();
  damping_ = tree.damping.cast<T>();
  coulomb_ = tree.coulomb.cast<T>();
  coulomb_smoothing_ = tree.coulomb_smoothing.cast<T>();
  coulomb_sign_ = tree.coulomb_sign;
  gravity_ = T(tree.gravity);

  // The closed form's fit and constants (docs/derivations/phantom_closed_form.md §1-2), from the
  // reference's kinematics at q = 0: every body's rotation a signed column permutation turned
  // about a coordinate axis, the four arm bodies turning about -y of {B} through points in
  // {B}'s xz-plane, the base about z through the origin, the gimbal's joints at one point.
  // Exact comparisons: the shipped tree is built from exact 0 and +-1.
  const PhantomModelD::Kinematics k0 = reference_.kinematics(Vec6::Zero(), Vec6::Zero());
  bool fit = gimbal_at_point_ && k0.a[kBase] == Vec3::UnitZ() && k0.p[kBase].isZero(0.0) &&
             tree.com[kBase].allFinite();
  for (int i = 0; i < kPhantomTreeDof; ++i) fit = fit && body_[i].axis_aligned;
  constexpr std::array<int, 4> kArm = {kUpperArm, kForearm, kCrank, kParallelLink};
  for (int j = 0; j < 4; ++j) {
    const int i = kArm[j];
    fit = fit && k0.a[i] == -Vec3::UnitY() && k0.p[i](1) == 0.0;
    const Mat3 D = k0.R[i] * tree.inertia[i].asDiagonal() * k0.R[i].transpose();
    fit = fit && D.isDiagonal(0.0);
    const Vec3 rho = k0.R[i] * tree.com[i];
    ArmBody& b = arm_[j];
    b.m = T(tree.mass[i]);
    b.rx = T(rho(0)), b.ry = T(rho(1)), b.rz = T(rho(2));
    b.dx = T(D(0, 0)), b.dy = T(D(1, 1)), b.dz = T(D(2, 2));
    b.Kyy = T(D(1, 1) + tree.mass[i] * (rho(0) * rho(0) + rho(2) * rho(2)));
  }
  fit = fit && k0.p[kUpperArm].isZero(0.0) && k0.p[kCrank].isZero(0.0) &&
        k0.p[kGimbalYaw](1) == 0.0;
  const Vec3& c0 = tree.com[kBase];
  base_zz_ = T(tree.inertia[kBase](2) + tree.mass[kBase] * (c0(0) * c0(0) + c0(1) * c0(1)));
  const Vec3 E0 = k0.p[kForearm], P0 = k0.p[kParallelLink], F0 = k0.p[kGimbalYaw] - E0;
  E0x_ = T(E0(0)), E0z_ = T(E0(2)), P0x_ = T(P0(0)), P0z_ = T(P0(2));
  F0x_ = T(F0(0)), F0z_ = T(F0(2));
  E0sq_ = T(E0.squaredNorm()), P0sq_ = T(P0.squaredNorm()), F0sq_ = T(F0.squaredNorm());
  fit = signed_permutation(k0.R[kForearm], fore_from_, fore_sign_) && fit;
  closed_form_ = fit;
  // The shipped gimbal (terms_closed<true>): rot0 = E, axes +e_1, +e_0, +e_2 (yaw, pitch, roll).
  bool shipped = specialise && fit;
  for (int g = 0; g < 3; ++g) {
    const Body& b = body_[kGimbalYaw + g];
    shipped = shipped && b.k == kShippedGimbalAxis[g] && b.axis_sign == T(1);
    for (int c = 0; c < 3; ++c) shipped = shipped && b.col_from[c] == c && b.col_sign[c] == T(1);
  }
  for (int c = 0; c < 3; ++c) {
    shipped = shipped && fore_from_[c] == kShippedForearmFrom[c] &&
              fore_sign_[c] == T(kShippedForearmSign[c]);
  }
  shipped_gimbal_ = shipped;
}

template <typename T>
void PhantomDynamics<T>::terms(const Vec6& q, const Vec6& qd, bool with_jacobian_rate,
                               DeviceTerms& out) const {
  if (shipped_gimbal_) {
    terms_closed<true>(q, qd, with_jacobian_rate, out);
  } else if (closed_form_) {
    terms_closed<false>(q, qd, with_jacobian_rate, out);
  } else {
    terms_tree(q, qd, with_jacobian_rate, out);
  }
}

template <typename T>
void PhantomDynamics<T>::terms_tree(const Vec6& q_in, const Vec6& qd_in, bool with_jacobian_rate,
                                    DeviceTerms& out) const {
  constexpr int n = kPhantomTreeDof;
  const V6 q = q_in.cast<T>();
  const V6 qd = qd_in.cast<T>();
  const std::array<T, n> thd = {qd(0),         qd(1), qd(2) - qd(1), qd(2),
                                qd(1) - qd(2), qd(3), qd(4),         qd(5)};
  // Sines and cosines of theta = G q: theta_2 = q3 - q2 by the angle-difference formulas,
  // theta_4 = -theta_2.
  std::array<T, n> sn, cs;
  const std::array<int, 6> device_body = {kBase,      kUpperArm,    kCrank,
                                          kGimbalYaw, kGimbalPitch, kGimbalRoll};
  for (int j = 0; j < 6; ++j) {
    sn[device_body[j]] = std::sin(q(j));
    cs[device_body[j]] = std::cos(q(j));
  }
  sn[kForearm] = sn[kCrank] * cs[kUpperArm] - cs[kCrank] * sn[kUpperArm];
  cs[kForearm] = cs[kCrank] * cs[kUpperArm] + sn[kCrank] * sn[kUpperArm];
  sn[kParallelLink] = -sn[kForearm];
  cs[kParallelLink] = cs[kForearm];

  // 1. Forward sweep: kinematics (header section 1).
  std::array<M3, n> R;
  std::array<V3, n> p, a, r, w, vo, vc;
#pragma GCC unroll 8
  for (int i = 0; i < n; ++i) {
    const Body& b = body_[i];
    const int par = kParent[i];
    if (b.axis_aligned) {
      M3& Ri = R[i];  // R_par rot0: signed column permutation of R_par (E at the root)
      for (int c = 0; c < 3; ++c) {
        if (par < 0) {
          Ri.col(c) = b.col_sign[c] * M3::Identity().col(b.col_from[c]);
        } else {
          Ri.col(c) = b.col_sign[c] * R[par].col(b.col_from[c]);
        }
      }
      a[i] = b.axis_sign * Ri.col(b.k);
      const int ci = (b.k + 1) % 3, cj = (b.k + 2) % 3;
      const T st = b.axis_sign * sn[i];
      const V3 col_i = Ri.col(ci);
      Ri.col(ci) = cs[i] * col_i + st * Ri.col(cj);
      Ri.col(cj) = cs[i] * Ri.col(cj) - st * col_i;
    } else {
      const M3 local = b.A + sn[i] * b.B + (T(1) - cs[i]) * b.D;
      if (par < 0) {
        R[i] = local;
        a[i] = b.s;
      } else {
        R[i].noalias() = R[par] * local;
        a[i].noalias() = R[par] * b.s;
      }
    }
    if (par < 0) {
      p[i] = b.pos;
      w[i] = a[i] * thd[i];
      vo[i].setZero();
    } else if (b.at_parent_origin) {
      p[i] = p[par];
      w[i] = w[par] + a[i] * thd[i];
      vo[i] = vo[par];
    } else {
      const V3 d = R[par] * b.pos;
      p[i] = p[par] + d;
      w[i] = w[par] + a[i] * thd[i];
      vo[i] = vo[par] + cross(w[par], d);
    }
    r[i].noalias() = R[i] * b.com;
    vc[i] = vo[i] + cross(w[i], r[i]);
  }

  // 2. Backward sweep: composite bodies about their joint points (header section 2). The
  // symmetric inertias are kept as their 6 distinct entries (Sym3).
  std::array<T, n> m;
  std::array<V3, n> h, P, L;
  std::array<Sym3<T>, n> K;
#pragma GCC unroll 8
  for (int i = 0; i < n; ++i) {
    const Body& b = body_[i];
    const Sym3<T> I = Sym3<T>::rotated(R[i], b.inertia);  // R diag(I) R^T
    m[i] = b.mass;
    h[i] = b.mass * r[i];
    P[i] = b.mass * vc[i];
    L[i] = cross(r[i], P[i]) + I * w[i];
    K[i] = I;
    K[i].add_from_com(b.mass, r[i]);  // from the CoM to the joint point
  }
#pragma GCC unroll 8
  for (int k = n - 1; k > 0; --k) {  // children have larger indices than their parents
    const int j = kParent[k];
    K[j] += K[k];
    if (body_[k].at_parent_origin) {
      h[j] += h[k];
      L[j] += L[k];
    } else {
      const V3 d = p[k] - p[j];
      K[j].add_shift(m[k], h[k], d);
      h[j] += h[k] + m[k] * d;
      L[j] += L[k] + cross(d, P[k]);
    }
    m[j] += m[k];
    P[j] += P[k];
  }

  // 3. Tree terms (header section 3). M_tree(j, k) = a_k . (n_j - p_k x u_j) = a_k . n_j
  // + u_j . (p_k x a_k) with n_j = K_j a_j + p_j x u_j: the moment about the world origin
  // (spatial force of the unit rate) against the Pluecker coordinates of axis k.
  std::array<T, n> gt, ct;
  std::array<V3, n> u, nj, mk;
  T t[n][n];  // lower triangle (k <= j) of M_tree on ancestor pairs
#pragma GCC unroll 8
  for (int j = 0; j < n; ++j) {
    u[j] = cross(a[j], h[j]);
    const V3 F = K[j] * a[j];
    nj[j] = F + cross(p[j], u[j]);
    mk[j] = cross(p[j], a[j]);
    gt[j] = gravity_ * u[j](2);
    ct[j] = cross(w[j], a[j]).dot(L[j]) - a[j].dot(cross(vo[j], P[j]));
    t[j][j] = a[j].dot(F);
#pragma GCC unroll 8
    for (int k = kParent[j]; k >= 0; k = kParent[k]) t[j][k] = a[k].dot(nj[j]) + u[j].dot(mk[k]);
  }
  // M = G^T M_tree G + diag(armature), written out; pairs of unrelated joints (crank or parallel
  // link with upper arm, forearm or gimbal) are zero and left out. Lower triangle, mirrored.
  constexpr int b0 = kBase, b1 = kUpperArm, b2 = kForearm, b3 = kCrank, b4 = kParallelLink,
                b5 = kGimbalYaw, b6 = kGimbalPitch, b7 = kGimbalRoll;
  // clang-format off
  const T lower[21] = {
      t[b0][b0],                                                                  // (0, 0)
      t[b1][b0] - t[b2][b0] + t[b4][b0],                                          // (1, 0)
      t[b2][b0] + t[b3][b0] - t[b4][b0],                                          // (2, 0)
      t[b5][b0], t[b6][b0], t[b7][b0],                                            // (3..5, 0)
      t[b1][b1] + t[b2][b2] - T(2) * t[b2][b1] + t[b4][b4],                       // (1, 1)
      t[b2][b1] - t[b2][b2] + t[b4][b3] - t[b4][b4],                              // (2, 1)
      t[b5][b1] - t[b5][b2], t[b6][b1] - t[b6][b2], t[b7][b1] - t[b7][b2],        // (3..5, 1)
      t[b2][b2] + t[b3][b3] + t[b4][b4] - T(2) * t[b4][b3],                       // (2, 2)
      t[b5][b2], t[b6][b2], t[b7][b2],                                            // (3..5, 2)
      t[b5][b5], t[b6][b5], t[b7][b5],                                            // (3..5, 3)
      t[b6][b6], t[b7][b6],                                                       // (4..5, 4)
      t[b7][b7]};                                                                 // (5, 5)
  // clang-format on
  for (int c = 0, e = 0; c < 6; ++c) {
    for (int rr = c; rr < 6; ++rr, ++e) {
      out.M(rr, c) = double(lower[e]);
      out.M(c, rr) = out.M(rr, c);
    }
    out.M(c, c) += double(armature_(c));
  }
  out.g = tree_to_joint(gt).template cast<double>();
  out.CTqd = tree_to_joint(ct).template cast<double>();
  for (int j = 0; j < 6; ++j) {
    out.tau_f(j) =
        double(phantom_joint_friction(damping_(j), coulomb_(j), coulomb_smoothing_(j), qd(j),
                                      coulomb_sign_[j]));
  }

  // 4. Tool pose, J_t and dJ_t/dt (header section 4).
  constexpr int kTipChain[6] = {kBase, kUpperArm, kForearm, kGimbalYaw, kGimbalPitch, kGimbalRoll};
  const M3& R1 = R[kGimbalRoll];
  const V3 x1 = p[kGimbalRoll] + R1 * tip_;
  out.pose.x = x1.template cast<double>();
  out.pose.R = R1.template cast<double>();
  Eigen::Matrix<T, 6, 6> Jc;  // tree columns of the tip chain, in kTipChain order
  for (int c = 0; c < 6; ++c) {
    const int j = kTipChain[c];
    Jc.col(c).template head<3>() = cross(a[j], x1 - p[j]);
    Jc.col(c).template tail<3>().noalias() = R1.transpose() * a[j];
  }
  tip_chain_to_joint(Jc, out.J_t);
  if (with_jacobian_rate) {
    const V3& w1 = w[kGimbalRoll];
    const V3 xd1 = vo[kGimbalRoll] + cross(w1, x1 - p[kGimbalRoll]);
    for (int c = 0; c < 6; ++c) {
      const int j = kTipChain[c];
      const V3 da = cross(w[j], a[j]);
      Jc.col(c).template head<3>() = cross(da, x1 - p[j]) + cross(a[j], xd1 - vo[j]);
      Jc.col(c).template tail<3>().noalias() = R1.transpose() * (da - cross(w1, a[j]));
    }
    tip_chain_to_joint(Jc, out.J_t_dot);
  } else {
    out.J_t_dot.setZero();
  }
}

// The closed form (docs/derivations/phantom_closed_form.md; the section numbers below are its).
// Everything is evaluated in the base frame {B} at q1 = 0: M, C^T qd and g do not depend on q1
// (the yaw turns about gravity's axis), and the world-frame rows of the pose, J_t and dJ_t/dt are
// {B}'s turned by Rz(q1) (§6).
template <typename T>
template <bool Shipped>
void PhantomDynamics<T>::terms_closed(const Vec6& q_in, const Vec6& qd_in,
                                      bool with_jacobian_rate, DeviceTerms& out) const {
  using std::cos;
  using std::sin;
  const V6 q = q_in.cast<T>();
  const V6 qd = qd_in.cast<T>();
  const T s1 = sin(q(0)), c1 = cos(q(0)), s2 = sin(q(1)), c2 = cos(q(1)), s3 = sin(q(2)),
          c3 = cos(q(2));
  const T qd1 = qd(0), qd2 = qd(1), qd3 = qd(2);

  // §2 The arm's points: rot(phi) (x, z) = (c x - s z, s x + c z); d/dphi of it = (-z', x').
  const T Ex = c2 * E0x_ - s2 * E0z_, Ez = s2 * E0x_ + c2 * E0z_;  // elbow
  const T Px = c3 * P0x_ - s3 * P0z_, Pz = s3 * P0x_ + c3 * P0z_;  // parallel link's pivot
  const T fx = c3 * F0x_ - s3 * F0z_, fz = s3 * F0x_ + c3 * F0z_;  // elbow to gimbal centre
  const T Cx = Ex + fx, Cz = Ez + fz;                               // gimbal centre
  // §3 Velocities: Omega_A = (0, -qd2, qd1) (upper arm, parallel link), Omega_B = (0, -qd3, qd1)
  // (forearm, crank, and the gimbal's carrier).
  const V3 vE(-qd2 * Ez, qd1 * Ex, qd2 * Ex);
  const V3 vP(-qd3 * Pz, qd1 * Px, qd3 * Px);
  const V3 vC(vE(0) - qd3 * fz, vE(1) + qd1 * fx, vE(2) + qd3 * fx);

  // §2-3 One arm body at angle (c, s), pivot velocity vo, angular velocity (0, wy, qd1): its
  // first moment h about the pivot, the zz and yz entries of its inertia K about the pivot, its
  // momentum P and the x component of its angular momentum about the pivot.
  struct Arm {
    T hx, hy, hz, Kzz, Kyz, Px, Py, Pz, Lx;
  };
  auto arm = [qd1](const ArmBody& b, T c, T s, const V3& vo, T wy) {
    const T rx = c * b.rx - s * b.rz, rz = s * b.rx + c * b.rz;
    const T Izz = s * s * b.dx + c * c * b.dz, Ixz = c * s * (b.dx - b.dz);
    Arm a;
    a.hx = b.m * rx, a.hy = b.m * b.ry, a.hz = b.m * rz;
    a.Kzz = Izz + b.m * (rx * rx + b.ry * b.ry);
    a.Kyz = -a.hy * rz;
    a.Px = b.m * vo(0) + (wy * a.hz - qd1 * a.hy);  // m (vo + w x r)
    a.Py = b.m * vo(1) + qd1 * a.hx;
    a.Pz = b.m * vo(2) - wy * a.hx;
    a.Lx = b.ry * a.Pz - rz * a.Py + Ixz * qd1;  // (r x P + I w)_x
    return a;
  };
  const V3 zero = V3::Zero();
  const Arm A1 = arm(arm_[0], c2, s2, zero, -qd2);  // upper arm, pivot O
  const Arm A2 = arm(arm_[1], c3, s3, vE, -qd3);    // forearm, pivot E
  const Arm A3 = arm(arm_[2], c3, s3, zero, -qd3);  // crank, pivot O
  const Arm A4 = arm(arm_[3], c2, s2, vP, -qd2);    // parallel link, pivot P

  // §4 The gimbal about its centre C: rotations by column turns from the forearm's, composites
  // (mass, first moment h, inertia K) and momenta of the subtrees of yaw, pitch and roll.
  M3 R[3];
  V3 a[3], w[3];
  {
    V3 wpar(T(0), -qd3, qd1);
    M3 RB;  // the forearm's orientation Ry(-q3) F, F a signed permutation
    int g0 = 0;  // the first gimbal body the loop below turns
    if constexpr (Shipped) {
      // The shipped forearm, F = (e_y, -e_z, -e_x) (kShippedForearmFrom, kShippedForearmSign):
      // RB = (e_y, (s3, 0, -c3), (-c3, 0, -s3)), and yaw turns its columns 2 and 0 about its
      // column 1. The loop's products with RB's exact 0 and 1 left out: the same doubles, a
      // zero's sign aside.
      const T sn = sin(q(3)), cs = cos(q(3)), qd4 = qd(3);
      R[0].col(0) = V3(sn * c3, cs, sn * s3);
      R[0].col(1) = V3(s3, T(0), -c3);
      R[0].col(2) = V3(-(cs * c3), sn, -(cs * s3));
      a[0] = R[0].col(1);
      w[0] = V3(s3 * qd4, -qd3, qd1 - c3 * qd4);
      wpar = w[0];
      g0 = 1;
    } else {
      for (int c = 0; c < 3; ++c) {
        const int from = fore_from_[c];
        const T sg = fore_sign_[c];
        if (from == 0) {
          RB.col(c) = V3(sg * c3, T(0), sg * s3);
        } else if (from == 1) {
          RB.col(c) = V3(T(0), sg, T(0));
        } else {
          RB.col(c) = V3(-sg * s3, T(0), sg * c3);
        }
      }
    }
#pragma GCC unroll 3
    for (int g = g0; g < 3; ++g) {
      const Body& b = body_[kGimbalYaw + g];
      const M3& Rp = g == 0 ? RB : R[g - 1];
      M3& Ri = R[g];
      const T sn = sin(q(3 + g)), cs = cos(q(3 + g));
      int ci, cj;
      T st;
      if constexpr (Shipped) {  // rot0 = E, axis +e_k: the multiplications by +1 left out
        constexpr std::array<int, 3> kCi = {2, 1, 0}, kCj = {0, 2, 1};  // (k + 1, k + 2) % 3
        Ri = Rp;
        a[g] = Ri.col(kShippedGimbalAxis[g]);
        ci = kCi[g], cj = kCj[g];
        st = sn;
      } else {
        for (int c = 0; c < 3; ++c) Ri.col(c) = b.col_sign[c] * Rp.col(b.col_from[c]);
        a[g] = b.axis_sign * Ri.col(b.k);
        ci = b.ci, cj = b.cj;
        st = b.axis_sign * sn;
      }
      const V3 col_i = Ri.col(ci);
      Ri.col(ci) = cs * col_i + st * Ri.col(cj);
      Ri.col(cj) = cs * Ri.col(cj) - st * col_i;
      w[g] = wpar + a[g] * qd(3 + g);
      wpar = w[g];
    }
  }
  T mg[3];
  V3 h[3], P[3], L[3];
  Sym3<T> K[3];
  for (int g = 2; g >= 0; --g) {  // roll, pitch, yaw: a subtree is its body and the one below
    const Body& b = body_[kGimbalYaw + g];
    const V3 r = R[g] * b.com;
    const Sym3<T> I = Sym3<T>::rotated(R[g], b.inertia);
    const V3 Pi = b.mass * (vC + cross(w[g], r));
    K[g] = I;
    K[g].add_from_com(b.mass, r);
    mg[g] = b.mass;
    h[g] = b.mass * r;
    P[g] = Pi;
    L[g] = cross(r, Pi) + I * w[g];
    if (g < 2) {
      K[g] += K[g + 1];
      mg[g] += mg[g + 1];
      h[g] += h[g + 1];
      P[g] += P[g + 1];
      L[g] += L[g + 1];
    }
  }

  // §5 M: the arm block from the four arm bodies, the base and the gimbal as one body at C; the
  // gimbal's rows from its subtrees (F_j = K_j a_j, u_j = a_j x h_j).
  const Sym3<T>& KG = K[0];
  const V3& hG = h[0];
  const T m00 = base_zz_ + A1.Kzz + A3.Kzz + arm_[1].m * Ex * Ex + T(2) * Ex * A2.hx + A2.Kzz +
                arm_[3].m * Px * Px + T(2) * Px * A4.hx + A4.Kzz + mg[0] * Cx * Cx +
                T(2) * Cx * hG(0) + KG.zz;
  const T m10 = -A1.Kyz + Ez * A2.hy - A4.Kyz + Ez * hG(1);
  const T m20 = -A3.Kyz - A2.Kyz + Pz * A4.hy + fz * hG(1) - KG.yz;
  const T m11 = arm_[0].Kyy + arm_[1].m * E0sq_ + arm_[3].Kyy + mg[0] * E0sq_;
  const T m21 = Ez * A2.hz + Ex * A2.hx + Pz * A4.hz + Px * A4.hx +
                mg[0] * (Ez * fz + Ex * fx) + Ez * hG(2) + Ex * hG(0);
  const T m22 = arm_[2].Kyy + arm_[1].Kyy + arm_[3].m * P0sq_ + mg[0] * F0sq_ +
                T(2) * (fz * hG(2) + fx * hG(0)) + KG.yy;
  out.M(0, 0) = double(m00);
  out.M(1, 0) = double(m10);
  out.M(2, 0) = double(m20);
  out.M(1, 1) = double(m11);
  out.M(2, 1) = double(m21);
  out.M(2, 2) = double(m22);
  V3 F[3], u[3];
  for (int j = 0; j < 3; ++j) {
    F[j] = K[j] * a[j];
    u[j] = cross(a[j], h[j]);
    out.M(3 + j, 0) = double(Cx * u[j](1) + F[j](2));
    out.M(3 + j, 1) = double(Ex * u[j](2) - Ez * u[j](0));
    out.M(3 + j, 2) = double(fx * u[j](2) - fz * u[j](0) - F[j](1));
    for (int k = 0; k <= j; ++k) out.M(3 + j, 3 + k) = double(a[k].dot(F[j]));
  }
  for (int c = 0; c < 6; ++c) {
    for (int rr = c + 1; rr < 6; ++rr) out.M(c, rr) = out.M(rr, c);
    out.M(c, c) += double(armature_(c));
  }

  // §5 g = dV/dq, V = |g| sum m z_c.
  out.g(0) = 0.0;
  out.g(1) = double(gravity_ * (A1.hx + arm_[1].m * Ex + A4.hx + mg[0] * Ex));
  out.g(2) = double(gravity_ * (A3.hx + A2.hx + arm_[3].m * Px + mg[0] * fx + hG(0)));
  for (int j = 0; j < 3; ++j) out.g(3 + j) = double(gravity_ * u[j](2));

  // §5 C^T qd = dT/dq by the subtrees' momenta (header section 3's tree formula).
  const T P2x = A2.Px + P[0](0), P2y = A2.Py + P[0](1), P2z = A2.Pz + P[0](2);
  const T L2x = A2.Lx + L[0](0) - fz * P[0](1);  // forearm's subtree about E
  const T ct2 = qd1 * L2x + (vE(2) * P2x - vE(0) * P2z);
  const T ct1 = qd1 * (A1.Lx + L2x - Ez * P2y);
  const T ct4 = qd1 * A4.Lx + (vP(2) * A4.Px - vP(0) * A4.Pz);
  const T ct3 = qd1 * (A3.Lx + A4.Lx - Pz * A4.Py);
  out.CTqd(0) = 0.0;
  out.CTqd(1) = double(ct1 - ct2 + ct4);
  out.CTqd(2) = double(ct2 + ct3 - ct4);
  for (int j = 0; j < 3; ++j) {
    out.CTqd(3 + j) = double(cross(w[j], a[j]).dot(L[j]) - a[j].dot(cross(vC, P[j])));
  }
  for (int j = 0; j < 6; ++j) {
    out.tau_f(j) =
        double(phantom_joint_friction(damping_(j), coulomb_(j), coulomb_smoothing_(j), qd(j),
                                      coulomb_sign_[j]));
  }

  // §6 Pose and J_t in {B}; the world rows turned by Rz(q1).
  const M3& R1 = R[2];
  const V3 rt = R1 * tip_;  // C to the tip
  const V3 x1(Cx + rt(0), rt(1), Cz + rt(2));
  auto yaw = [c1, s1](T x, T y) { return std::array<double, 2>{double(c1 * x - s1 * y),
                                                              double(s1 * x + c1 * y)}; };
  {
    const auto xy = yaw(x1(0), x1(1));
    out.pose.x = Vec3(xy[0], xy[1], double(x1(2)));
    for (int c = 0; c < 3; ++c) {
      const auto rc = yaw(R1(0, c), R1(1, c));
      out.pose.R(0, c) = rc[0], out.pose.R(1, c) = rc[1], out.pose.R(2, c) = double(R1(2, c));
    }
  }
  // Column c of J (J_t or dJ_t/dt) from its {B} entries, turned and written in place (no 6x6 in
  // between).
  auto put = [&](Mat6& J, int c, T vx, T vy, T vz, T wx, T wy, T wz) {
    const auto xy = yaw(vx, vy);
    J(0, c) = xy[0], J(1, c) = xy[1], J(2, c) = double(vz);
    J(3, c) = double(wx), J(4, c) = double(wy), J(5, c) = double(wz);
  };
  auto put6 = [&](Mat6& J, int c, const V6& v) { put(J, c, v(0), v(1), v(2), v(3), v(4), v(5)); };
  put(out.J_t, 0, -x1(1), x1(0), T(0), R1(2, 0), R1(2, 1), R1(2, 2));  // z x x1, R1^T z
  put(out.J_t, 1, -Ez, T(0), Ex, T(0), T(0), T(0));                     // dE/dq2
  put(out.J_t, 2, -(x1(2) - Ez), T(0), x1(0) - Ex, -R1(1, 0), -R1(1, 1),
      -R1(1, 2));  // -y x (x1 - E)
  for (int j = 0; j < 3; ++j) {
    const V3 v = cross(a[j], rt);
    put(out.J_t, 3 + j, v(0), v(1), v(2), R1.col(0).dot(a[j]), R1.col(1).dot(a[j]),
        R1.col(2).dot(a[j]));
  }
  if (!with_jacobian_rate) {
    out.J_t_dot.setZero();
    return;
  }
  // dJ_t/dt: header section 4's columns at q1 = 0, then turned (§6).
  Mat6& dJ = out.J_t_dot;
  const V3& w1 = w[2];
  const V3 xd1 = vC + cross(w1, rt);
  const V3 ey(T(0), T(1), T(0)), ez(T(0), T(0), T(1));
  const V3 OA(T(0), -qd2, qd1), OB(T(0), -qd3, qd1), E(Ex, T(0), Ez), C(Cx, T(0), Cz);
  auto col = [&](const V3& aj, const V3& wj, const V3& pj, const V3& voj) {
    const V3 da = cross(wj, aj);
    const V3 xp = x1 - pj, xv = xd1 - voj, dv = cross(da, xp), av = cross(aj, xv);
    const V3 dw = da - cross(w1, aj);
    V6 v;
    v << dv(0) + av(0), dv(1) + av(1), dv(2) + av(2), R1.col(0).dot(dw), R1.col(1).dot(dw),
        R1.col(2).dot(dw);
    return v;
  };
  if constexpr (Shipped) {
    // The arm's three columns with the known zeros of their axes (ez, -ey), the arm's angular
    // velocities (0, *, qd1) and points (y = 0) left out: the same products and sums as col()'s
    // on the entries that are not zero, so the same doubles (a zero's sign aside).
    // Column 0: a = ez, w = (0, 0, qd1): w x a = 0, so dv = 0, av = ez x xd1, dw = -(w1 x ez).
    // Columns A (q2's upper arm, about O) and B (q3's forearm, about E): a = -ey, w = (0, *, qd1),
    // w x a = (qd1, 0, 0), dw = (qd1 - w1_z, 0, w1_x) in both, so their difference's angular rows
    // are zero.
    const V3 xv = xd1 - vE;
    const T xp2 = x1(2) - Ez;
    const T dwx = qd1 - w1(2);
    T ang0[3], ang2[3];
    for (int c = 0; c < 3; ++c) {
      ang0[c] = R1(0, c) * -w1(1) + R1(1, c) * w1(0);
      ang2[c] = R1(0, c) * dwx + R1(2, c) * w1(0);
    }
    const T z2 = qd1 * x1(1) + xv(0);
    put(dJ, 0, -xd1(1), xd1(0), T(0), ang0[0], ang0[1], ang0[2]);
    put(dJ, 1, -xd1(2) + xv(2), qd1 * xp2 - qd1 * x1(2), (qd1 * x1(1) + xd1(0)) - z2, T(0), T(0),
        T(0));
    put(dJ, 2, -xv(2), -(qd1 * xp2), z2, ang2[0], ang2[1], ang2[2]);
  } else {
    put6(dJ, 0, col(ez, V3(T(0), T(0), qd1), zero, zero));
    put6(dJ, 1, col(-ey, OA, zero, zero) - col(-ey, OB, E, vE));
    put6(dJ, 2, col(-ey, OB, E, vE));
  }
  for (int j = 0; j < 3; ++j) put6(dJ, 3 + j, col(a[j], w[j], C, vC));
}

namespace {

// A^-1 by the adjugate (cofactors over the determinant); a zero determinant gives a non-finite
// inverse.
Mat3 inverse3(const Mat3& a) {
  Mat3 adj;  // adj(i, j) = cofactor (j, i)
  adj(0, 0) = a(1, 1) * a(2, 2) - a(1, 2) * a(2, 1);
  adj(1, 0) = a(1, 2) * a(2, 0) - a(1, 0) * a(2, 2);
  adj(2, 0) = a(1, 0) * a(2, 1) - a(1, 1) * a(2, 0);
  adj(0, 1) = a(0, 2) * a(2, 1) - a(0, 1) * a(2, 2);
  adj(1, 1) = a(0, 0) * a(2, 2) - a(0, 2) * a(2, 0);
  adj(2, 1) = a(0, 1) * a(2, 0) - a(0, 0) * a(2, 1);
  adj(0, 2) = a(0, 1) * a(1, 2) - a(0, 2) * a(1, 1);
  adj(1, 2) = a(0, 2) * a(1, 0) - a(0, 0) * a(1, 2);
  adj(2, 2) = a(0, 0) * a(1, 1) - a(0, 1) * a(1, 0);
  const double det = a(0, 0) * adj(0, 0) + a(0, 1) * adj(1, 0) + a(0, 2) * adj(2, 0);
  if (!(det != 0.0)) return Mat3::Constant(std::numeric_limits<double>::quiet_NaN());
  return adj * (1.0 / det);
}

}  // namespace

template <typename T>
bool PhantomDynamics<T>::jacobian_inverse(const Mat6& J_t, const Mat3& R1, Mat6* J1) const {
  if (!gimbal_at_point_) return false;
  // Section 6 of the header.
  Mat3 P;
  P.noalias() = R1 * S_tip_;
  const auto Aw = J_t.bottomLeftCorner<3, 3>();
  Mat3 Vc = J_t.topLeftCorner<3, 3>();
  Vc.noalias() += P * Aw;
  const Mat3 X = inverse3(Vc);
  const Mat3 Y = inverse3(J_t.bottomRightCorner<3, 3>());
  Mat3 AwX, Z;
  AwX.noalias() = Aw * X;
  Z.noalias() = -Y * AwX;
  J1->topLeftCorner<3, 3>() = X;
  J1->topRightCorner<3, 3>().noalias() = X * P;
  J1->bottomLeftCorner<3, 3>() = Z;
  J1->bottomRightCorner<3, 3>() = Y;
  J1->bottomRightCorner<3, 3>().noalias() += Z * P;
  return true;
}

template <typename T>
DeviceTerms PhantomDynamics<T>::terms_at(const VecX& q, const Vec6& qd) const {
  DeviceTerms t;
  terms(phantom_vec6(q, "q"), qd, false, t);
  return t;
}

template <typename T>
MatX PhantomDynamics<T>::mass_matrix(const VecX& q) const {
  return terms_at(q, Vec6::Zero()).M;
}

template <typename T>
MatX PhantomDynamics<T>::coriolis_matrix(const VecX& q, const VecX& qd) const {
  return reference_.C(phantom_vec6(q, "q"), phantom_vec6(qd, "qd"));
}

template <typename T>
VecX PhantomDynamics<T>::gravity(const VecX& q) const {
  return terms_at(q, Vec6::Zero()).g;
}

template <typename T>
bool PhantomDynamics<T>::joint_friction_coefficients(Vec6* b, Vec6* f_c) const {
  *b = params_.damping_n_m_s_per_rad;
  *f_c = params_.coulomb_n_m;
  return true;
}

template <typename T>
VecX PhantomDynamics<T>::friction_torque(const VecX& q, const VecX& qd) const {
  return terms_at(q, phantom_vec6(qd, "qd")).tau_f;
}

template <typename T>
Pose PhantomDynamics<T>::forward_kinematics(const VecX& q) const {
  return terms_at(q, Vec6::Zero()).pose;
}

template <typename T>
Mat6 PhantomDynamics<T>::twist_to_joint(const VecX& q) const {
  return terms_at(q, Vec6::Zero()).J_t.partialPivLu().inverse();  // (2.2)
}

template class PhantomDynamics<double>;
template class PhantomDynamics<float>;

}  // namespace dentsim::fast
