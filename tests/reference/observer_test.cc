// Tests for reference/observer.h (momentum observer (3.7)-(3.8), §4.1.1) on the planar two-link
// arm of reference/two_link_model.h.
//
// The plant is the "continuous" arm: classical RK4 with 20 substeps per 1 ms servo tick, the motor
// torque held over the tick (zero-order hold) and the human force f applied as a known joint
// torque. The observer runs once per tick on the exact samples (q, qd).
// Predictions (docs/derivations/decomposition_and_observer.md):
//   step f at t = 0:        f_hat_k = f (1 - (1 - L T)^k) ~ f (1 - e^{-L t_k}), 63 % at t ~ 1/L
//   model damping B + dB:   steady f_hat = f + dB qd
//   f = 0, moving arm:      f_hat ~ 0 (trapezoid residual only)
#include "reference/observer.h"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>

#include "reference/core/so3.h"
#include "reference/rigid_body_device.h"
#include "reference/two_link_model.h"

namespace dentsim {
namespace {

constexpr int kSubsteps = 20;

unsigned seed_for(unsigned offset) {
  const int flag = GTEST_FLAG_GET(random_seed);
  const unsigned base = flag != 0 ? static_cast<unsigned>(flag) : 1u;
  std::printf("[ seed ] %u (re-run: --gtest_random_seed=%u)\n", base + offset, base);
  return base + offset;
}

VecX v2(double a, double b) {
  VecX v(2);
  v << a, b;
  return v;
}

// Advances the plant over one tick of length T with tau + f held.
void plant_tick(const DeviceModel& arm, const VecX& tau, const VecX& f, double T, VecX& q,
                VecX& qd) {
  for (int j = 0; j < kSubsteps; ++j) rk4_step(arm, tau + f, T / kSubsteps, q, qd);
}

TEST(TwoLinkArm, ChristoffelIdentityDmDtEqualsCPlusCTranspose) {
  const TwoLinkArm arm;
  std::mt19937 rng(seed_for(21));
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  double worst = 0.0;
  for (int i = 0; i < 500; ++i) {
    const VecX q = v2(u(rng), u(rng)), qd = v2(u(rng), u(rng));
    const double h = 1e-5;
    const MatX dM = (arm.mass_matrix(q + h * qd) - arm.mass_matrix(q - h * qd)) / (2.0 * h);
    const MatX C = arm.coriolis_matrix(q, qd);
    const double err = (dM - C - C.transpose()).norm() / std::max(1e-12, dM.norm());
    worst = std::max(worst, err);
    ASSERT_LT((dM - C - C.transpose()).norm(), 1e-8 * (1.0 + dM.norm())) << i;
    // M SPD, and C qd are the Christoffel terms: qd^T (dM/dt / 2 - C) qd = 0.
    const MatX M = arm.mass_matrix(q);
    ASSERT_GT(M.determinant(), 0.0);
    ASSERT_GT(M(0, 0), 0.0);
    ASSERT_NEAR(qd.dot((0.5 * dM - C) * qd), 0.0, 1e-8 * (1.0 + qd.squaredNorm()));
  }
  std::printf("max |dM/dt - C - C^T| / |dM/dt| = %.3g\n", worst);
}

TEST(TwoLinkArm, GravityIsTheGradientOfThePotential) {
  const TwoLinkArm arm;
  std::mt19937 rng(seed_for(22));
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  for (int i = 0; i < 200; ++i) {
    const VecX q = v2(u(rng), u(rng));
    const double h = 1e-6;
    const VecX g = arm.gravity(q);
    for (int j = 0; j < 2; ++j) {
      VecX dq = VecX::Zero(2);
      dq(j) = h;
      const double fd = (arm.potential_energy(q + dq) - arm.potential_energy(q - dq)) / (2 * h);
      ASSERT_NEAR(g(j), fd, 1e-7) << i;
    }
  }
}

TEST(TwoLinkArm, PlantEnergyBalance) {
  // dE/dt = qd^T (tau - tau_f): checks M, C, g of the plant together (and the RK4 plant).
  const TwoLinkArm arm;
  VecX q = v2(-0.4, 0.9), qd = v2(1.0, -2.0);
  const double T = 1e-3;
  const double E0 = arm.kinetic_energy(q, qd) + arm.potential_energy(q);
  double work = 0.0;  // int qd^T (tau - tau_f) dt, by the trapezoid on 0.05 ms substeps
  for (int k = 0; k < 1000; ++k) {
    const VecX tau = v2(0.3 * std::sin(7.0 * k * T), -0.2 * std::cos(5.0 * k * T));
    for (int j = 0; j < kSubsteps; ++j) {
      const double h = T / kSubsteps;
      const double p0 = qd.dot(tau - arm.friction_torque(q, qd));
      rk4_step(arm, tau, h, q, qd);
      const double p1 = qd.dot(tau - arm.friction_torque(q, qd));
      work += 0.5 * h * (p0 + p1);
    }
  }
  const double E1 = arm.kinetic_energy(q, qd) + arm.potential_energy(q);
  std::printf("energy change %.9f J, work %.9f J\n", E1 - E0, work);
  EXPECT_NEAR(E1 - E0, work, 1e-6 * std::abs(work) + 1e-8);
  EXPECT_GT(std::abs(work), 0.05);
}

TEST(MomentumObserver, StepForceIsTrackedAsFirstOrderLag) {
  const TwoLinkArm arm;
  const VecX L = v2(40.0, 60.0);  // [1/s]
  const double T = 1e-3;
  const VecX f = v2(0.3, -0.15);  // step at t = 0 [N m]
  VecX q = v2(-0.5, 0.8), qd = VecX::Zero(2);
  MomentumObserver obs(arm, L);
  obs.reset(q, qd);
  double max_cont = 0.0, max_disc = 0.0;
  VecX t63 = VecX::Constant(2, -1.0);
  for (int k = 1; k <= 250; ++k) {
    const VecX tau = arm.gravity(q);  // gravity compensation from the sample, held
    plant_tick(arm, tau, f, T, q, qd);
    const VecX& fh = obs.update(q, qd, tau, T);
    const double t = k * T;
    for (int i = 0; i < 2; ++i) {
      const double cont = f(i) * (1.0 - std::exp(-L(i) * t));
      const double disc = f(i) * (1.0 - std::pow(1.0 - L(i) * T, k));
      max_cont = std::max(max_cont, std::abs(fh(i) - cont) / std::abs(f(i)));
      max_disc = std::max(max_disc, std::abs(fh(i) - disc) / std::abs(f(i)));
      if (t63(i) < 0.0 && fh(i) / f(i) >= 1.0 - std::exp(-1.0)) t63(i) = t;
    }
  }
  std::printf(
      "max |f_hat - f(1-e^{-Lt})|/|f| = %.4g, max |f_hat - f(1-(1-LT)^k)|/|f| = %.3g, "
      "63%% times %.4f s, %.4f s (1/L = %.4f, %.4f); arm moved to q = (%.3f, %.3f)\n",
      max_cont, max_disc, t63(0), t63(1), 1.0 / L(0), 1.0 / L(1), q(0), q(1));
  EXPECT_LT(max_cont, 0.02);  // within 2 % of the step of the continuous lag
  EXPECT_LT(max_disc, 1e-3);  // and the sampled lag it actually is, to 0.1 % (measured 0.02 %)
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(t63(i), 1.0 / L(i), 1.5 * T);
  }
  EXPECT_GT((q - v2(-0.5, 0.8)).norm(), 0.05);  // the arm really moved
}

TEST(MomentumObserver, VaryingTickLengthFollowsTheSampledLag) {
  // T_k varies tick to tick: f_hat_k = f (1 - prod_j (1 - L T_j)).
  const TwoLinkArm arm;
  std::mt19937 rng(seed_for(23));
  std::uniform_real_distribution<double> u(0.5e-3, 1.5e-3);
  const VecX L = v2(50.0, 30.0);
  const VecX f = v2(-0.2, 0.1);
  VecX q = v2(0.3, -1.0), qd = v2(0.5, 0.5);
  MomentumObserver obs(arm, L);
  obs.reset(q, qd);
  VecX prod = VecX::Ones(2);
  double worst = 0.0;
  for (int k = 0; k < 300; ++k) {
    const double T = u(rng);
    const VecX tau = v2(0.1 * std::sin(10.0 * k * 1e-3), 0.05);
    plant_tick(arm, tau, f, T, q, qd);
    const VecX& fh = obs.update(q, qd, tau, T);
    for (int i = 0; i < 2; ++i) {
      prod(i) *= 1.0 - L(i) * T;
      worst = std::max(worst, std::abs(fh(i) - f(i) * (1.0 - prod(i))));
    }
  }
  std::printf("max |f_hat - f(1 - prod(1 - L T_j))| = %.3g N m (steps %.2f, %.2f N m)\n", worst,
              f(0), f(1));
  // The residual is the trapezoid's O(T^2) error on the arm swinging under gravity: the same
  // 5e-4 N m bound as the zero-force test (0.5 % of the smaller step).
  EXPECT_LT(worst, 5e-4);
}

TEST(MomentumObserver, WrongModelDampingBiasesByDeltaBTimesVelocity) {
  const TwoLinkArm arm;  // the true plant
  TwoLinkParams wrong = arm.params();
  const VecX dB = v2(0.02, -0.015);  // model damping error [N m s/rad]
  wrong.b1 += dB(0);
  wrong.b2 += dB(1);
  const TwoLinkArm model(wrong);
  const VecX L = v2(40.0, 40.0);
  const double T = 1e-3;
  const VecX f = v2(0.05, -0.03);  // constant human force
  const VecX qd_ref = v2(1.5, -2.5);
  const double K = 2.0;  // velocity-loop gain [N m s/rad]
  VecX q = v2(0.0, 0.5), qd = VecX::Zero(2);
  MomentumObserver obs(model, L);
  obs.reset(q, qd);
  for (int k = 0; k < 1500; ++k) {
    // Velocity servo with exact model feed-forward: M qdd = K (qd_ref - qd) + f.
    const VecX tau = arm.coriolis_matrix(q, qd) * qd + arm.gravity(q) + arm.friction_torque(q, qd) +
                     K * (qd_ref - qd);
    plant_tick(arm, tau, f, T, q, qd);
    obs.update(q, qd, tau, T);
  }
  const VecX bias = obs.estimate() - f;
  const VecX predicted = dB.cwiseProduct(qd);
  std::printf("qd = (%.4f, %.4f) rad/s; bias = (%.6f, %.6f), predicted dB qd = (%.6f, %.6f)\n",
              qd(0), qd(1), bias(0), bias(1), predicted(0), predicted(1));
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(bias(i), predicted(i), 0.05 * std::abs(predicted(i)));
  }
  // Guard: the bias is a real signal, several times the estimator's resolution.
  EXPECT_GT(predicted.cwiseAbs().minCoeff(), 0.02);
}

TEST(MomentumObserver, ZeroExternalForceOnAMovingArmGivesSmallEstimate) {
  const TwoLinkArm arm;
  const VecX L = v2(50.0, 50.0);
  const double T = 1e-3;
  VecX q = v2(0.2, 0.3), qd = v2(0.0, 3.0);
  MomentumObserver obs(arm, L);
  obs.reset(q, qd);
  double max_fh = 0.0, max_tau = 0.0, max_g = 0.0, max_qd = 0.0;
  const VecX zero = VecX::Zero(2);
  for (int k = 0; k < 3000; ++k) {
    // Uncompensated arm swinging under gravity, plus a motor excitation.
    const double t = k * T;
    const VecX tau = v2(0.8 * std::sin(6.0 * t), 0.3 * std::sin(11.0 * t + 0.4));
    plant_tick(arm, tau, zero, T, q, qd);
    const VecX& fh = obs.update(q, qd, tau, T);
    max_fh = std::max(max_fh, fh.cwiseAbs().maxCoeff());
    max_tau = std::max(max_tau, tau.cwiseAbs().maxCoeff());
    max_g = std::max(max_g, arm.gravity(q).cwiseAbs().maxCoeff());
    max_qd = std::max(max_qd, qd.cwiseAbs().maxCoeff());
  }
  std::printf(
      "max |f_hat| = %.3g N m with max |tau| = %.3g, max |g| = %.3g N m, max |qd| = %.3g "
      "rad/s\n",
      max_fh, max_tau, max_g, max_qd);
  EXPECT_LT(max_fh, 5e-4);  // below 0.02 % of the gravity torque swinging the arm
  EXPECT_GT(max_g, 2.0);
  EXPECT_GT(max_qd, 3.0);
}

TEST(MomentumObserver, RectangleRuleOnBetaWouldBeBiased) {
  // Documents why the trapezoid is used: on the swinging arm a rectangle-rule observer (beta at
  // the previous sample only) is biased by ~T/2 dbeta/dt, far above the trapezoid's residual.
  const TwoLinkArm arm;
  const VecX L = v2(50.0, 50.0);
  const double T = 1e-3;
  VecX q = v2(0.2, 0.3), qd = v2(0.0, 3.0);
  MomentumObserver obs(arm, L);
  obs.reset(q, qd);
  VecX p_hat = arm.mass_matrix(q) * qd, f_rect = VecX::Zero(2);
  double max_trap = 0.0, max_rect = 0.0;
  for (int k = 0; k < 2000; ++k) {
    const VecX beta_prev = obs.beta(q, qd);
    plant_tick(arm, VecX::Zero(2), VecX::Zero(2), T, q, qd);
    p_hat += T * (beta_prev + f_rect);
    f_rect = L.asDiagonal() * (arm.mass_matrix(q) * qd - p_hat);
    const VecX& fh = obs.update(q, qd, VecX::Zero(2), T);
    max_trap = std::max(max_trap, fh.cwiseAbs().maxCoeff());
    max_rect = std::max(max_rect, f_rect.cwiseAbs().maxCoeff());
  }
  std::printf("zero-force estimate: trapezoid max %.3g N m, rectangle rule max %.3g N m\n",
              max_trap, max_rect);
  EXPECT_LT(10.0 * max_trap, max_rect);
}

TEST(MomentumObserver, SixDofDeviceHumanWrenchInMaximalCoordinates) {
  // The 6-DoF rigid-body device (reference/rigid_body_device.h, q-dependent M and C): a constant
  // human wrench F1 (maximal coordinates) enters as the joint force f = J1^-T F1, held per tick;
  // F1_hat = J1^T f_hat (joint_to_wrench) tracks F1 as the sampled lag of every joint.
  RigidBodyDeviceParams prm;
  prm.damping_lin = 0.5;
  prm.damping_ang = 2e-4;
  prm.gravity = 9.81;
  const RigidBodyDevice dev(prm);
  Pose pose;
  pose.x = Vec3(0.02, -0.01, 0.05);
  pose.R = exp_so3(Vec3(0.3, -0.5, 0.8));
  VecX q = dev.joint_position(pose);
  VecX qd = dev.joint_velocity(q, (Vec6() << 0.05, 0.0, -0.02, 0.5, -0.3, 0.2).finished());
  const Vec6 F1 = (Vec6() << 0.5, -0.2, 0.3, 2e-3, -1e-3, 1e-3).finished();
  const double T = 1e-3, Lg = 50.0;
  MomentumObserver obs(dev, VecX::Constant(6, Lg));
  obs.reset(q, qd);
  double worst = 0.0, worst_joint = 0.0;
  VecX f_pred = VecX::Zero(6);  // the sampled lag applied to the (slowly varying) joint force
  const Pose start = dev.forward_kinematics(q);
  for (int k = 1; k <= 200; ++k) {
    const Mat6 J1 = dev.twist_to_joint(q);
    const VecX f = J1.transpose().partialPivLu().solve(F1);  // f = J1^-T F1, held
    const VecX tau = dev.gravity(q);                         // gravity compensation, held
    plant_tick(dev, tau, f, T, q, qd);
    const VecX& fh = obs.update(q, qd, tau, T);
    f_pred = (1.0 - Lg * T) * f_pred + Lg * T * f;
    worst_joint =
        std::max(worst_joint, (fh - f_pred).cwiseAbs().maxCoeff() / f.cwiseAbs().maxCoeff());
    const Vec6 F1_hat = joint_to_wrench(dev.twist_to_joint(q), fh);
    const Vec6 expected = F1 * (1.0 - std::pow(1.0 - Lg * T, k));
    for (int i = 0; i < 6; ++i) {
      worst = std::max(worst, std::abs(F1_hat(i) - expected(i)) / std::abs(F1(i)));
    }
  }
  const Pose end = dev.forward_kinematics(q);
  std::printf(
      "6-DoF device: joint space max |f_hat - lag(f)|/max|f| = %.3g; maximal coordinates "
      "max |F1_hat - F1(1-(1-LT)^k)|/|F1| per component = %.3g; tip moved %.3f m, turned "
      "%.3f rad\n",
      worst_joint, worst, (end.x - start.x).norm(), rotation_angle(start.R.transpose() * end.R));
  // Joint space: the observer is the sampled lag of the joint force it sees (the residual is the
  // trapezoid error and the ~1e-9 finite-difference C of the device model).
  EXPECT_LT(worst_joint, 1e-4);  // measured 1.5e-6
  // Maximal coordinates: f = J1^-T F1 turns with the device, so F1_hat also carries the lag of
  // that change (~|df/dt| / L); within 2 % of each component.
  EXPECT_LT(worst, 0.02);
  EXPECT_GT(rotation_angle(start.R.transpose() * end.R), 0.1);
}

TEST(MomentumObserver, RejectsBadInput) {
  const TwoLinkArm arm;
  EXPECT_THROW(MomentumObserver(arm, VecX::Ones(3)), std::invalid_argument);
  EXPECT_THROW(MomentumObserver(arm, v2(10.0, 0.0)), std::invalid_argument);
  EXPECT_THROW(MomentumObserver(arm, v2(10.0, std::nan(""))), std::invalid_argument);
  MomentumObserver obs(arm, v2(10.0, 10.0));
  EXPECT_THROW(obs.update(v2(0, 0), v2(0, 0), v2(0, 0), 1e-3), std::logic_error);
  obs.reset(v2(0, 0), v2(0, 0));
  EXPECT_THROW(obs.update(v2(0, 0), v2(0, 0), v2(0, 0), 0.0), std::invalid_argument);
  EXPECT_THROW(obs.update(VecX::Zero(3), v2(0, 0), v2(0, 0), 1e-3), std::invalid_argument);
}

TEST(MomentumObserver, JointToWrenchPreservesPower) {
  std::mt19937 rng(seed_for(24));
  std::normal_distribution<double> n(0.0, 1.0);
  for (int i = 0; i < 100; ++i) {
    Mat6 J1;
    for (int j = 0; j < 36; ++j) J1(j) = n(rng);
    Vec6 V1;
    VecX f(6);
    for (int j = 0; j < 6; ++j) {
      V1(j) = n(rng);
      f(j) = n(rng);
    }
    const VecX qd = J1 * V1;
    EXPECT_NEAR(V1.dot(joint_to_wrench(J1, f)), qd.dot(f), 1e-12 * (1.0 + std::abs(qd.dot(f))));
  }
}

}  // namespace
}  // namespace dentsim
