// Tests for reference/grasp_mass_model.h on the analytic Phantom model: the added tip mass's
// kinetic energy, the Christoffel identity dM/dt = C + C^T, and the observer seeing no human
// force from the mass when its model carries it (and -m a when it does not).
#include "reference/grasp_mass_model.h"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>

#include "reference/observer.h"
#include "reference/phantom/phantom_model.h"
#include "reference/two_link_model.h"

namespace dentsim {
namespace {

constexpr double kMass = 0.554;    // the literature hand (device/scripted_hand.h)
constexpr double kInertia = 2e-4;  // [kg m^2]

VecX random_q(const PhantomParams& p, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  VecX q(6);
  // Inner 60 % of the joint ranges (away from the singular edges).
  for (int j = 0; j < 6; ++j) {
    q(j) = p.q_min_rad(j) + (0.2 + 0.6 * u(rng)) * (p.q_max_rad(j) - p.q_min_rad(j));
  }
  return q;
}

// A random joint state: q in the inner joint ranges, |qd_j| < 2 rad/s.
void random_state(std::mt19937& rng, VecX& q, VecX& qd) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  q = random_q(default_phantom_params(), rng);
  qd.resize(6);
  for (int j = 0; j < 6; ++j) qd(j) = 2.0 * u(rng);
}

TEST(GraspMassModel, AddsTheTipMassKineticEnergy) {
  const PhantomModel base(default_phantom_params());
  const GraspMassModel model(base, kMass, kInertia);
  std::mt19937 rng(3);
  double worst = 0.0;
  for (int i = 0; i < 200; ++i) {
    VecX q, qd;
    random_state(rng, q, qd);
    const Vec6 V = base.twist_to_joint(q).partialPivLu().solve(Vec6(qd));
    const double expected = 0.5 * (kMass * V.head<3>().squaredNorm() +
                                   kInertia * V.tail<3>().squaredNorm());
    const double added = 0.5 * qd.dot((model.mass_matrix(q) - base.mass_matrix(q)) * qd);
    worst = std::max(worst, std::abs(added - expected) / expected);
  }
  std::printf("max relative error of the added kinetic energy: %.3g\n", worst);
  EXPECT_LT(worst, 1e-10);
}

TEST(GraspMassModel, ChristoffelIdentityHolds) {
  const PhantomModel base(default_phantom_params());
  const GraspMassModel model(base, kMass, kInertia);
  std::mt19937 rng(4);
  double worst = 0.0;
  for (int i = 0; i < 100; ++i) {
    VecX q, qd;
    random_state(rng, q, qd);
    const double h = 1e-5;
    const MatX dM = (model.mass_matrix(q + h * qd) - model.mass_matrix(q - h * qd)) / (2.0 * h);
    const MatX C = model.coriolis_matrix(q, qd);
    worst = std::max(worst, (dM - C - C.transpose()).norm() / dM.norm());
  }
  std::printf("max |dM/dt - C - C^T| / |dM/dt| = %.3g\n", worst);
  EXPECT_LT(worst, 1e-5);  // two nested central differences (h = 1e-5, 1e-6)
}

TEST(GraspMassModel, ObserverSeesNoForceFromAModelledTipMass) {
  // Plant: the Phantom with the hand's mass on the tip, gravity off, random torques held per
  // tick, no human force. The observer with the grasp mass in its model estimates ~0; without it
  // the estimate is the mass's inertial reaction -m a (order m |a|).
  PhantomParams p = default_phantom_params();
  p.gravity_on = false;
  const PhantomModel base(p);
  const GraspMassModel plant(base, kMass, kInertia);
  MomentumObserver with_mass(plant, VecX::Constant(6, 200.0));
  MomentumObserver without(base, VecX::Constant(6, 200.0));
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  VecX q = VecX::Zero(6), qd = VecX::Zero(6);  // the Z-width start pose
  with_mass.reset(q, qd);
  without.reset(q, qd);
  const double T = 1e-3;
  double max_with = 0.0, max_without = 0.0, max_tau = 0.0;
  VecX tau = VecX::Zero(6);
  for (int k = 0; k < 500; ++k) {
    if (k % 50 == 0) {
      for (int j = 0; j < 6; ++j) tau(j) = 0.02 * u(rng) * (j < 3 ? 5.0 : 0.5);
    }
    for (int s = 0; s < 20; ++s) rk4_step(plant, tau, T / 20, q, qd);
    max_with = std::max(max_with, with_mass.update(q, qd, tau, T).cwiseAbs().maxCoeff());
    max_without = std::max(max_without, without.update(q, qd, tau, T).cwiseAbs().maxCoeff());
    max_tau = std::max(max_tau, tau.cwiseAbs().maxCoeff());
  }
  std::printf("max |f_hat|: model with the grasp mass %.3g N m, without %.3g N m (|tau| <= %.3g)\n",
              max_with, max_without, max_tau);
  EXPECT_LT(max_with, 1e-3 * max_tau);
  EXPECT_GT(max_without, 0.1 * max_tau);
}

TEST(GraspMassModel, RejectsBadMass) {
  const PhantomModel base(default_phantom_params());
  EXPECT_THROW(GraspMassModel(base, -0.1, 0.0), std::invalid_argument);
  EXPECT_THROW(GraspMassModel(base, 0.5, std::nan("")), std::invalid_argument);
}

}  // namespace
}  // namespace dentsim
