// Tests for fast/contact.h: the penalty contact wrench as symmetric rank-1 updates, against the
// reference's contact_wrench_unchecked (reference/contact.h) on random and adversarial contact
// sets, and on its own physics (a tool tip pressed into a half-space).
//
// Tolerance (docs/tolerance_policy.md item 2, round-off): the two implementations sum the same
// terms in another order, so they differ by at most c * eps * n * (sum of the terms' magnitudes)
// per entry, with n the number of members, eps = 2.2e-16 and c = 16 (a handful of products and
// sums per term, in either order). Where the algebra makes a result exact (an empty set, members
// that do not penetrate, G's symmetry) the test asks for bitwise equality. Seeds fixed, printed.
#include "fast/contact.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <vector>

#include "reference/contact.h"
#include "reference/core/contact_provider.h"
#include "reference/core/so3.h"
#include "tests/support/contacts.h"
#include "tests/support/random.h"

namespace dentsim {
namespace {

using Rng = std::mt19937_64;
constexpr double kEps = 2.220446049250313e-16;
constexpr double kC = 16.0;  // the round-off constant of the bound (header)

double uni(Rng& rng, double a, double b) { return testing::uniform(rng, a, b); }
using testing::random_unit;

Pose random_pose(Rng& rng, double angle) {
  Pose p;
  p.x = Vec3(uni(rng, -0.1, 0.1), uni(rng, -0.1, 0.1), uni(rng, -0.1, 0.1));
  p.R = exp_so3(angle * random_unit(rng));
  return p;
}

// A member whose contact point on the proxy (body offset r) sits `depth` below the surface point
// x_o along n (depth > 0 penetrates; recomputed from the pose by both implementations).
Contact member(const Pose& proxy, const Vec3& r, const Vec3& n, double depth, double k, double b,
               double weight) {
  return testing::make_contact(proxy, n, r, depth, k, b, weight);
}

// The sums' scales: per entry, sum over penetrating members of |w k delta a| (f0) and of
// |g a a^T| (G), a = [n; r x R^T n], g = w (k T/2 [midpoint] + b).
struct Scales {
  double f0 = 0.0, G = 0.0;
};
Scales scales(const std::vector<Contact>& set, const Pose& proxy, double T, Scheme scheme) {
  const ContactWeights w(set);
  Scales s;
  for (const Contact& c : set) {
    const double delta = penetration_depth(c, proxy);
    if (!(delta > 0.0)) continue;
    const double an = std::max(1.0, (c.r.cross(proxy.R.transpose() * c.n)).cwiseAbs().maxCoeff());
    const double g =
        w(c) * ((scheme == Scheme::kMidpoint ? 0.5 * T : 0.0) * c.stiffness + c.damping);
    s.f0 += w(c) * c.stiffness * delta * an;
    s.G += g * an * an;
  }
  return s;
}

// Compares fast with reference on one set; returns the larger of the two error ratios
// |fast - reference|_inf / bound (<= 1 passes).
double compare(const std::vector<Contact>& set, const Pose& proxy, double T, Scheme scheme) {
  const AffineWrench a = contact_wrench_unchecked(set, proxy, T, scheme);
  const AffineWrench b = fast::contact_wrench_unchecked(set, proxy, T, scheme);
  EXPECT_EQ(b.G, b.G.transpose());  // symmetric by construction: exactly
  const Scales s = scales(set, proxy, T, scheme);
  const double n = static_cast<double>(std::max<std::size_t>(set.size(), 1));
  const double df = (a.f0 - b.f0).cwiseAbs().maxCoeff();
  const double dG = (a.G - b.G).cwiseAbs().maxCoeff();
  const double bf = kC * kEps * n * s.f0, bG = kC * kEps * n * s.G;
  // A zero scale (nothing penetrates) must give exactly zero in both.
  const double rf = bf > 0.0 ? df / bf : (df == 0.0 ? 0.0 : INFINITY);
  const double rG = bG > 0.0 ? dG / bG : (dG == 0.0 ? 0.0 : INFINITY);
  return std::max(rf, rG);
}

TEST(FastContact, RandomSetsEqualTheReferenceWithinRoundOff) {
  const unsigned seed = 20261126;
  Rng rng(seed);
  double worst = 0.0;
  long penetrating_sets = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Pose proxy = random_pose(rng, uni(rng, 0.0, std::numbers::pi));
    const int n = 1 + static_cast<int>(rng() % 40);
    const bool zero_weights = trial % 7 == 0;  // all zero: equal weights 1/N
    std::vector<Contact> set;
    for (int i = 0; i < n; ++i) {
      const Vec3 r = Vec3(uni(rng, -1, 1), uni(rng, -1, 1), uni(rng, -1, 1)) * 0.02;
      set.push_back(member(proxy, r, random_unit(rng), uni(rng, -2e-4, 5e-4),
                           std::pow(10.0, uni(rng, 2.0, 6.0)), uni(rng, 0.0, 20.0),
                           zero_weights ? 0.0 : uni(rng, 0.0, 2.0)));
    }
    const double T = std::pow(10.0, uni(rng, -5.0, -2.0));
    for (Scheme scheme : {Scheme::kMidpoint, Scheme::kExplicit}) {
      worst = std::max(worst, compare(set, proxy, T, scheme));
    }
    if (scales(set, proxy, T, Scheme::kExplicit).f0 > 0.0) ++penetrating_sets;
  }
  std::printf("seed %u: worst |fast - reference| / bound = %.3f over 4000 sets\n", seed, worst);
  EXPECT_LE(worst, 1.0) << "seed " << seed;
  EXPECT_GT(penetrating_sets, 1900);  // the comparison saw force, not only empty wrenches
}

TEST(FastContact, AdversarialSetsEqualTheReference) {
  Rng rng(7);
  const double T = 1e-3;
  // Empty set and a set where nothing penetrates (depth exactly 0, and negative): zero, exactly.
  const Pose p0 = random_pose(rng, 1.0);
  for (Scheme scheme : {Scheme::kMidpoint, Scheme::kExplicit}) {
    const AffineWrench e = fast::contact_wrench_unchecked({}, p0, T, scheme);
    EXPECT_EQ(e.f0, Vec6::Zero());
    EXPECT_EQ(e.G, Mat6::Zero());
    std::vector<Contact> out;
    out.push_back(member(p0, Vec3(0.01, 0, 0), Vec3::UnitZ(), -1e-4, 1e4, 5.0, 1.0));
    Contact touching;  // x_o exactly at the contact point: delta = 0, unilateral
    touching.r = Vec3::Zero();
    touching.n = Vec3::UnitX();
    touching.x_o = p0.x;
    touching.stiffness = 1e4;
    out.push_back(touching);
    const AffineWrench z = fast::contact_wrench_unchecked(out, p0, T, scheme);
    EXPECT_EQ(z.f0, Vec6::Zero());
    EXPECT_EQ(z.G, Mat6::Zero());
    EXPECT_EQ(compare(out, p0, T, scheme), 0.0);
  }
  double worst = 0.0;
  for (double angle : {0.0, 1e-9, std::numbers::pi - 1e-9, std::numbers::pi}) {
    const Pose p = random_pose(rng, angle);
    // One member on the proxy origin (no torque), a grazing one (depth 1e-300), a stiffness
    // range of 12 orders, a zero-stiffness member, duplicates, and the buffer's full capacity.
    std::vector<Contact> s;
    s.push_back(member(p, Vec3::Zero(), random_unit(rng), 1e-4, 1e4, 0.0, 1.0));
    s.push_back(member(p, Vec3(0, 0, 0.02), random_unit(rng), 1e-300, 1e4, 3.0, 1.0));
    s.push_back(member(p, Vec3(0.01, 0, 0), random_unit(rng), 2e-4, 1e-3, 0.0, 1.0));
    s.push_back(member(p, Vec3(0, 0.01, 0), random_unit(rng), 2e-4, 1e9, 1e3, 1e-6));
    s.push_back(member(p, Vec3(0, 0.01, 0.01), random_unit(rng), 3e-4, 0.0, 2.0, 1.0));
    for (Scheme scheme : {Scheme::kMidpoint, Scheme::kExplicit}) {
      for (double t : {1e-5, 1e-3, 1e-2}) worst = std::max(worst, compare(s, p, t, scheme));
    }
    std::vector<Contact> full;
    const Contact one = member(p, Vec3(0.003, -0.002, 0.01), random_unit(rng), 1e-4, 3e4, 5.0, 1.0);
    full.assign(kContactCapacity, one);
    for (Scheme scheme : {Scheme::kMidpoint, Scheme::kExplicit}) {
      worst = std::max(worst, compare(full, p, T, scheme));
      // The same member reported N times is one member (weights 1/N), in fast as in the reference.
      const AffineWrench a = fast::contact_wrench_unchecked(full, p, T, scheme);
      const AffineWrench b = fast::contact_wrench_unchecked({&one, 1}, p, T, scheme);
      EXPECT_LE((a.f0 - b.f0).cwiseAbs().maxCoeff(),
                kC * kEps * kContactCapacity * b.f0.cwiseAbs().maxCoeff());
      EXPECT_LE((a.G - b.G).cwiseAbs().maxCoeff(),
                kC * kEps * kContactCapacity * b.G.cwiseAbs().maxCoeff());
    }
  }
  std::printf("adversarial: worst |fast - reference| / bound = %.3f\n", worst);
  EXPECT_LE(worst, 1.0);
}

// The surface proxy's spring across the normal (add_anchored_spring_unchecked, issue #32), fast
// against the reference on random sets: held fractions 0 to 1, dampers from 0 (all of K_t
// implicit) to beyond the bound (nothing added, bit for bit in both), the sphere's centre off the
// proxy origin. The terms are the same products summed in another order (two tangent rank-1
// updates for the reference's J_o^T P J_o): within the round-off bound of the header, with the
// added term's magnitude (K_imp T/2 (1 + |o|)^2) as its scale; and G stays symmetric negative
// semidefinite (the spring integrated at its midpoint generates no energy).
TEST(FastContact, AnchoredSpringEqualsTheReference) {
  const unsigned seed = 32;
  Rng rng(seed);
  double worst = 0.0;
  long added = 0, unchanged = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Pose proxy = random_pose(rng, uni(rng, 0.0, std::numbers::pi));
    const int n = 1 + static_cast<int>(rng() % 3);
    std::vector<Contact> set;
    for (int i = 0; i < n; ++i) {
      const Vec3 r = Vec3(uni(rng, -1, 1), uni(rng, -1, 1), uni(rng, -1, 1)) * 0.01;
      set.push_back(member(proxy, r, random_unit(rng), uni(rng, -2e-4, 5e-4),
                           uni(rng, 1e3, 5e4), uni(rng, 0.0, 10.0), uni(rng, 0.0, 2.0)));
    }
    const AnchoredSpring spring{Vec3(uni(rng, -1, 1), uni(rng, -1, 1), uni(rng, -1, 1)) * 8e-3,
                                trial % 5 == 0 ? 0.0 : uni(rng, 0.0, 1.0)};
    const double b_lin = trial % 4 == 0 ? 0.0 : uni(rng, 0.0, 40.0);
    const double b_ang = trial % 6 == 0 ? 0.0 : uni(rng, 0.0, 0.01);
    const double T = std::pow(10.0, uni(rng, -4.0, -2.0));
    for (Scheme scheme : {Scheme::kMidpoint, Scheme::kExplicit}) {
      AffineWrench a = contact_wrench_unchecked(set, proxy, T, scheme);
      AffineWrench b = fast::contact_wrench_unchecked(set, proxy, T, scheme);
      const Mat6 a_before = a.G, b_before = b.G;
      add_anchored_spring_unchecked(&a, set, proxy, T, scheme, spring, b_lin, b_ang);
      fast::add_anchored_spring_unchecked(&b, set, proxy, T, scheme, spring, b_lin, b_ang);
      EXPECT_EQ(a.f0, contact_wrench_unchecked(set, proxy, T, scheme).f0);  // f0 untouched
      if (a.G == a_before) {
        EXPECT_EQ(b.G, b_before);  // the same decision: nothing added in either
        ++unchanged;
      } else {
        ++added;
      }
      const Scales sc = scales(set, proxy, T, scheme);
      const double o = 1.0 + spring.center.norm();
      const double k_sum = 0.5 * T * 5e4 * 2.0 * o * o;  // the added terms' magnitude, at most
      const double bound = kC * kEps * 3.0 * (sc.G + k_sum);
      worst = std::max(worst, (a.G - b.G).cwiseAbs().maxCoeff() / bound);
      EXPECT_EQ(b.G, b.G.transpose());
      EXPECT_LE(Eigen::SelfAdjointEigenSolver<Mat6>(b.G).eigenvalues().maxCoeff(),
                kC * kEps * 6.0 * (sc.G + k_sum));
    }
  }
  std::printf("seed %u: %ld wrenches with the anchored spring, %ld unchanged; worst |fast - "
              "reference| / bound = %.3f\n",
              seed, added, unchanged, worst);
  EXPECT_LE(worst, 1.0);
  EXPECT_GT(added, 500);
  EXPECT_GT(unchanged, 1000);
}

// Physics: the tip of a tool (a point at body offset r) pressed delta into the half-space
// n^T (x - x_s) < 0. The force is K delta along +n (out of the surface), applied at the contact
// point: the body torque is r x (R^T f); the velocity part is -(K T/2 + B) a a^T (midpoint) or
// -B a a^T (explicit), so the wrench's power at any V is the spring's power minus a dissipation.
TEST(FastContact, HalfSpacePushesOutAlongTheNormalWithKDelta) {
  Rng rng(11);
  for (int trial = 0; trial < 200; ++trial) {
    const Pose p = random_pose(rng, uni(rng, 0.0, std::numbers::pi));
    const Vec3 n = random_unit(rng);
    const Vec3 r = Vec3(uni(rng, -1, 1), uni(rng, -1, 1), uni(rng, -1, 1)) * 0.02;
    const double delta = uni(rng, 1e-6, 1e-3), K = uni(rng, 1e3, 1e5), B = uni(rng, 0.0, 10.0);
    const double T = 1e-3;
    const Contact c = member(p, r, n, delta, K, B, 1.0);
    const AffineWrench Fm = fast::contact_wrench_unchecked({&c, 1}, p, T, Scheme::kMidpoint);
    const AffineWrench Fe = fast::contact_wrench_unchecked({&c, 1}, p, T, Scheme::kExplicit);
    const Vec3 f = Fm.f0.head<3>();
    // delta is recomputed from the pose: round-off of the positions' size (|x_o| ~ 0.1 m), not of
    // delta's.
    const double tol = 8 * kEps * K * (delta + c.x_o.cwiseAbs().maxCoeff() + r.norm());
    EXPECT_NEAR(f.dot(n), K * delta, tol);          // magnitude K delta
    EXPECT_LE((f - f.dot(n) * n).norm(), tol);      // along n: no tangential part
    EXPECT_EQ(Fe.f0, Fm.f0);                        // the spring at t_k in both schemes
    const Vec3 tau = r.cross(p.R.transpose() * f);  // the torque of f at x_c (body)
    EXPECT_LE((Fm.f0.tail<3>() - tau).norm(), tol * 0.05);
    Vec6 a;
    a << n, r.cross(p.R.transpose() * n);
    const Mat6 Gm = -(K * 0.5 * T + B) * a * a.transpose();
    const Mat6 Ge = -B * a * a.transpose();
    EXPECT_LE((Fm.G - Gm).cwiseAbs().maxCoeff(), 8 * kEps * (K * T + B));
    EXPECT_LE((Fe.G - Ge).cwiseAbs().maxCoeff(), 8 * kEps * (B + 1.0));
    // Dissipative in V: V^T G V <= 0 for every twist (G = -g a a^T, g >= 0).
    Vec6 V;
    for (int i = 0; i < 6; ++i) V(i) = uni(rng, -1, 1);
    EXPECT_LE(V.dot(Fm.G * V), 8 * kEps * (K * T + B) * 36);
    // Sliding along the surface (a^T V = 0) meets no damping or midpoint stiffness.
    Vec6 Vt = V - (a.dot(V) / a.squaredNorm()) * a;
    EXPECT_LE((Fm.G * Vt).cwiseAbs().maxCoeff(), 64 * kEps * (K * T + B));
  }
}

}  // namespace
}  // namespace dentsim
