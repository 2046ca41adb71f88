// Tests of the analytic Phantom model (reference/phantom/phantom_model.h): the published closed
// form (Cavusoglu 2002, docs/device_facts.md §2), Lagrangian identities by finite differences,
// kinematics, and the ceres::Jet instantiation. Tolerance policy: docs/phantom.md.
#include "reference/phantom/phantom_model.h"

#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <cmath>
#include <cstdio>
#include <random>

#include "reference/core/so3.h"
#include "tests/support/phantom_states.h"

namespace dentsim {
namespace {

constexpr std::uint64_t kSeed = 20021;

// The fixed seed of this file's states.
class RandomStates : public testing::PhantomStates {
 public:
  explicit RandomStates(const PhantomParams& p, std::uint64_t seed = kSeed)
      : PhantomStates(p, seed) {}
};

double rel_err(const MatX& a, const MatX& b) {
  return (a - b).cwiseAbs().maxCoeff() / b.cwiseAbs().maxCoeff();
}

// ---- Cavusoglu 2002 closed form with the published numbers (docs/device_facts.md §2) ---------
struct Published {
  double l1 = 0.215, l2 = 0.170, l3 = 0.0325, l5 = -0.0368, l6 = 0.0527, g = 9.81;
  double ma = 0.0202, mc = 0.0249, mbe = 0.2359, mdf = 0.1906;
  double Iaxx = 0.4864e-4, Iayy = 0.001843e-4, Iazz = 0.4864e-4;
  double Icxx = 0.959e-4, Icyy = 0.959e-4, Iczz = 0.0051e-4;
  double Ibexx = 11.09e-4, Ibeyy = 10.06e-4, Ibezz = 0.591e-4;
  double Idfxx = 7.11e-4, Idfyy = 0.629e-4, Idfzz = 6.246e-4;
  double Ibase = 11.87e-4;

  Mat3 M(double q2, double q3) const {
    const double l1s = l1 * l1, l2s = l2 * l2, l3s = l3 * l3;
    Mat3 m = Mat3::Zero();
    m(0, 0) =
        0.125 * (4 * Iayy + 4 * Iazz + 8 * Ibase + 4 * Ibeyy + 4 * Ibezz + 4 * Icyy + 4 * Iczz +
                 4 * Idfyy + 4 * Idfzz + 4 * l1s * ma + l2s * ma + l1s * mc + 4 * l3s * mc) +
        0.125 * (4 * Ibeyy - 4 * Ibezz + 4 * Icyy - 4 * Iczz + l1s * (4 * ma + mc)) *
            std::cos(2 * q2) +
        0.125 * (4 * Iayy - 4 * Iazz + 4 * Idfyy - 4 * Idfzz - l2s * ma - 4 * l3s * mc) *
            std::cos(2 * q3) +
        l1 * (l2 * ma + l3 * mc) * std::cos(q2) * std::sin(q3);
    m(1, 1) = Ibexx + Icxx + l1s * ma + 0.25 * l1s * mc;
    m(2, 2) = Iaxx + Idfxx + 0.25 * l2s * ma + l3s * mc;
    m(1, 2) = m(2, 1) = -0.5 * l1 * (l2 * ma + l3 * mc) * std::sin(q2 - q3);
    return m;
  }
  Vec3 G(double q2, double q3) const {
    return Vec3(0.0, 0.5 * g * (2 * l1 * ma + 2 * l5 * mbe + l1 * mc) * std::cos(q2),
                0.5 * g * (l2 * ma + 2 * l3 * mc - 2 * l6 * mdf) * std::sin(q3));
  }
};

// The arm alone: gimbal bodies massless, armature zero.
PhantomTreeT<double> arm_only_tree() {
  PhantomTreeT<double> t = phantom_tree<double>(default_phantom_params());
  for (int b : {kGimbalYaw, kGimbalPitch, kGimbalRoll}) {
    t.mass[b] = 0.0;
    t.inertia[b].setZero();
  }
  t.armature.setZero();
  return t;
}

TEST(PhantomModel, ArmMatchesCavusogluClosedForm) {
  const Published pub;
  const PhantomParams p = default_phantom_params();
  const PhantomModelD model(arm_only_tree());
  // The default file keeps CoM inertias that satisfy the triangle inequality and moved the excess
  // of the published shoulder-axis moments into the armature (phantom_params.cc); add it back.
  const double excess_be = pub.Ibexx - (p.upper_arm.inertia_kg_m2(0) + pub.mbe * pub.l5 * pub.l5);
  const double excess_df = pub.Idfxx - (p.crank.inertia_kg_m2(0) + pub.mdf * pub.l6 * pub.l6);
  EXPECT_NEAR(excess_be, 0.44534784e-4, 1e-15);
  EXPECT_NEAR(excess_df, 0.23648526e-4, 1e-15);
  RandomStates rs(p);
  double worst_m = 0.0, worst_g = 0.0;
  for (int s = 0; s < 1000; ++s) {
    const Vec6 q = rs.q();
    Mat3 m = model.M(q).topLeftCorner<3, 3>();
    m(1, 1) += excess_be;
    m(2, 2) += excess_df;
    worst_m = std::max(worst_m, rel_err(m, pub.M(q(1), q(2))));
    const Vec3 g = model.g(q).head<3>();
    worst_g = std::max(worst_g, (g - pub.G(q(1), q(2))).cwiseAbs().maxCoeff() /
                                    pub.G(q(1), q(2)).cwiseAbs().maxCoeff());
  }
  std::printf("closed form: max rel error M %.3e, g %.3e\n", worst_m, worst_g);
  EXPECT_LT(worst_m, 1e-13);
  EXPECT_LT(worst_g, 1e-13);
}

// C qd equals the Christoffel velocity terms of the closed-form M, including the corrected
// C(3,2) = -1/2 l1 (l2 ma + l3 mc) cos(q2 - q3) q2dot (docs/device_facts.md §2's sign note).
TEST(PhantomModel, ArmBiasMatchesChristoffelOfClosedForm) {
  const Published pub;
  const PhantomModelD model(arm_only_tree());
  RandomStates rs(default_phantom_params());
  const double h = 1e-6;
  double worst = 0.0, worst_c32 = 0.0;
  for (int s = 0; s < 200; ++s) {
    Vec6 q = rs.q(), qd = rs.qd();
    qd.tail<3>().setZero();
    // dM/dq_i of the closed form by central differences (M depends on q2, q3 only).
    std::array<Mat3, 3> dM;
    dM[0].setZero();
    for (int i = 1; i < 3; ++i) {
      Vec3 a(0, q(1), q(2)), b(0, q(1), q(2));
      a(i) += h;
      b(i) -= h;
      dM[i] = (pub.M(a(1), a(2)) - pub.M(b(1), b(2))) / (2 * h);
    }
    Mat3 C =
        Mat3::Zero();  // Christoffel: C_kj = sum_i 1/2 (dM_kj/dq_i + dM_ki/dq_j - dM_ij/dq_k) qd_i
    for (int k = 0; k < 3; ++k) {
      for (int j = 0; j < 3; ++j) {
        for (int i = 0; i < 3; ++i) {
          C(k, j) += 0.5 * (dM[i](k, j) + dM[j](k, i) - dM[k](i, j)) * qd(i);
        }
      }
    }
    const double c32 =
        -0.5 * pub.l1 * (pub.l2 * pub.ma + pub.l3 * pub.mc) * std::cos(q(1) - q(2)) * qd(1);
    worst_c32 = std::max(worst_c32, std::abs(C(2, 1) - c32));
    const Vec3 ref = C * qd.head<3>();
    const Vec3 got = model.bias(q, qd).head<3>();
    worst = std::max(worst, (got - ref).cwiseAbs().maxCoeff() / ref.cwiseAbs().maxCoeff());
  }
  std::printf("arm C qd vs Christoffel of the closed form: max rel %.3e; C32 formula %.3e\n", worst,
              worst_c32);
  EXPECT_LT(worst, 1e-7);  // central differences, h = 1e-6
  EXPECT_LT(worst_c32, 1e-10);
}

// dM/dt = C + C^T (the property the momentum observer (3.7) relies on), full 6-DoF model.
TEST(PhantomModel, MassMatrixDerivativeIsCPlusCTranspose) {
  const PhantomParams p = default_phantom_params();
  const PhantomModelD model(p);
  RandomStates rs(p);
  const double h = 1e-6;
  double worst = 0.0;
  for (int s = 0; s < 200; ++s) {
    const Vec6 q = rs.q(), qd = rs.qd();
    const Mat6 dM = (model.M(q + h * qd) - model.M(q - h * qd)) / (2 * h);
    const Mat6 C = model.C(q, qd);
    worst = std::max(worst, rel_err(C + C.transpose(), dM));
  }
  std::printf("dM/dt vs C + C^T: max rel %.3e\n", worst);
  EXPECT_LT(worst, 1e-7);
}

// C qd = dM/dt qd - 1/2 d(qd^T M qd)/dq (Lagrange), and g = dU/dq, by central differences.
TEST(PhantomModel, BiasAndGravityAreLagrangian) {
  const PhantomParams p = default_phantom_params();
  const PhantomModelD model(p);
  RandomStates rs(p);
  const double h = 1e-6;
  double worst_c = 0.0, worst_g = 0.0;
  for (int s = 0; s < 200; ++s) {
    const Vec6 q = rs.q(), qd = rs.qd();
    const Mat6 dM = (model.M(q + h * qd) - model.M(q - h * qd)) / (2 * h);
    Vec6 dT, dU;
    for (int i = 0; i < 6; ++i) {
      const Vec6 e = h * Vec6::Unit(i);
      dT(i) = (model.kinetic_energy(q + e, qd) - model.kinetic_energy(q - e, qd)) / (2 * h);
      dU(i) = (model.potential_energy(q + e) - model.potential_energy(q - e)) / (2 * h);
    }
    const Vec6 ref = dM * qd - dT;
    worst_c = std::max(worst_c, rel_err(model.bias(q, qd), ref));
    worst_g = std::max(worst_g, rel_err(model.g(q), dU));
  }
  std::printf("C qd vs Lagrange %.3e, g vs dU/dq %.3e (max rel)\n", worst_c, worst_g);
  EXPECT_LT(worst_c, 1e-7);
  EXPECT_LT(worst_g, 1e-8);
}

// J_t against finite differences of fk; J1 J_t = I (2.2); V1 = [v world; w body].
TEST(PhantomModel, JacobianMatchesFiniteDifferencesOfFk) {
  const PhantomParams p = default_phantom_params();
  const PhantomModelD model(p);
  RandomStates rs(p);
  const double h = 1e-6;
  double worst = 0.0, worst_inv = 0.0;
  for (int s = 0; s < 200; ++s) {
    const Vec6 q = rs.q();
    Mat6 fd;
    for (int j = 0; j < 6; ++j) {
      Vec3 xa, xb;
      Mat3 Ra, Rb;
      model.fk(q + h * Vec6::Unit(j), &xa, &Ra);
      model.fk(q - h * Vec6::Unit(j), &xb, &Rb);
      fd.col(j) << (xa - xb) / (2 * h), log_so3(Rb.transpose() * Ra) / (2 * h);
    }
    const Mat6 J = model.tool_jacobian(q);
    worst = std::max(worst, rel_err(J, fd));
    worst_inv = std::max(worst_inv, (model.J1(q) * J - Mat6::Identity()).cwiseAbs().maxCoeff());
  }
  std::printf("J_t vs fd %.3e, |J1 J_t - I| %.3e\n", worst, worst_inv);
  EXPECT_LT(worst, 1e-8);
  EXPECT_LT(worst_inv, 1e-10);
}

// The default joint-limit box keeps J1 regular (docs/phantom.md): the smallest singular value of
// J_t (mixed units: m/rad and rad/rad; measured 0.0199) stays away from 0 at 2000 random states
// and the 64 box corners; it vanishes at a stretched elbow or gimbal lock.
TEST(PhantomModel, DefaultWorkspaceIsFreeOfSingularities) {
  const PhantomParams p = default_phantom_params();
  const PhantomModelD model(p);
  RandomStates rs(p);
  double smin = 1e300;
  auto check = [&](const Vec6& q) {
    Eigen::JacobiSVD<Mat6> svd(model.tool_jacobian(q));
    smin = std::min(smin, svd.singularValues()(5));
  };
  for (int s = 0; s < 2000; ++s) check(rs.q());
  for (int mask = 0; mask < 64; ++mask) {
    Vec6 q;
    for (int j = 0; j < 6; ++j) q(j) = (mask >> j) & 1 ? p.q_max_rad(j) : p.q_min_rad(j);
    check(q);
  }
  std::printf("smallest singular value of J_t over the box: %.4f\n", smin);
  EXPECT_GT(smin, 0.01);
}

// Known pose: at q = 0 the gimbal centre is at (l1, 0, -l2) (docs/device_facts.md §1) and the arm
// fk x = c1 (l1 c2 + l2 s3), y = s1 (...), z = l1 s2 - l2 c3 holds everywhere.
TEST(PhantomModel, ArmForwardKinematicsMatchesPublished) {
  PhantomParams p = default_phantom_params();
  p.tip_offset_m.setZero();
  p.pitch_pos_m.setZero();
  p.roll_pos_m.setZero();
  const PhantomModelD model(p);
  RandomStates rs(p);
  double worst = 0.0;
  for (int s = 0; s < 200; ++s) {
    const Vec6 q = rs.q();
    Vec3 x;
    model.fk(q, &x, nullptr);
    const double r = p.l1_m * std::cos(q(1)) + p.l2_m * std::sin(q(2));
    const Vec3 ref(std::cos(q(0)) * r, std::sin(q(0)) * r,
                   p.l1_m * std::sin(q(1)) - p.l2_m * std::cos(q(2)));
    worst = std::max(worst, (x - ref).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst, 1e-15);
}

// The DeviceModel adapter returns the same numbers and checks sizes.
TEST(PhantomModel, DeviceModelAdapter) {
  const PhantomModel dev(default_phantom_params());
  const PhantomModelD& m = dev.model();
  RandomStates rs(dev.params());
  const Vec6 q = rs.q(), qd = rs.qd();
  EXPECT_EQ(dev.dof(), 6);
  EXPECT_EQ(MatX(dev.mass_matrix(q)), MatX(m.M(q)));
  EXPECT_EQ(MatX(dev.coriolis_matrix(q, qd)), MatX(m.C(q, qd)));
  EXPECT_EQ(VecX(dev.gravity(q)), VecX(m.g(q)));
  EXPECT_EQ(VecX(dev.friction_torque(q, qd)), VecX(m.friction(qd)));
  EXPECT_EQ(dev.twist_to_joint(q), m.J1(q));
  EXPECT_THROW(dev.mass_matrix(VecX::Zero(5)), std::invalid_argument);
  // Friction: b qd + f_c tanh(qd / v_s).
  const PhantomParams& p = dev.params();
  for (int j = 0; j < 6; ++j) {
    EXPECT_DOUBLE_EQ(m.friction(qd)(j),
                     p.damping_n_m_s_per_rad(j) * qd(j) +
                         p.coulomb_n_m(j) * std::tanh(qd(j) / p.coulomb_smoothing_rad_s(j)));
  }
}

// Without friction and torque, RK4 on forward_dynamics conserves T + U (a check that M, C, g
// are one consistent Lagrangian): the drift over 0.5 s at h = 1e-4 is below 1e-9 of the
// potential-energy swing.
TEST(PhantomModel, FreeMotionConservesEnergy) {
  PhantomParams p = default_phantom_params();
  p.damping_n_m_s_per_rad.setZero();
  p.coulomb_n_m.setZero();
  const PhantomModelD model(p);
  RandomStates rs(p);
  Vec6 q = rs.q(), qd = rs.qd(2.0);
  const double e0 = model.kinetic_energy(q, qd) + model.potential_energy(q);
  const double h = 1e-4;
  double drift = 0.0, swing = 0.0;
  const double u0 = model.potential_energy(q);
  for (int k = 0; k < 5000; ++k) {
    auto f = [&](const Vec6& x, const Vec6& v) {
      return model.forward_dynamics(x, v, Vec6::Zero());
    };
    const Vec6 k1x = qd, k1v = f(q, qd);
    const Vec6 k2x = qd + 0.5 * h * k1v, k2v = f(q + 0.5 * h * k1x, qd + 0.5 * h * k1v);
    const Vec6 k3x = qd + 0.5 * h * k2v, k3v = f(q + 0.5 * h * k2x, qd + 0.5 * h * k2v);
    const Vec6 k4x = qd + h * k3v, k4v = f(q + h * k3x, qd + h * k3v);
    q += h / 6 * (k1x + 2 * k2x + 2 * k3x + k4x);
    qd += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
    const double e = model.kinetic_energy(q, qd) + model.potential_energy(q);
    drift = std::max(drift, std::abs(e - e0));
    swing = std::max(swing, std::abs(model.potential_energy(q) - u0));
  }
  std::printf("energy drift %.3e J over an exchange of %.3e J\n", drift, swing);
  EXPECT_GT(swing, 1e-3);  // the motion exchanges real energy (not trivially true)
  EXPECT_LT(drift, 1e-9 * swing);
}

// ceres::Jet: dM/dm_forearm through the template equals a finite difference (M is linear in m).
TEST(PhantomModel, JetDerivativeOfMassMatrixMatchesFiniteDifference) {
  using Jet = ceres::Jet<double, 2>;
  const PhantomParams p = default_phantom_params();
  PhantomTreeT<Jet> tree = phantom_tree<Jet>(p);
  tree.mass[kForearm].v[0] = 1.0;  // d/d m_a
  tree.armature(1).v[1] = 1.0;     // d/d armature_2
  const PhantomModelT<Jet> jm(tree);
  RandomStates rs(p);
  const double h = 1e-4;
  double worst = 0.0;
  for (int s = 0; s < 50; ++s) {
    const Vec6 q = rs.q();
    const Eigen::Matrix<Jet, 6, 6> Mj = jm.M(q.cast<Jet>());
    PhantomParams a = p, b = p;
    a.forearm.mass_kg += h;
    b.forearm.mass_kg -= h;
    const Mat6 fd = (PhantomModelD(a).M(q) - PhantomModelD(b).M(q)) / (2 * h);
    Mat6 d0, d1, val;
    for (int r = 0; r < 6; ++r) {
      for (int c = 0; c < 6; ++c) {
        d0(r, c) = Mj(r, c).v[0];
        d1(r, c) = Mj(r, c).v[1];
        val(r, c) = Mj(r, c).a;
      }
    }
    worst = std::max(worst, rel_err(d0, fd));
    EXPECT_EQ(d1, Mat6(Vec6::Unit(1).asDiagonal()));
    EXPECT_LT(rel_err(val, PhantomModelD(p).M(q)), 1e-15);
  }
  std::printf("Jet dM/dm_a vs finite difference: max rel %.3e\n", worst);
  EXPECT_LT(worst, 1e-9);
}

}  // namespace
}  // namespace dentsim
