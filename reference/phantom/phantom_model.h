// Joint-space model of the Phantom Premium 1.5/6DoF (issue #3), templated on the scalar type so
// that calibration/ can differentiate through it with ceres::Jet (explicitly instantiated for
// double in phantom_model.cc).
//
// Coordinates. q = (q1..q6) [rad] as the device reports them: q1 base yaw, q2 absolute elevation
// of the upper arm `be`, q3 absolute angle of the forearm `a` (OpenHaptics convention,
// docs/device_facts.md §1), q4..q6 gimbal yaw, pitch, roll. The mechanism is computed as a
// kinematic tree of 8 bodies (base, be, a, df, c, yaw, pitch, roll) with tree coordinates
// theta = G q, G the constant 8x6 map of phantom_tree_map(): the elbow angle theta_2 = q3 - q2 and
// the parallel-link angle theta_4 = q2 - q3 close the parallelogram, so the closed chain is exact
// in q (docs/device_facts.md §4: M_red = G^T M_tree G). The same tree (body placements, axes,
// inertias) generates the MJCF (plant/phantom_mjcf.h), so the two models agree to round-off by
// construction.
//
// Dynamics (device_model.h, thesis (2.1)):
//     M(q) qdd + C(q, qd) qd + g(q) + tau_f(qd) = tau + f_h
// - M(q) = G^T M_tree(theta) G + diag(armature), M_tree = sum_i m_i Jv_i^T Jv_i + Jw_i^T I_i Jw_i
//   (Jv_i the CoM Jacobian in {O}, Jw_i the angular Jacobian in {O}, I_i = R_i diag(I) R_i^T).
// - C(q, qd) = G^T C_tree G with C_tree = sum_i m_i Jv_i^T dJv_i/dt
//   + Jw_i^T (I_i dJw_i/dt + S(w_i) I_i Jw_i): a factorisation with dM/dt = C + C^T (tested),
//   whose C qd equals the Christoffel (Cavusoglu 2002) velocity terms.
// - g(q) = G^T sum_i m_i Jv_i^T (0, 0, |g|): gradient of the potential sum_i m_i |g| z_i.
// - tau_f = b qd + f_c tanh(qd / v_s) (f_c sign(qd) when v_s = 0), per device joint.
// Kinematics (thesis (2.2)): tool tip x1 = p_roll + R_roll tip_offset, R1 = R_roll; the tool
// Jacobian J_t gives V1 = [v1 (world); w1 (body)] = J_t qd, and the modified Jacobian of (2.2) is
// J1 = J_t^-1 (qd = J1 V1).
// Units: SI (m, kg, s, rad, N m).
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <array>
#include <cmath>

#include "reference/core/device_model.h"
#include "reference/phantom/phantom_params.h"

namespace dentsim {

inline constexpr int kPhantomTreeDof = 8;

// Bodies of the kinematic tree; body i carries tree joint i.
enum PhantomTreeBody : int {
  kBase = 0,
  kUpperArm = 1,      // be   (theta_1 = q2)
  kForearm = 2,       // a    (theta_2 = q3 - q2, relative elbow)
  kCrank = 3,         // df   (theta_3 = q3)
  kParallelLink = 4,  // c    (theta_4 = q2 - q3, relative)
  kGimbalYaw = 5,     // theta_5 = q4
  kGimbalPitch = 6,   // theta_6 = q5
  kGimbalRoll = 7,    // theta_7 = q6
};
const char* phantom_tree_body_name(int body);  // "base", "upper_arm", ... (model-file names)
// Tree joint carrying device joint j (0-based): (0, 1, 3, 5, 6, 7).
int phantom_actuated_tree_joint(int device_joint);

// G: theta = G q (constant), docs/device_facts.md §4 "M_red = G^T M G".
Eigen::Matrix<double, kPhantomTreeDof, 6> phantom_tree_map();

// The tree: body i hangs from parent[i] (-1 = world) at pos[i] (parent frame) with fixed
// orientation rot0[i] (parent frame), turned by tree joint i about axis[i] (unit, own frame)
// through its origin; R_i = R_parent rot0_i Rot(axis_i, theta_i) — MuJoCo's body/joint semantics.
template <typename T>
struct PhantomTreeT {
  using V3 = Eigen::Matrix<T, 3, 1>;
  using M3 = Eigen::Matrix<T, 3, 3>;
  using V6 = Eigen::Matrix<T, 6, 1>;
  std::array<int, kPhantomTreeDof> parent{};
  std::array<V3, kPhantomTreeDof> pos;
  std::array<M3, kPhantomTreeDof> rot0;
  std::array<V3, kPhantomTreeDof> axis;
  std::array<T, kPhantomTreeDof> mass;
  std::array<V3, kPhantomTreeDof> com;      // CoM, own frame
  std::array<V3, kPhantomTreeDof> inertia;  // principal moments about the CoM, own axes
  V3 tip;                                   // tool tip in the roll frame
  V6 armature, damping, coulomb;            // per device joint
  V6 coulomb_smoothing;                     // v_s per device joint [rad/s]
  std::array<CoulombSign, 6> coulomb_sign;  // the smooth sign per device joint
  T gravity;                                // |g| [m/s^2], 0 when gravity is off
};

// The tree of `p` with every number cast to T (T(double) must exist, e.g. ceres::Jet).
template <typename T>
PhantomTreeT<T> phantom_tree(const PhantomParams& p);

// Friction of one device joint (the one definition of the law, used by PhantomModelT, by
// fast/phantom, by the simulated device's kTanh law and by the calibration's Coulomb column):
// tau_f = b qd + f_c s(qd / v_s) [N m] with the smooth sign s = tanh or erf (CoulombSign), or
// f_c sign(qd) when v_s = 0 (b [N m s/rad], f_c [N m], v_s [rad/s], qd [rad/s]).
template <typename T>
T phantom_joint_friction(const T& b, const T& f_c, const T& v_s, const T& qd,
                         CoulombSign sign = CoulombSign::kTanh) {
  using std::erf;
  using std::tanh;
  T s;
  if (v_s > T(0)) {
    s = sign == CoulombSign::kErf ? erf(qd / v_s) : tanh(qd / v_s);
  } else {
    s = qd > T(0) ? T(1) : (qd < T(0) ? T(-1) : T(0));
  }
  return b * qd + f_c * s;
}

// v as a 6-vector; std::invalid_argument "PhantomModel: <what> must have 6 entries, got n"
// otherwise (the size check of the DeviceModel adapters).
Vec6 phantom_vec6(const VecX& v, const char* what);

template <typename T>
class PhantomModelT {
 public:
  using V3 = Eigen::Matrix<T, 3, 1>;
  using M3 = Eigen::Matrix<T, 3, 3>;
  using V6 = Eigen::Matrix<T, 6, 1>;
  using M6 = Eigen::Matrix<T, 6, 6>;
  using VT = Eigen::Matrix<T, kPhantomTreeDof, 1>;
  using MT = Eigen::Matrix<T, kPhantomTreeDof, kPhantomTreeDof>;

  // Positions and velocities of every body, world frame.
  struct Kinematics {
    std::array<M3, kPhantomTreeDof> R;   // body orientation
    std::array<V3, kPhantomTreeDof> p;   // body origin (= joint point)
    std::array<V3, kPhantomTreeDof> a;   // joint axis
    std::array<V3, kPhantomTreeDof> c;   // CoM
    std::array<V3, kPhantomTreeDof> w;   // angular velocity
    std::array<V3, kPhantomTreeDof> vo;  // velocity of the origin
    std::array<V3, kPhantomTreeDof> vc;  // velocity of the CoM
  };

  explicit PhantomModelT(const PhantomTreeT<T>& tree);
  explicit PhantomModelT(const PhantomParams& p) : PhantomModelT(phantom_tree<T>(p)) {}

  const PhantomTreeT<T>& tree() const { return tree_; }
  PhantomTreeT<T>& mutable_tree() { return tree_; }

  Kinematics kinematics(const V6& q, const V6& qd) const;

  M6 M(const V6& q) const;                   // M(q), armature included
  M6 C(const V6& q, const V6& qd) const;     // C(q, qd), dM/dt = C + C^T
  V6 bias(const V6& q, const V6& qd) const;  // C(q, qd) qd
  V6 g(const V6& q) const;                   // g(q)
  V6 friction(const V6& qd) const;           // tau_f(qd)
  // qdd of M qdd + C qd + g + tau_f = tau.
  V6 forward_dynamics(const V6& q, const V6& qd, const V6& tau) const;

  void fk(const V6& q, V3* x1, M3* R1) const;  // tool tip x1 (world), R1
  M6 tool_jacobian(const V6& q) const;         // J_t: [v1 (world); w1 (body)] = J_t qd
  M6 J1(const V6& q) const;                    // (2.2): qd = J1 [v1; w1], J1 = J_t^-1

  // From one kinematics pass k = kinematics(q, qd) (the servo tick's device terms):
  // joint-space M, C and g (any pointer may be null; M includes the armature), the tool tip pose,
  // J_t, and its time derivative along qd:
  //   column j (tree joint j, an ancestor of the roll body; x1 the tip, p_j the joint point):
  //     v-row  d/dt (a_j x (x1 - p_j)) = (w_j x a_j) x (x1 - p_j) + a_j x (xd1 - vo_j)
  //     w-row  d/dt (R1^T a_j)         = R1^T (w_j x a_j - w_roll x a_j)
  //   with xd1 = vo_roll + w_roll x (x1 - p_roll), then J_t = J_tree G, dJ_t/dt = dJ_tree/dt G.
  void joint_terms(const Kinematics& k, M6* M, M6* C, V6* g) const;
  void tool_pose(const Kinematics& k, V3* x1, M3* R1) const;
  M6 tool_jacobian(const Kinematics& k) const;
  M6 tool_jacobian_rate(const Kinematics& k) const;

  T kinetic_energy(const V6& q, const V6& qd) const { return T(0.5) * qd.dot(M(q) * qd); }
  T potential_energy(const V6& q) const;  // sum_i m_i |g| z_i (zero at z = 0)

 private:
  bool ancestor_or_self(int j, int i) const { return (anc_[i] >> j) & 1u; }
  // Tree-coordinate M, C (and gravity) from one kinematics pass.
  void tree_terms(const Kinematics& k, MT* M, MT* C, VT* g) const;

  PhantomTreeT<T> tree_;
  std::array<unsigned, kPhantomTreeDof> anc_{};
};

// ---- implementation (templated; double is instantiated in phantom_model.cc) --------------------

namespace phantom_detail {

template <typename T>
Eigen::Matrix<T, 3, 3> skew_t(const Eigen::Matrix<T, 3, 1>& a) {
  Eigen::Matrix<T, 3, 3> s;
  // clang-format off
  s << T(0), -a(2),  a(1),
        a(2),  T(0), -a(0),
       -a(1),  a(0),  T(0);
  // clang-format on
  return s;
}

// Rot(axis, angle) by Rodrigues' formula (axis unit).
template <typename T>
Eigen::Matrix<T, 3, 3> axis_rotation(const Eigen::Matrix<T, 3, 1>& axis, const T& angle) {
  using std::cos;
  using std::sin;
  const Eigen::Matrix<T, 3, 3> S = skew_t<T>(axis);
  return Eigen::Matrix<T, 3, 3>::Identity() + sin(angle) * S + (T(1) - cos(angle)) * (S * S);
}

}  // namespace phantom_detail

template <typename T>
PhantomTreeT<T> phantom_tree(const PhantomParams& p) {
  PhantomTreeT<T> t;
  Mat3 perm;  // be frame at q2 = 0 in the base frame: x = shoulder axis (base y), z = base x
  // clang-format off
  perm << 0, 0, 1,
          1, 0, 0,
          0, 1, 0;
  // clang-format on
  const Mat3 flip = Eigen::Vector3d(1, -1, -1).asDiagonal();  // Rx(pi)
  const Vec3 shoulder_axis(-1, 0, 0);  // q2, q3 > 0 raise the upper arm / swing the forearm out
  struct Row {
    int parent;
    Vec3 pos;
    Mat3 rot0;
    Vec3 axis;
    const PhantomBody* body;
  };
  const std::array<Row, kPhantomTreeDof> rows = {{
      {-1, Vec3::Zero(), Mat3::Identity(), Vec3::UnitZ(), &p.base},
      {kBase, Vec3::Zero(), perm, shoulder_axis, &p.upper_arm},
      {kUpperArm, Vec3(0, 0, p.l1_m), flip, shoulder_axis, &p.forearm},
      {kBase, Vec3::Zero(), perm * flip, shoulder_axis, &p.crank},
      {kCrank, Vec3(0, p.l3_m, 0), flip, shoulder_axis, &p.parallel_link},
      {kForearm, Vec3(0, p.l2_m, 0), Mat3::Identity(), p.yaw_axis, &p.gimbal_yaw},
      {kGimbalYaw, p.pitch_pos_m, Mat3::Identity(), p.pitch_axis, &p.gimbal_pitch},
      {kGimbalPitch, p.roll_pos_m, Mat3::Identity(), p.roll_axis, &p.gimbal_roll},
  }};
  for (int i = 0; i < kPhantomTreeDof; ++i) {
    t.parent[i] = rows[i].parent;
    t.pos[i] = rows[i].pos.template cast<T>();
    t.rot0[i] = rows[i].rot0.template cast<T>();
    t.axis[i] = rows[i].axis.template cast<T>();
    t.mass[i] = T(rows[i].body->mass_kg);
    t.com[i] = rows[i].body->com_m.template cast<T>();
    t.inertia[i] = rows[i].body->inertia_kg_m2.template cast<T>();
  }
  t.tip = p.tip_offset_m.cast<T>();
  t.armature = p.armature_kg_m2.cast<T>();
  t.damping = p.damping_n_m_s_per_rad.cast<T>();
  t.coulomb = p.coulomb_n_m.cast<T>();
  t.coulomb_smoothing = p.coulomb_smoothing_rad_s.cast<T>();
  t.coulomb_sign = p.coulomb_sign;
  t.gravity = T(p.gravity_on ? p.gravity_m_s2 : 0.0);
  return t;
}

template <typename T>
PhantomModelT<T>::PhantomModelT(const PhantomTreeT<T>& tree) : tree_(tree) {
  for (int i = 0; i < kPhantomTreeDof; ++i) {
    anc_[i] = 1u << i;
    if (tree_.parent[i] >= 0) anc_[i] |= anc_[tree_.parent[i]];  // parents precede children
  }
}

template <typename T>
typename PhantomModelT<T>::Kinematics PhantomModelT<T>::kinematics(const V6& q,
                                                                   const V6& qd) const {
  const Eigen::Matrix<T, kPhantomTreeDof, 6> G = phantom_tree_map().cast<T>();
  const VT th = G * q;
  const VT thd = G * qd;
  Kinematics k;
  for (int i = 0; i < kPhantomTreeDof; ++i) {
    const int par = tree_.parent[i];
    const M3 Rp = par < 0 ? M3::Identity() : k.R[par];
    const V3 pp = par < 0 ? V3::Zero() : k.p[par];
    const V3 wp = par < 0 ? V3::Zero() : k.w[par];
    const V3 vp = par < 0 ? V3::Zero() : k.vo[par];
    const M3 Rj = Rp * tree_.rot0[i];  // joint frame
    k.a[i] = Rj * tree_.axis[i];
    k.R[i] = Rj * phantom_detail::axis_rotation<T>(tree_.axis[i], th(i));
    k.p[i] = pp + Rp * tree_.pos[i];
    k.c[i] = k.p[i] + k.R[i] * tree_.com[i];
    k.w[i] = wp + k.a[i] * thd(i);
    k.vo[i] = vp + wp.cross(k.p[i] - pp);
    k.vc[i] = k.vo[i] + k.w[i].cross(k.c[i] - k.p[i]);
  }
  return k;
}

template <typename T>
void PhantomModelT<T>::tree_terms(const Kinematics& k, MT* M, MT* C, VT* g) const {
  if (M) M->setZero();
  if (C) C->setZero();
  if (g) g->setZero();
  for (int i = 0; i < kPhantomTreeDof; ++i) {
    Eigen::Matrix<T, 3, kPhantomTreeDof> Jv = Eigen::Matrix<T, 3, kPhantomTreeDof>::Zero();
    Eigen::Matrix<T, 3, kPhantomTreeDof> Jw = Eigen::Matrix<T, 3, kPhantomTreeDof>::Zero();
    Eigen::Matrix<T, 3, kPhantomTreeDof> dJv = Eigen::Matrix<T, 3, kPhantomTreeDof>::Zero();
    Eigen::Matrix<T, 3, kPhantomTreeDof> dJw = Eigen::Matrix<T, 3, kPhantomTreeDof>::Zero();
    for (int j = 0; j <= i; ++j) {
      if (!ancestor_or_self(j, i)) continue;
      const V3 r = k.c[i] - k.p[j];
      Jw.col(j) = k.a[j];
      Jv.col(j) = k.a[j].cross(r);
      const V3 da = k.w[j].cross(k.a[j]);  // the axis turns with its body
      dJw.col(j) = da;
      dJv.col(j) = da.cross(r) + k.a[j].cross(k.vc[i] - k.vo[j]);
    }
    const M3 I = k.R[i] * tree_.inertia[i].asDiagonal() * k.R[i].transpose();
    if (M) *M += tree_.mass[i] * (Jv.transpose() * Jv) + Jw.transpose() * I * Jw;
    if (C) {
      *C += tree_.mass[i] * (Jv.transpose() * dJv) +
            Jw.transpose() * (I * dJw + phantom_detail::skew_t<T>(k.w[i]) * I * Jw);
    }
    if (g) *g += tree_.mass[i] * tree_.gravity * Jv.row(2).transpose();
  }
}

template <typename T>
typename PhantomModelT<T>::M6 PhantomModelT<T>::M(const V6& q) const {
  const Eigen::Matrix<T, kPhantomTreeDof, 6> G = phantom_tree_map().cast<T>();
  MT Mt;
  tree_terms(kinematics(q, V6::Zero()), &Mt, nullptr, nullptr);
  M6 out = G.transpose() * Mt * G;
  out.diagonal() += tree_.armature;
  return out;
}

template <typename T>
typename PhantomModelT<T>::M6 PhantomModelT<T>::C(const V6& q, const V6& qd) const {
  const Eigen::Matrix<T, kPhantomTreeDof, 6> G = phantom_tree_map().cast<T>();
  MT Ct;
  tree_terms(kinematics(q, qd), nullptr, &Ct, nullptr);
  return G.transpose() * Ct * G;
}

template <typename T>
typename PhantomModelT<T>::V6 PhantomModelT<T>::bias(const V6& q, const V6& qd) const {
  return C(q, qd) * qd;
}

template <typename T>
typename PhantomModelT<T>::V6 PhantomModelT<T>::g(const V6& q) const {
  const Eigen::Matrix<T, kPhantomTreeDof, 6> G = phantom_tree_map().cast<T>();
  VT gt;
  tree_terms(kinematics(q, V6::Zero()), nullptr, nullptr, &gt);
  return G.transpose() * gt;
}

template <typename T>
typename PhantomModelT<T>::V6 PhantomModelT<T>::friction(const V6& qd) const {
  V6 f;
  for (int j = 0; j < 6; ++j) {
    f(j) =
        phantom_joint_friction(tree_.damping(j), tree_.coulomb(j), tree_.coulomb_smoothing(j), qd(j),
                               tree_.coulomb_sign[j]);
  }
  return f;
}

template <typename T>
typename PhantomModelT<T>::V6 PhantomModelT<T>::forward_dynamics(const V6& q, const V6& qd,
                                                                 const V6& tau) const {
  const Eigen::Matrix<T, kPhantomTreeDof, 6> G = phantom_tree_map().cast<T>();
  const Kinematics k = kinematics(q, qd);
  MT Mt, Ct;
  VT gt;
  tree_terms(k, &Mt, &Ct, &gt);
  M6 Mq = G.transpose() * Mt * G;
  Mq.diagonal() += tree_.armature;
  const V6 rhs = tau - G.transpose() * (Ct * (G * qd) + gt) - friction(qd);
  return Mq.llt().solve(rhs);
}

template <typename T>
void PhantomModelT<T>::fk(const V6& q, V3* x1, M3* R1) const {
  const Kinematics k = kinematics(q, V6::Zero());
  if (x1) *x1 = k.p[kGimbalRoll] + k.R[kGimbalRoll] * tree_.tip;
  if (R1) *R1 = k.R[kGimbalRoll];
}

template <typename T>
typename PhantomModelT<T>::M6 PhantomModelT<T>::tool_jacobian(const V6& q) const {
  return tool_jacobian(kinematics(q, V6::Zero()));
}

template <typename T>
typename PhantomModelT<T>::M6 PhantomModelT<T>::J1(const V6& q) const {
  return tool_jacobian(q).partialPivLu().inverse();  // (2.2)
}

template <typename T>
void PhantomModelT<T>::joint_terms(const Kinematics& k, M6* M, M6* C, V6* g) const {
  const Eigen::Matrix<T, kPhantomTreeDof, 6> G = phantom_tree_map().cast<T>();
  MT Mt, Ct;
  VT gt;
  tree_terms(k, M ? &Mt : nullptr, C ? &Ct : nullptr, g ? &gt : nullptr);
  if (M) {
    *M = G.transpose() * Mt * G;
    M->diagonal() += tree_.armature;
  }
  if (C) *C = G.transpose() * Ct * G;
  if (g) *g = G.transpose() * gt;
}

template <typename T>
void PhantomModelT<T>::tool_pose(const Kinematics& k, V3* x1, M3* R1) const {
  if (x1) *x1 = k.p[kGimbalRoll] + k.R[kGimbalRoll] * tree_.tip;
  if (R1) *R1 = k.R[kGimbalRoll];
}

template <typename T>
typename PhantomModelT<T>::M6 PhantomModelT<T>::tool_jacobian(const Kinematics& k) const {
  const Eigen::Matrix<T, kPhantomTreeDof, 6> G = phantom_tree_map().cast<T>();
  const V3 x1 = k.p[kGimbalRoll] + k.R[kGimbalRoll] * tree_.tip;
  Eigen::Matrix<T, 6, kPhantomTreeDof> Jt = Eigen::Matrix<T, 6, kPhantomTreeDof>::Zero();
  for (int j = 0; j < kPhantomTreeDof; ++j) {
    if (!ancestor_or_self(j, kGimbalRoll)) continue;
    Jt.col(j).template head<3>() = k.a[j].cross(x1 - k.p[j]);              // v1, world
    Jt.col(j).template tail<3>() = k.R[kGimbalRoll].transpose() * k.a[j];  // w1, body
  }
  return Jt * G;
}

template <typename T>
typename PhantomModelT<T>::M6 PhantomModelT<T>::tool_jacobian_rate(const Kinematics& k) const {
  const Eigen::Matrix<T, kPhantomTreeDof, 6> G = phantom_tree_map().cast<T>();
  const M3& R = k.R[kGimbalRoll];
  const V3 x1 = k.p[kGimbalRoll] + R * tree_.tip;
  const V3 w_tip = k.w[kGimbalRoll];
  const V3 xd1 = k.vo[kGimbalRoll] + w_tip.cross(x1 - k.p[kGimbalRoll]);
  Eigen::Matrix<T, 6, kPhantomTreeDof> dJ = Eigen::Matrix<T, 6, kPhantomTreeDof>::Zero();
  for (int j = 0; j < kPhantomTreeDof; ++j) {
    if (!ancestor_or_self(j, kGimbalRoll)) continue;
    const V3 da = k.w[j].cross(k.a[j]);  // the axis turns with its body
    dJ.col(j).template head<3>() = da.cross(x1 - k.p[j]) + k.a[j].cross(xd1 - k.vo[j]);
    dJ.col(j).template tail<3>() = R.transpose() * (da - w_tip.cross(k.a[j]));
  }
  return dJ * G;
}

template <typename T>
T PhantomModelT<T>::potential_energy(const V6& q) const {
  const Kinematics k = kinematics(q, V6::Zero());
  T u = T(0);
  for (int i = 0; i < kPhantomTreeDof; ++i) u += tree_.mass[i] * tree_.gravity * k.c[i](2);
  return u;
}

extern template class PhantomModelT<double>;
extern template PhantomTreeT<double> phantom_tree<double>(const PhantomParams&);

using PhantomModelD = PhantomModelT<double>;

// The double model behind the device-model interface the observer and the tick use
// (reference/core/device_model.h). q, qd must have 6 entries (std::invalid_argument otherwise).
class PhantomModel : public SixDofDeviceModel {
 public:
  explicit PhantomModel(PhantomParams params);

  const PhantomParams& params() const { return params_; }
  const PhantomModelD& model() const { return model_; }

  MatX mass_matrix(const VecX& q) const override;
  MatX coriolis_matrix(const VecX& q, const VecX& qd) const override;
  VecX gravity(const VecX& q) const override;
  VecX friction_torque(const VecX& q, const VecX& qd) const override;
  Pose forward_kinematics(const VecX& q) const override;
  Mat6 twist_to_joint(const VecX& q) const override;  // J1(q) of (2.2)
  // One kinematics pass for every term (PhantomModelT::joint_terms, tool_jacobian(_rate));
  // no allocation. M, C and g equal mass_matrix, coriolis_matrix and gravity bitwise.
  void terms(const Vec6& q, const Vec6& qd, bool with_jacobian_rate,
             DeviceTerms& out) const override;
  // The tree's damping and coulomb (phantom_joint_friction's b and f_c); always true.
  bool joint_friction_coefficients(Vec6* b, Vec6* f_c) const override;

 private:
  PhantomParams params_;
  PhantomModelD model_;
};

}  // namespace dentsim
