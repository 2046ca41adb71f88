// Tests for fast/pmi.h: the PMI solve (4.9) by partial-pivoting LU of the scaled system, against
// the reference's full-pivoting pmi_try_solve (reference/pmi.h) on random and adversarial systems,
// and on its own physics (the discrete energy balance of PMI on a spring).
//
// Tolerances (docs/tolerance_policy.md item 2): two backward-stable solves of the same scaled
// system D A D y = D b differ by at most c * eps * n * kappa(D A D) * |y| (forward error of each
// <= that, n = 6, c = 10); the energy balance of PMI is exact in exact arithmetic, so its residual
// per tick is bounded by c * eps * (the energy level) with c = 100, growing linearly with ticks.
// Seeds fixed and printed.
#include "fast/pmi.h"

#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

#include "reference/pmi.h"
#include "tests/support/random.h"

namespace dentsim {
namespace {

using Rng = std::mt19937_64;
constexpr double kEps = 2.220446049250313e-16;

double uni(Rng& rng, double a, double b) { return testing::uniform(rng, a, b); }

// A system of the tick's kind: the proxy's inertia (4.2), a coupling / contact term G = -S (S
// symmetric positive semidefinite, rank <= 6, stiffness spanning `decades` orders), a
// non-symmetric feed-forward term and the gyroscopic skew term.
PmiSystem random_system(Rng& rng, double T, double decades) {
  ProxyParams p;
  p.mass = std::pow(10.0, uni(rng, -3.0, 0.0));
  p.inertia = Vec3(uni(rng, 0.5, 2.0), uni(rng, 0.5, 2.0), uni(rng, 0.5, 2.0)).asDiagonal() *
              std::pow(10.0, uni(rng, -7.0, -4.0));
  p.damping_lin = uni(rng, 0.0, 5.0);
  p.gyroscopic = true;
  ProxyState s;
  for (int i = 0; i < 6; ++i) s.V(i) = uni(rng, -1.0, 1.0);
  PmiSystem sys = pmi_inertia_system_unchecked(p, s, T);
  AffineWrench F;
  Mat6 L;
  for (int i = 0; i < 36; ++i) L(i) = uni(rng, -1.0, 1.0);
  const Vec6 scale =
      Vec6::NullaryExpr([&](Eigen::Index) { return std::pow(10.0, uni(rng, 0.0, decades)); });
  F.G = -(scale.asDiagonal() * L * L.transpose() * scale.asDiagonal()) * T;
  Mat6 N;
  for (int i = 0; i < 36; ++i) N(i) = uni(rng, -1.0, 1.0) * 1e-3;
  F.G += N;
  for (int i = 0; i < 6; ++i) F.f0(i) = uni(rng, -10.0, 10.0);
  sys.add(F);
  return sys;
}

// |fast - reference|_inf / (c eps n kappa |V|_inf) with kappa the 2-norm condition number of the
// scaled system (both solve it).
double compare(const PmiSystem& sys) {
  Vec6 a, b;
  const bool ok_ref = pmi_try_solve(sys, &a);
  const bool ok_fast = fast::pmi_try_solve(sys, &b);
  EXPECT_EQ(ok_ref, ok_fast);
  if (!ok_ref || !ok_fast) return 0.0;
  const Vec6 d = pmi_scaling(sys.A);
  const Mat6 As = d.asDiagonal() * sys.A * d.asDiagonal();
  const Eigen::JacobiSVD<Mat6> svd(As);
  const double kappa = svd.singularValues()(0) / svd.singularValues()(5);
  // Compare in the scaled unknowns y = D^-1 V (the units the solve works in).
  const Vec6 ya = a.cwiseQuotient(d), yb = b.cwiseQuotient(d);
  return (ya - yb).cwiseAbs().maxCoeff() / (10.0 * kEps * 6.0 * kappa * ya.cwiseAbs().maxCoeff());
}

TEST(FastPmi, RandomSystemsEqualTheReferenceWithinRoundOff) {
  const unsigned seed = 31;
  Rng rng(seed);
  double worst = 0.0;
  for (int trial = 0; trial < 3000; ++trial) {
    const double T = std::pow(10.0, uni(rng, -5.0, -2.0));
    worst = std::max(worst, compare(random_system(rng, T, uni(rng, 0.0, 8.0))));
  }
  std::printf("seed %u: worst |fast - reference| / bound = %.3e over 3000 systems\n", seed, worst);
  EXPECT_LE(worst, 1.0) << "seed " << seed;
}

TEST(FastPmi, AdversarialSystemsAgreeWithTheReference) {
  Rng rng(5);
  Vec6 V;
  // Not finite: both refuse.
  for (double bad :
       {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
        -std::numeric_limits<double>::infinity()}) {
    PmiSystem s = random_system(rng, 1e-3, 2.0);
    s.A(2, 3) = bad;
    EXPECT_FALSE(fast::pmi_try_solve(s, &V));
    EXPECT_FALSE(pmi_try_solve(s, &V));
    s = random_system(rng, 1e-3, 2.0);
    s.b(4) = bad;
    EXPECT_FALSE(fast::pmi_try_solve(s, &V));
    EXPECT_FALSE(pmi_try_solve(s, &V));
  }
  // Exactly singular: a zero row and column; two equal rows and columns; all zero.
  {
    PmiSystem s = random_system(rng, 1e-3, 2.0);
    s.A.row(1).setZero();
    s.A.col(1).setZero();
    EXPECT_FALSE(fast::pmi_try_solve(s, &V));
    EXPECT_FALSE(pmi_try_solve(s, &V));
    PmiSystem e;
    e.A = Mat6::Identity();
    e.A.block<2, 2>(3, 3).setConstant(2.0);
    EXPECT_FALSE(fast::pmi_try_solve(e, &V));
    EXPECT_FALSE(pmi_try_solve(e, &V));
    PmiSystem z;
    EXPECT_FALSE(fast::pmi_try_solve(z, &V));
    EXPECT_FALSE(pmi_try_solve(z, &V));
  }
  // Solvable extremes: b = 0 gives V = 0 exactly; a diagonal system; tick lengths 1e-6 to 1 s;
  // stiffness spanning 12 orders; a negative diagonal entry (scaling by |A_ii|).
  double worst = 0.0;
  {
    PmiSystem s = random_system(rng, 1e-3, 4.0);
    s.b.setZero();
    Vec6 a, b;
    ASSERT_TRUE(fast::pmi_try_solve(s, &b));
    ASSERT_TRUE(pmi_try_solve(s, &a));
    EXPECT_EQ(b, Vec6::Zero());
    PmiSystem d;
    d.A = Vec6(1e-9, 1.0, 1e9, 3.0, -2.0, 1e-3).asDiagonal();
    d.b = Vec6(1.0, -2.0, 3.0, -4.0, 5.0, -6.0);
    ASSERT_TRUE(fast::pmi_try_solve(d, &b));
    ASSERT_TRUE(pmi_try_solve(d, &a));
    worst = std::max(worst, compare(d));
    EXPECT_NEAR(b(2), 3e-9, 4 * kEps * 3e-9);
  }
  for (double T : {1e-6, 1e-5, 1e-2, 1.0}) {
    for (int i = 0; i < 50; ++i) worst = std::max(worst, compare(random_system(rng, T, 12.0)));
  }
  std::printf("adversarial: worst |fast - reference| / bound = %.3e\n", worst);
  EXPECT_LE(worst, 1.0);
}

// Physics: a proxy on a linear spring to an anchor (PMI form: f = -k (x_hat - a), the midpoint
// position, f0 = -k (x_k - a), G = -k T/2 I), advanced with the fast solve. PMI's discrete energy
// balance (reference/pmi.h (2.6)): without damping, 1/2 m v^2 + 1/2 k |x - a|^2 is conserved to
// round-off at any tick length — including T = 10 ms with k = 1e5 N/m, where omega T = 14 and
// explicit Euler diverges; with damping b it decreases every tick by exactly T b |v_hat|^2.
TEST(FastPmi, SpringEnergyIsConservedOrDissipatedExactly) {
  for (double T : {1e-3, 1e-2}) {
    for (double b : {0.0, 2.0}) {
      ProxyParams p;
      p.mass = 0.05;
      p.damping_lin = b;
      const double k = 1e5;
      const Vec3 anchor(0.01, -0.02, 0.03);
      ProxyState s;
      s.pose.x = anchor + Vec3(2e-3, -1e-3, 5e-4);
      s.V << 0.1, 0.05, -0.2, 0.0, 0.0, 0.0;
      auto energy = [&](const ProxyState& st) {
        return 0.5 * p.mass * st.V.head<3>().squaredNorm() +
               0.5 * k * (st.pose.x - anchor).squaredNorm();
      };
      const double E0 = energy(s);
      double worst_residual = 0.0, E = E0;
      long increases = 0;
      const int ticks = 5000;
      for (int i = 0; i < ticks; ++i) {
        PmiSystem sys = pmi_inertia_system_unchecked(p, s, T);
        AffineWrench spring;
        spring.f0.head<3>() = -k * (s.pose.x - anchor);
        spring.G.topLeftCorner<3, 3>() = -k * 0.5 * T * Mat3::Identity();
        sys.add(spring);
        Vec6 V_hat;
        ASSERT_TRUE(fast::pmi_try_solve(sys, &V_hat)) << "tick " << i;
        s = pmi_advance_unchecked(s, V_hat, T);
        const double E1 = energy(s);
        const double dissipated = T * b * V_hat.head<3>().squaredNorm();
        worst_residual = std::max(worst_residual, std::abs(E1 - E + dissipated));
        if (E1 > E + 100.0 * kEps * E0) ++increases;  // beyond round-off
        E = E1;
      }
      std::printf("T %.0e s, b %.1f: E0 %.4e J, E_end %.4e J, worst per-tick residual %.2e J\n", T,
                  b, E0, E, worst_residual);
      EXPECT_LE(worst_residual, 100.0 * kEps * E0) << "T " << T << " b " << b;
      if (b == 0.0) {
        EXPECT_LE(std::abs(E - E0), 100.0 * kEps * E0 * ticks);
      } else {
        EXPECT_EQ(increases, 0);
        EXPECT_LT(E, 0.5 * E0);  // the signal: damping removed most of the energy
      }
    }
  }
}

}  // namespace
}  // namespace dentsim
