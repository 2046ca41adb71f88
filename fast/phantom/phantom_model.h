// The Phantom's device terms in one pass, specialised to its 8-body tree (issue #14): the fast
// twin of reference/phantom/phantom_model.h (same PhantomParams, same tree, same quantities; it
// differs from the reference only by round-off, tests/fast/phantom_model_test.cc).
//
// Two evaluations, chosen once at construction (closed_form()): the closed form of
// docs/derivations/phantom_closed_form.md (the base frame at q1 = 0, the four arm bodies as
// scalars turning about one axis, the gimbal as composites at its centre; no tree sweep, the
// mass matrix's zero pairs never formed) for every file with that structure (the shipped one),
// and the tree sweeps below (sections 1-5) for any other file. Both pinned against the reference
// by tests/fast/phantom_model_test.cc; the closed form also against MuJoCo's model.
//
// Coordinates and tree as in the reference: q = (q1..q6) [rad], tree angles theta = G q with
//     theta = (q1, q2, q3 - q2, q3, q2 - q3, q4, q5, q6),
// bodies 0 base, 1 upper arm, 2 forearm, 3 crank, 4 parallel link, 5..7 gimbal yaw, pitch, roll,
// parents (-, 0, 1, 0, 3, 2, 5, 6). Every vector below is in the world frame {O}; units SI.
//
// 1. Kinematics, one forward sweep (parents first). With the constants of body i precomputed at
//    construction (A_i = rot0_i, its axis s_i = rot0_i axis_i, B_i = rot0_i S(axis_i),
//    D_i = rot0_i S(axis_i)^2; Rodrigues: rot0 Rot(axis, th) = A + sin(th) B + (1 - cos(th)) D):
//        R_i = R_par (A_i + sin th_i B_i + (1 - cos th_i) D_i),   a_i = R_par s_i,
//        p_i = p_par + R_par pos_i,   r_i = R_i com_i (CoM from the joint point),
//        w_i = w_par + a_i thd_i,   vo_i = vo_par + w_par x (p_i - p_par),
//        vc_i = vo_i + w_i x r_i.
//    For the bodies whose rot0 is a signed permutation and whose axis is a coordinate axis +-e_k
//    (all of them with the shipped parameters), R_par rot0 is a signed column permutation of
//    R_par and Rot turns two of its columns: 12 multiplications instead of 45.
//    theta_4 = -theta_2 exactly, so its sine and cosine are reused, and theta_2 = q3 - q2 comes
//    from the angle-difference formulas: 6 sin/cos pairs, not 8. Bodies hinged at their parent's
//    origin (base, upper arm and crank; the gimbal bodies when pitch_pos = roll_pos = 0) skip
//    the terms with pos (and in section 2 the shift by d = 0).
//
// 2. Composite bodies, one backward sweep (children first). For the subtree S(j) of joint j,
//    about its joint point p_j: mass m_j, first moment h_j = sum m_i (c_i - p_j), rotational
//    inertia K_j = sum I_i + m_i (|c_i - p_j|^2 E - (c_i - p_j)(c_i - p_j)^T) (I_i = R_i I R_i^T),
//    linear momentum P_j = sum m_i vc_i and angular momentum L_j = sum m_i (c_i - p_j) x vc_i
//    + I_i w_i. A child k is merged into its parent j with d = p_k - p_j (parallel-axis shift):
//        K_j += K_k + (2 h_k.d + m_k |d|^2) E - h_k d^T - d h_k^T - m_k d d^T,
//        h_j += h_k + m_k d,   m_j += m_k,   P_j += P_k,   L_j += L_k + d x P_k
//    (symmetric inertias stored as their 6 distinct entries).
//
// 3. Tree terms from the composites (the reference's Jacobian sums, regrouped per subtree):
//    - M_tree (composite-rigid-body algorithm): a unit rate of joint j moves S(j) with momentum
//      u_j = a_j x h_j and angular momentum K_j a_j about p_j, so for k an ancestor of j or j
//          M_tree(j, k) = a_k . (K_j a_j + (p_j - p_k) x u_j)   (0 for unrelated joints)
//                       = a_k . n_j + u_j . (p_k x a_k),   n_j = K_j a_j + p_j x u_j
//      (the unit rate's moment about the origin against the Pluecker coordinates of axis k: two
//      dot products per pair).
//    - g_tree(j) = |g| sum m_i (a_j x (c_i - p_j))_z = |g| (u_j)_z.
//    - C^T qd: with the reference's C_tree = sum_i m_i Jv_i^T dJv_i + Jw_i^T (I_i dJw_i
//      + S(w_i) I_i Jw_i), Jv_i thd = vc_i, Jw_i thd = w_i and w.(w x x) = 0,
//          (C_tree^T thd)_j = (w_j x a_j) . L_j - a_j . (vo_j x P_j).
//      C^T qd is the same for every factorisation with dM/dt = C + C^T: it equals
//      dM/dt qd - C qd = d/dq (1/2 qd^T M qd) (Lagrange), which the tests check.
//    Joint space (device_model.h): M = G^T M_tree G + diag(armature) (written out entry by
//    entry, zero pairs left out), C^T qd = G^T (C_tree^T thd), g = G^T g_tree, with
//    G^T v = (v0, v1 - v2 + v4, v2 + v3 - v4, v5, v6, v7).
//
// 4. Tool (thesis (2.2)): x1 = p_7 + R_7 tip, R1 = R_7; for the tip's ancestors j in
//    {0, 1, 2, 5, 6, 7}: J_tree col j = [a_j x (x1 - p_j); R1^T a_j], J_t = J_tree G; along qd
//    (xd1 = vo_7 + w_7 x (x1 - p_7)):
//        dJ col j = [(w_j x a_j) x (x1 - p_j) + a_j x (xd1 - vo_j); R1^T (w_j x a_j - w_7 x a_j)].
//
// 5. tau_f: the reference's law, phantom_joint_friction (reference/phantom/phantom_model.h).
//
// 6. J1 = J_t^-1 on the Jacobian's block structure (jacobian_inverse), when the gimbal's three
//    joints sit at one point p_c (pitch_pos = roll_pos = 0, as shipped). With r = x1 - p_c
//    = R1 tip, every column of J_t = [Jv; Jw] (Jw in the tool frame) is the velocity vc of p_c
//    plus the turn about it: Jv = vc + (R1 Jw) x r = vc - P Jw, P = S(r) R1 = R1 S(tip); the
//    gimbal's columns move p_c not at all. In 3x3 blocks (arm q1..q3 | gimbal q4..q6):
//        J_t = [I -P; 0 I] [Vc 0; Aw Gw],   Vc = Av + P Aw  (the velocity Jacobian of p_c),
//        J1 = [X  X P; Z  Z P + Y],   X = Vc^-1, Y = Gw^-1, Z = -Y Aw X,
//    two 3x3 inverses by their adjugates instead of a 6x6 LU (~200 multiplications, not ~300,
//    and no pivot search). J_t is singular exactly when Vc (arm: stretched elbow, tip over the
//    yaw axis) or Gw (gimbal lock) is; a zero determinant leaves J1 non-finite, as the LU's
//    inverse of a singular J_t.
//
// Everything lives in fixed-size stack arrays: terms() neither allocates nor throws. The scalar
// type T of the arithmetic is a template parameter: PhantomModel (double) is the model; a float
// variant (PhantomModelFloat) exists only as a measured point on the time-vs-error curve.
// Measured (docs/benchmarks.md): 3.3x faster than the reference terms, and faster than MuJoCo's
// mass matrix from q alone on the same states.
#pragma once

#include <Eigen/Core>
#include <array>

#include "reference/core/device_model.h"
#include "reference/phantom/phantom_model.h"
#include "reference/phantom/phantom_params.h"

namespace dentsim::fast {

template <typename T>
class PhantomDynamics : public SixDofDeviceModel {
 public:
  // specialise false keeps the closed form's run-time gimbal path even for a file that fits the
  // shipped gimbal (tests compare the two; every other caller takes the default).
  explicit PhantomDynamics(const PhantomParams& params, bool specialise = true);

  const PhantomParams& params() const { return params_; }

  // All of DeviceTerms at (q, qd) in one pass (sections 1-5 above); J_t_dot only when
  // with_jacobian_rate (zero otherwise, as the reference). No allocation, no exception.
  void terms(const Vec6& q, const Vec6& qd, bool with_jacobian_rate,
             DeviceTerms& out) const override;

  // True when the device file fits the closed form of docs/derivations/phantom_closed_form.md
  // (decided once, at construction): terms() then takes it; otherwise the tree sweeps above.
  bool closed_form() const { return closed_form_; }
  // True when the closed form runs its specialisation for the shipped gimbal (decided at
  // construction): rot0 = E for yaw, pitch and roll, axes +y, +x, +z, and the forearm's {B}
  // orientation at q3 = 0 (e_y, -e_z, -e_x) (the shipped file's), fixed at compile time; any
  // other file that fits the closed form takes its run-time column turns (col_from, col_sign,
  // axis_sign, fore_from_, fore_sign_). The same operations on the same numbers less products
  // with exact zeros and ones: equal as doubles (a zero's sign aside).
  bool shipped_gimbal() const { return shipped_gimbal_; }
  // True when jacobian_inverse() applies (the gimbal's joints meet at a point; at construction).
  bool block_jacobian_inverse() const { return gimbal_at_point_; }

  // J1 = J_t^-1 (section 6) from terms()' J_t and R1 (the pose's), when the gimbal's joints meet
  // at a point; false (J1 untouched) otherwise, for the caller's general inverse. No allocation,
  // no exception.
  bool jacobian_inverse(const Mat6& J_t, const Mat3& R1, Mat6* J1) const;

  // The DeviceModel interface through terms(); q, qd must have 6 entries
  // (std::invalid_argument otherwise, as the reference adapter).
  MatX mass_matrix(const VecX& q) const override;
  MatX coriolis_matrix(const VecX& q, const VecX& qd) const override;  // reference's C (below)
  VecX gravity(const VecX& q) const override;
  VecX friction_torque(const VecX& q, const VecX& qd) const override;
  Pose forward_kinematics(const VecX& q) const override;
  Mat6 twist_to_joint(const VecX& q) const override;  // J1 = J_t^-1 (2.2)
  // The params' damping and Coulomb coefficients, as the reference model's; always true.
  bool joint_friction_coefficients(Vec6* b, Vec6* f_c) const override;

 private:
  DeviceTerms terms_at(const VecX& q, const Vec6& qd) const;  // q size-checked, no dJ_t/dt
  // Sections 1-5 on the tree (any device file).
  void terms_tree(const Vec6& q, const Vec6& qd, bool with_jacobian_rate, DeviceTerms& out) const;
  // The closed form (docs/derivations/phantom_closed_form.md), when closed_form_.
  // Shipped: the gimbal's permutations and axes fixed at compile time (shipped_gimbal()).
  template <bool Shipped>
  void terms_closed(const Vec6& q, const Vec6& qd, bool with_jacobian_rate,
                    DeviceTerms& out) const;

  using V3 = Eigen::Matrix<T, 3, 1>;
  using M3 = Eigen::Matrix<T, 3, 3>;
  using V6 = Eigen::Matrix<T, 6, 1>;

  struct Body {
    M3 A, B, D;  // rot0, rot0 S(axis), rot0 S(axis)^2
    V3 s;        // rot0 axis
    V3 pos, com, inertia;
    T mass;
    // When rot0 is a signed permutation (column c of rot0 = col_sign[c] e_col_from[c]) and the
    // axis is +-e_k (axis_sign): R = R_par rot0 Rot is a signed column permutation of R_par whose
    // columns i, j (k, i, j cyclic) are turned by axis_sign * theta (header section 1).
    bool axis_aligned = false;
    std::array<int, 3> col_from{};
    std::array<T, 3> col_sign{};
    int k = 0;
    int ci = 1, cj = 2;  // (k + 1) % 3, (k + 2) % 3: the columns the joint turns
    T axis_sign = T(1);
    bool at_parent_origin = false;  // pos = 0: p_i = p_par, vo_i = vo_par, no parallel-axis shift
  };

  PhantomParams params_;
  std::array<Body, kPhantomTreeDof> body_;
  V3 tip_;
  Mat3 S_tip_ = Mat3::Zero();     // S(tip) in double (section 6)
  bool gimbal_at_point_ = false;  // pitch_pos = roll_pos = 0: section 6 applies
  // The closed form's constants (docs/derivations/phantom_closed_form.md §2), in the base frame
  // {B} at q1 = 0. An arm body (upper arm, forearm, crank, parallel link) at its absolute angle
  // phi: CoM offset r = Ry(-phi) rho from its pivot, inertia Ry(-phi) diag(d) Ry(-phi)^T.
  struct ArmBody {
    T m, rx, ry, rz;  // mass, rho
    T dx, dy, dz;     // inertia about the CoM along {B}'s axes at phi = 0
    T Kyy;            // dy + m (rho_x^2 + rho_z^2): the yy entry about the pivot, constant
  };
  bool closed_form_ = false;
  bool shipped_gimbal_ = false;
  std::array<ArmBody, 4> arm_{};  // upper arm, forearm, crank, parallel link
  T base_zz_ = T(0);              // the base's zz inertia about the yaw axis
  T E0x_ = T(0), E0z_ = T(0);     // elbow at q2 = 0
  T P0x_ = T(0), P0z_ = T(0);     // crank's end (the parallel link's pivot) at q3 = 0
  T F0x_ = T(0), F0z_ = T(0);     // elbow to gimbal centre at q3 = 0
  T E0sq_ = T(0), P0sq_ = T(0), F0sq_ = T(0);  // their squared lengths
  std::array<int, 3> fore_from_{};  // the forearm's {B} orientation at q3 = 0, a signed
  std::array<T, 3> fore_sign_{};    // permutation: column c = fore_sign_[c] e_fore_from_[c]
  V6 armature_, damping_, coulomb_;
  V6 coulomb_smoothing_;
  std::array<CoulombSign, 6> coulomb_sign_{};
  T gravity_;
  // The full matrix C (not a servo-tick quantity: only coriolis_matrix() needs it) comes from
  // the reference model, which defines which factorisation C is.
  PhantomModelD reference_;
};

extern template class PhantomDynamics<double>;
extern template class PhantomDynamics<float>;

// The fast Phantom model (double): what the fast pipeline uses.
class PhantomModel : public PhantomDynamics<double> {
 public:
  using PhantomDynamics<double>::PhantomDynamics;
};

// The same arithmetic in float (inputs and outputs stay double): a time-vs-error point only.
class PhantomModelFloat : public PhantomDynamics<float> {
 public:
  using PhantomDynamics<float>::PhantomDynamics;
};

}  // namespace dentsim::fast
