// Tests for reference/friction.h: constraint-based Coulomb friction (2.20)-(2.22), (4.10).
//
// The PMI system (4.9) is assembled locally: A = M 2/T (+ coupling-like terms in the property
// test) - G, b = M 2/T V_k + f0, with gravity as a constant AffineWrench and the contact wrench of
// reference/contact.h; then V_k+1 = 2 V_hat - V_k, x_k+1 = x_k + T v_hat (2.7). Seeds are fixed
// and printed.
#include "reference/friction.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <vector>

#include "reference/contact.h"
#include "reference/core/io.h"
#include "reference/core/so3.h"
#include "tests/support/friction_cases.h"
#include "tests/support/stress.h"

namespace dentsim {
namespace {

using Rng = std::mt19937_64;
constexpr double kG = 9.81;
constexpr double kPi = std::numbers::pi;

double uni(Rng& rng, double a, double b) {
  return std::uniform_real_distribution<double>(a, b)(rng);
}

Vec3 random_unit(Rng& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  return Vec3(g(rng), g(rng), g(rng)).normalized();
}

Mat6 block_inertia() { return block_diag(0.05 * Mat3::Identity(), 2e-5 * Mat3::Identity()); }

// A block (point contact at its centre, r = 0) resting on a plane tilted by theta about the world
// y axis, gravity -g z. Returns the final displacement after `ticks` PMI ticks; records the
// largest tangential contact-point velocity and whether any tick slid.
struct SlopeRun {
  Vec3 displacement = Vec3::Zero();
  Vec3 velocity = Vec3::Zero();
  double max_tangential_speed = 0.0;
  bool any_sliding = false;
  bool all_sliding = true;
  double max_cone_ratio = 0.0;  // max |f_t| / (mu f_n)
};

// kMidpoint: PMI (4.9), V = V_hat. kExplicit: the explicit-Euler baseline, A = M / T,
// b = M / T V_k + F(V_k), V = V_k+1, x_k+1 = x_k + T V_k+1 (the friction solve is the same).
SlopeRun run_slope(double theta, double mu, int ticks, double T,
                   Scheme scheme = Scheme::kMidpoint) {
  const Mat6 M = block_inertia();
  const double m = M(0, 0), K = 2e4;
  const Vec3 n(-std::sin(theta), 0.0, std::cos(theta));  // outward plane normal
  const Vec3 gravity(0.0, 0.0, -m * kG);
  Pose pose;
  pose.R = exp_so3(Vec3(0.2, -0.4, 0.3));  // orientation is irrelevant with r = 0
  Contact c;
  c.n = n;
  c.stiffness = K;
  c.damping = 2.0;
  // Start at the equilibrium depth m g cos(theta) / K, at rest.
  c.x_o = pose.x + (m * kG * std::cos(theta) / K) * n;
  const Pose start = pose;
  Vec6 V = Vec6::Zero();
  FrictionParams fp;
  fp.enabled = true;
  fp.mu = mu;
  SlopeRun out;
  for (int k = 0; k < ticks; ++k) {
    const bool pmi = scheme == Scheme::kMidpoint;
    AffineWrench normal = contact_wrench(std::span(&c, 1), pose, T, scheme);
    if (!pmi) normal = AffineWrench{normal.at(V), Mat6::Zero()};  // evaluated at V_k
    PmiSystem sys;
    sys.A = M * ((pmi ? 2.0 : 1.0) / T);
    sys.b = sys.A * V;
    AffineWrench g;
    g.f0 = stack(gravity, Vec3::Zero());
    sys.add(g);
    sys.add(normal);
    const FrictionSolution sol = solve_with_friction(sys, std::span(&c, 1), pose, normal, fp);
    EXPECT_TRUE(sol.active);
    const Vec3 xdot_c = contact_point_jacobian(c.r, pose.R) * sol.V;
    out.max_tangential_speed =
        std::max(out.max_tangential_speed, (xdot_c - n * n.dot(xdot_c)).norm());
    out.any_sliding = out.any_sliding || sol.sliding;
    out.all_sliding = out.all_sliding && sol.sliding;
    out.max_cone_ratio = std::max(out.max_cone_ratio, sol.f_t.norm() / (mu * sol.f_n));
    V = pmi ? Vec6(2.0 * sol.V - V) : sol.V;
    pose.x += T * lin(sol.V);
    pose.R = pose.R * exp_so3(T * ang(sol.V));
  }
  out.displacement = pose.x - start.x;
  out.velocity = lin(V);
  return out;
}

// Below the friction angle (tan theta < mu) the block sticks: the contact point's tangential
// velocity is zero to round-off and the block stays within 1e-9 m over 1000 ticks.
TEST(Friction, BlockOnSlopeSticksBelowFrictionAngle) {
  const double T = 1e-3;
  for (double theta_deg : {5.0, 15.0, 25.0, 26.0}) {
    const double theta = theta_deg * kPi / 180.0, mu = 0.5;  // atan(0.5) = 26.57 deg
    const SlopeRun run = run_slope(theta, mu, 1000, T);
    std::printf(
        "theta %.1f deg, mu %.2f: drift %.3e m, max tangential speed %.3e m/s, "
        "max |f_t|/(mu f_n) %.6f\n",
        theta_deg, mu, run.displacement.norm(), run.max_tangential_speed, run.max_cone_ratio);
    EXPECT_FALSE(run.any_sliding) << theta_deg;
    EXPECT_LT(run.displacement.norm(), 1e-9) << theta_deg;
    EXPECT_LT(run.max_tangential_speed, 1e-15) << theta_deg;
    // The sticking force holds the tangential weight: |f_t| = m g sin(theta) < mu m g cos(theta).
    EXPECT_NEAR(run.max_cone_ratio, std::tan(theta) / mu, 1e-9) << theta_deg;
  }
}

// Above the friction angle it slides with the acceleration g (sin theta - mu cos theta).
TEST(Friction, BlockOnSlopeSlidesWithCoulombAcceleration) {
  const double T = 1e-3;
  const int ticks = 1000;
  for (const auto& [theta_deg, mu] :
       {std::pair{30.0, 0.3}, std::pair{45.0, 0.5}, std::pair{60.0, 0.2}, std::pair{28.0, 0.5}}) {
    const double theta = theta_deg * kPi / 180.0;
    const SlopeRun run = run_slope(theta, mu, ticks, T);
    const Vec3 down(-std::cos(theta), 0.0, -std::sin(theta));  // downhill tangent
    const double t_end = ticks * T;
    const double a_expected = kG * (std::sin(theta) - mu * std::cos(theta));
    const double a_from_x = 2.0 * run.displacement.dot(down) / (t_end * t_end);
    const double a_from_v = run.velocity.dot(down) / t_end;
    std::printf(
        "theta %.1f deg, mu %.2f: a expected %.9f, from x %.9f, from v %.9f m/s^2, "
        "max |f_t|/(mu f_n) %.12f\n",
        theta_deg, mu, a_expected, a_from_x, a_from_v, run.max_cone_ratio);
    EXPECT_TRUE(run.all_sliding);
    EXPECT_NEAR(a_from_x / a_expected, 1.0, 0.01);
    EXPECT_NEAR(a_from_v / a_expected, 1.0, 0.01);
    // PMI integrates a constant acceleration exactly: far inside the 1 % the task asks for.
    EXPECT_NEAR(a_from_x / a_expected, 1.0, 1e-8);
    EXPECT_NEAR(run.max_cone_ratio, 1.0, 1e-12);  // on the cone
    // It stays on the plane: no motion along the normal.
    const Vec3 n(-std::sin(theta), 0.0, std::cos(theta));
    EXPECT_LT(std::abs(run.displacement.dot(n)), 1e-12);
  }
}

// The explicit-Euler baseline uses the same friction solve with V = V_k+1: it sticks below the
// friction angle and slides with g (sin theta - mu cos theta) above it (the velocity is exact; the
// position of semi-implicit Euler is off by a T / t relative term).
TEST(Friction, ExplicitSchemeSticksAndSlides) {
  const double T = 1e-3;
  const int ticks = 1000;
  const SlopeRun stick = run_slope(20.0 * kPi / 180.0, 0.5, ticks, T, Scheme::kExplicit);
  std::printf("explicit, 20 deg, mu 0.5: drift %.3e m, sliding %d\n", stick.displacement.norm(),
              stick.any_sliding);
  EXPECT_FALSE(stick.any_sliding);
  EXPECT_LT(stick.displacement.norm(), 1e-9);
  const double theta = 40.0 * kPi / 180.0, mu = 0.4;
  const SlopeRun slide = run_slope(theta, mu, ticks, T, Scheme::kExplicit);
  const Vec3 down(-std::cos(theta), 0.0, -std::sin(theta));
  const double a_expected = kG * (std::sin(theta) - mu * std::cos(theta));
  const double a_from_v = slide.velocity.dot(down) / (ticks * T);
  const double a_from_x = 2.0 * slide.displacement.dot(down) / std::pow(ticks * T, 2);
  std::printf("explicit, 40 deg, mu 0.4: a expected %.9f, from v %.9f, from x %.9f m/s^2\n",
              a_expected, a_from_v, a_from_x);
  EXPECT_TRUE(slide.all_sliding);
  EXPECT_NEAR(a_from_v / a_expected, 1.0, 1e-8);
  EXPECT_NEAR(a_from_x / a_expected, 1.0, 0.01);
}

// Stick-slip: a block on a level plane pulled by a horizontal PMI spring whose anchor moves at
// constant speed. It sticks (no motion at all) until the spring force at the midpoint exceeds
// mu m g and breaks away on exactly that tick; while sticking friction balances the spring.
TEST(Friction, SpringPulledBlockBreaksAwayAtMuMg) {
  const double T = 1e-3, K = 2e4, k_s = 200.0, v_a = 0.02, mu = 0.4;
  const Mat6 M = block_inertia();
  const double m = M(0, 0);
  Contact c;
  c.n = Vec3::UnitZ();
  c.stiffness = K;
  c.x_o = Vec3(0, 0, m * kG / K);  // block at the origin, at the equilibrium depth
  Pose pose;
  Vec6 V = Vec6::Zero();
  FrictionParams fp;
  fp.enabled = true;
  fp.mu = mu;
  int first_slide = -1;
  for (int k = 0; k < 400 && first_slide < 0; ++k) {
    const double x_a = v_a * (k + 0.5) * T;  // anchor at the midpoint of the tick
    AffineWrench spring;                     // f_x = -k_s (x_k + T/2 v_hat - x_a)
    spring.f0(0) = -k_s * (pose.x.x() - x_a);
    spring.G(0, 0) = -k_s * T / 2;
    AffineWrench gravity;
    gravity.f0(2) = -m * kG;
    const AffineWrench normal = contact_wrench(std::span(&c, 1), pose, T, Scheme::kMidpoint);
    PmiSystem sys;
    sys.A = M * (2.0 / T);
    sys.b = sys.A * V;
    sys.add(spring);
    sys.add(gravity);
    sys.add(normal);
    const FrictionSolution sol = solve_with_friction(sys, std::span(&c, 1), pose, normal, fp);
    if (sol.sliding) {
      first_slide = k;
      EXPECT_NEAR(sol.f_t.norm(), mu * m * kG, 1e-9);
      EXPECT_GT(sol.V(0), 0.0);  // moves towards the anchor
      break;
    }
    // Sticking: friction balances the spring exactly and the block does not move.
    EXPECT_NEAR(sol.f_t.x(), -spring.at(sol.V)(0), 1e-12);
    EXPECT_LT(sol.V.norm(), 1e-15);
    V = 2.0 * sol.V - V;
    pose.x += T * lin(sol.V);
  }
  // Break-away tick: the first k with k_s v_a (k + 1/2) T > mu m g.
  const int expected = static_cast<int>(std::floor(mu * m * kG / (k_s * v_a * T) - 0.5)) + 1;
  std::printf(
      "break-away at tick %d (expected %d), spring force there %.6f N, mu m g %.6f N, "
      "creep before it %.3e m\n",
      first_slide, expected, k_s * v_a * (first_slide + 0.5) * T, mu * m * kG, pose.x.norm());
  EXPECT_EQ(first_slide, expected);
  EXPECT_LT(pose.x.norm(), 1e-15);  // no creep before break-away (round-off only)
}

// A random PMI-like system and contact set (tests/support/friction_cases.h, shared with the fast
// twin's differential test).
FrictionState random_case(Rng& rng) { return testing::random_friction_case(rng); }

// Over many random states and loads: |f_t| <= mu |f_n| (+1e-12), friction never does positive
// work on the contact point, the solution satisfies A V = b + J^T f_t, sticking stops the
// tangential slip and matches a brute-force 8x8 KKT solve, sliding lies on the cone.
TEST(FrictionStress, ConeAndDissipationHoldOverRandomStates) {
  const unsigned seed = 21;
  const long samples = testing::stress_count(4000, 400000);
  std::printf("seed %u, %ld samples (DENTSIM_STRESS=full for the long form)\n", seed, samples);
  Rng rng(seed);
  long stick = 0, slide = 0, released = 0, inactive = 0;
  double worst_cone = -1e300, worst_power = -1e300, worst_residual = 0.0, worst_kkt = 0.0,
         worst_slip = 0.0;
  for (long s = 0; s < samples; ++s) {
    const FrictionState rc = random_case(rng);
    const FrictionSolution sol =
        solve_with_friction(rc.sys, rc.contacts, rc.proxy, rc.normal, rc.fp);
    const BlendedContact bc = blended_contact(rc.contacts, rc.proxy);
    ASSERT_EQ(sol.active, bc.active) << "sample " << s;
    if (!sol.active) {
      ++inactive;
      EXPECT_EQ(sol.f_t.norm(), 0.0);
      EXPECT_LT((rc.sys.A * sol.V - rc.sys.b).norm(), 1e-10 * rc.sys.b.norm());
      continue;
    }
    const Mat36 J = contact_point_jacobian(bc.r, rc.proxy.R);
    // The normal force at the solution, recomputed here.
    const double fn = std::max(0.0, bc.n.dot(lin(rc.normal.at(sol.V))));
    EXPECT_NEAR(sol.f_n, fn, 1e-12 * (1 + fn)) << "sample " << s;
    // (a) Coulomb cone.
    worst_cone = std::max(worst_cone, sol.f_t.norm() - rc.fp.mu * std::abs(fn));
    EXPECT_LE(sol.f_t.norm(), rc.fp.mu * std::abs(fn) + 1e-12) << "sample " << s;
    // (b) Friction is tangential and never does positive work on the contact point.
    EXPECT_LT(std::abs(sol.f_t.dot(bc.n)), 1e-12 * (1 + sol.f_t.norm()));
    const Vec3 xdot_c = J * sol.V;
    const double power = sol.f_t.dot(xdot_c);
    worst_power = std::max(worst_power, power);
    EXPECT_LE(power, 1e-12) << "sample " << s;
    // (c) The solution solves the system with the friction wrench J^T f_t = [I; S(r) R^T] f_t.
    const Vec6 F = stack(sol.f_t, skew(bc.r) * rc.proxy.R.transpose() * sol.f_t);
    EXPECT_LT((sol.F - F).norm(), 1e-12 * (1 + F.norm()));
    const double residual = (rc.sys.A * sol.V - rc.sys.b - F).norm() / (1 + rc.sys.b.norm());
    worst_residual = std::max(worst_residual, residual);
    const Vec3 slip = xdot_c - bc.n * bc.n.dot(xdot_c);
    if (!sol.sliding) {
      ++stick;
      // (d) Sticking: no tangential slip (2.22); brute-force KKT solve agrees.
      worst_slip = std::max(worst_slip, slip.norm() / (1e-3 + xdot_c.norm()));
      Vec3 t1, t2;
      tangent_basis(bc.n, t1, t2);
      Eigen::Matrix<double, 8, 8> KKT = Eigen::Matrix<double, 8, 8>::Zero();
      Eigen::Matrix<double, 6, 2> H;
      H << J.transpose() * t1, J.transpose() * t2;
      KKT.topLeftCorner<6, 6>() = rc.sys.A;
      KKT.topRightCorner<6, 2>() = -H;
      KKT.bottomLeftCorner<2, 6>() = H.transpose();
      Eigen::Matrix<double, 8, 1> rhs = Eigen::Matrix<double, 8, 1>::Zero();
      rhs.head<6>() = rc.sys.b;
      const Eigen::Matrix<double, 8, 1> z = KKT.fullPivLu().solve(rhs);
      worst_kkt = std::max(worst_kkt, (z.head<6>() - sol.V).norm() / (1e-6 + sol.V.norm()));
      EXPECT_LT((t1 * z(6) + t2 * z(7) - sol.f_t).norm(), 1e-8 * (1 + sol.f_t.norm()));
    } else if (fn > 0.0) {
      ++slide;
      // (e) Sliding: on the cone, force opposing the slip.
      EXPECT_NEAR(sol.f_t.norm(), rc.fp.mu * fn, 1e-12 * (1 + fn)) << "sample " << s;
      EXPECT_LE(sol.f_t.dot(slip), 1e-12) << "sample " << s;
    } else {
      ++released;  // the normal force vanishes at the solution: no friction
      EXPECT_EQ(sol.f_t.norm(), 0.0);
    }
  }
  std::printf("stick %ld, slide %ld, released %ld, inactive %ld\n", stick, slide, released,
              inactive);
  std::printf(
      "worst |f_t| - mu|f_n| %.3e N, worst friction power %.3e W, worst residual %.3e, "
      "worst KKT mismatch %.3e, worst relative stick slip %.3e\n",
      worst_cone, worst_power, worst_residual, worst_kkt, worst_slip);
  EXPECT_LT(worst_residual, 1e-12);
  EXPECT_LT(worst_kkt, 1e-9);
  EXPECT_LT(worst_slip, 1e-12);
  // Mistrust guard: every branch must be exercised by at least 5 % of the samples.
  EXPECT_GT(stick, samples / 20);
  EXPECT_GT(slide, samples / 20);
  EXPECT_GT(inactive, samples / 20);
  EXPECT_GT(released, 0);
}

// Friction inherits the aggregation: the same contact reported 1, 4, 16 or 64 times (weights
// arbitrary) gives the same solution, force and sliding state.
TEST(Friction, SolutionIndependentOfReportCount) {
  const unsigned seed = 24;
  std::printf("seed %u\n", seed);
  Rng rng(seed);
  double worst = 0.0;
  long sliding = 0, sticking = 0;
  for (int s = 0; s < 300; ++s) {
    FrictionState rc = random_case(rng);
    rc.contacts.resize(1);
    if (penetration_depth(rc.contacts[0], rc.proxy) <= 0.0) continue;
    const PmiSystem base = [&] {
      PmiSystem sys = rc.sys;
      sys.A += rc.normal.G;  // remove the multi-member normal that random_case added
      sys.b -= rc.normal.f0;
      return sys;
    }();
    const double T = 1e-3;
    const AffineWrench n1 = contact_wrench(rc.contacts, rc.proxy, T, Scheme::kMidpoint);
    PmiSystem sys1 = base;
    sys1.add(n1);
    const FrictionSolution ref = solve_with_friction(sys1, rc.contacts, rc.proxy, n1, rc.fp);
    (ref.sliding ? sliding : sticking)++;
    for (int N : {4, 16, 64}) {
      std::vector<Contact> set(N, rc.contacts[0]);
      for (Contact& c : set) c.weight = uni(rng, 0.1, 1.0);
      const AffineWrench nN = contact_wrench(set, rc.proxy, T, Scheme::kMidpoint);
      PmiSystem sysN = base;
      sysN.add(nN);
      const FrictionSolution sol = solve_with_friction(sysN, set, rc.proxy, nN, rc.fp);
      EXPECT_EQ(sol.sliding, ref.sliding);
      worst = std::max({worst, (sol.V - ref.V).norm() / (1e-9 + ref.V.norm()),
                        (sol.f_t - ref.f_t).norm() / (1e-9 + ref.f_t.norm())});
    }
  }
  std::printf("stick %ld, slide %ld; worst relative difference %.3e\n", sticking, sliding, worst);
  EXPECT_GT(sticking, 10);
  EXPECT_GT(sliding, 10);
  EXPECT_LT(worst, 1e-10);
}

TEST(Friction, DisabledOrNoContactIsThePlainSolve) {
  const unsigned seed = 22;
  std::printf("seed %u\n", seed);
  Rng rng(seed);
  for (int s = 0; s < 200; ++s) {
    FrictionState rc = random_case(rng);
    const Vec6 plain = rc.sys.A.fullPivLu().solve(rc.sys.b);
    rc.fp.enabled = s % 2 == 0;
    if (rc.fp.enabled) rc.fp.mu = 0.0;
    const FrictionSolution sol =
        solve_with_friction(rc.sys, rc.contacts, rc.proxy, rc.normal, rc.fp);
    EXPECT_FALSE(sol.active);
    EXPECT_LT((sol.V - plain).norm(), 1e-12 * (1 + plain.norm()));
    EXPECT_EQ(sol.f_t.norm(), 0.0);
    rc.fp.enabled = true;
    rc.fp.mu = 0.5;
    const FrictionSolution none = solve_with_friction(rc.sys, {}, rc.proxy, rc.normal, rc.fp);
    EXPECT_FALSE(none.active);
    EXPECT_LT((none.V - plain).norm(), 1e-12 * (1 + plain.norm()));
  }
}

TEST(Friction, TangentBasisIsOrthonormalAndRightHanded) {
  const unsigned seed = 23;
  std::printf("seed %u\n", seed);
  Rng rng(seed);
  std::vector<Vec3> normals{Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ(), -Vec3::UnitZ()};
  for (int i = 0; i < 500; ++i) normals.push_back(random_unit(rng));
  for (const Vec3& n : normals) {
    Vec3 t1, t2;
    tangent_basis(n, t1, t2);
    EXPECT_NEAR(t1.norm(), 1.0, 1e-15);
    EXPECT_NEAR(t2.norm(), 1.0, 1e-15);
    EXPECT_LT(std::abs(t1.dot(n)) + std::abs(t2.dot(n)) + std::abs(t1.dot(t2)), 1e-15);
    EXPECT_LT((t1.cross(t2) - n).norm(), 1e-15);
  }
}

TEST(Friction, BadInputThrows) {
  PmiSystem sys;
  sys.A = Mat6::Identity();
  FrictionParams fp;
  fp.enabled = true;
  fp.mu = -0.1;
  try {
    solve_with_friction(sys, {}, Pose{}, AffineWrench{}, fp);
    ADD_FAILURE() << "no InputError for mu < 0";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("friction.mu"), std::string::npos) << e.what();
  }
  fp.mu = 0.3;
  sys.A = Mat6::Zero();
  EXPECT_THROW(solve_with_friction(sys, {}, Pose{}, AffineWrench{}, fp), InputError);
}

}  // namespace
}  // namespace dentsim
