// fast::contact_wrench_unchecked + fast::add_anchored_spring_unchecked against the reference's
// (reference/contact.h) on random contact sets, the surface proxy's spring across the normal with
// the sphere's centre off the proxy origin included: the same f0 and G within the tolerance
// policy's "fast vs reference" (docs/tolerance_policy.md: 1e-9 relative; the sums differ only in
// order).
#include "fast/contact.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cstdio>
#include <random>
#include <vector>

#include "reference/contact.h"
#include "reference/core/so3.h"
#include "tests/support/random.h"

namespace dentsim {
namespace {

TEST(FastContact, WrenchEqualsTheReferenceWithTheAnchoredSpring) {
  const unsigned seed = 32;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0), pos(0.0, 1.0);
  double worst = 0.0;
  int anchored_sets = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    Pose proxy;
    proxy.x = Vec3(u(rng), u(rng), u(rng)) * 0.01;
    proxy.R = exp_so3(testing::random_unit(rng) * (3.0 * pos(rng)));
    std::vector<Contact> set(1 + trial % 4);
    for (Contact& c : set) {
      c.n = testing::random_unit(rng);
      c.r = Vec3(u(rng), u(rng), u(rng)) * 1e-3;
      c.x_o = proxy.x + proxy.R * c.r + c.n * (1e-3 * u(rng));  // about half penetrate
      c.stiffness = 1e3 + 4e4 * pos(rng);
      c.damping = 10.0 * pos(rng);
      c.weight = pos(rng);
    }
    const bool anchored = trial % 3 != 0;
    const Vec3 center = Vec3(u(rng), u(rng), u(rng)) * 2e-3;
    anchored_sets += anchored;
    const double T = trial % 2 ? 2e-3 : 1e-4;
    for (const Scheme scheme : {Scheme::kMidpoint, Scheme::kExplicit}) {
      AffineWrench a = contact_wrench_unchecked(set, proxy, T, scheme);
      AffineWrench b = fast::contact_wrench_unchecked(set, proxy, T, scheme);
      if (anchored) {
        add_anchored_spring_unchecked(&a, set, proxy, T, scheme, center);
        fast::add_anchored_spring_unchecked(&b, set, proxy, T, scheme, center);
      }
      const double f_scale = std::max(a.f0.cwiseAbs().maxCoeff(), 1e-300);
      const double g_scale = std::max(a.G.cwiseAbs().maxCoeff(), 1e-300);
      worst = std::max(worst, (a.f0 - b.f0).cwiseAbs().maxCoeff() / f_scale);
      worst = std::max(worst, (a.G - b.G).cwiseAbs().maxCoeff() / g_scale);
      // G stays symmetric negative semidefinite (the contact never generates energy in V).
      EXPECT_LE((b.G - b.G.transpose()).cwiseAbs().maxCoeff(), 1e-12 * g_scale);
      EXPECT_LE(Eigen::SelfAdjointEigenSolver<Mat6>(b.G).eigenvalues().maxCoeff(),
                1e-12 * g_scale);
    }
  }
  std::printf("seed %u: %d sets with the anchored spring, worst relative difference %.3e\n", seed,
              anchored_sets, worst);
  EXPECT_GT(anchored_sets, 1000);
  EXPECT_LE(worst, 1e-12);
}

// The anchored spring completes the midpoint spring across n at the sphere's centre: with the
// centre at the proxy origin and no rotation, G's translational block is -(K T/2) I - B n n^T
// exactly (the spring to a fixed anchor, isotropic), and under kExplicit nothing is added.
TEST(FastContact, AnchoredSpringIsTheMidpointSpringAcrossTheNormal) {
  Pose proxy;
  Contact c;
  c.n = Vec3(1.0, 2.0, 2.0) / 3.0;
  c.r = -0.5e-3 * c.n;
  c.x_o = c.r + 1e-4 * c.n;
  c.stiffness = 12000.0;
  c.damping = 5.0;
  const double T = 1e-3;
  const std::span<const Contact> set(&c, 1);
  const Mat3 nn = c.n * c.n.transpose();
  const Mat3 expected = -5.0 * nn - 0.5 * T * 12000.0 * Mat3::Identity();
  for (const bool fast_impl : {false, true}) {
    for (const Scheme scheme : {Scheme::kMidpoint, Scheme::kExplicit}) {
      AffineWrench F = fast_impl ? fast::contact_wrench_unchecked(set, proxy, T, scheme)
                                 : contact_wrench_unchecked(set, proxy, T, scheme);
      if (fast_impl) {
        fast::add_anchored_spring_unchecked(&F, set, proxy, T, scheme, Vec3::Zero());
      } else {
        add_anchored_spring_unchecked(&F, set, proxy, T, scheme, Vec3::Zero());
      }
      const Mat3 want = scheme == Scheme::kMidpoint ? expected : Mat3(-5.0 * nn);
      EXPECT_LE((F.G.topLeftCorner<3, 3>() - want).cwiseAbs().maxCoeff(), 1e-12) << fast_impl;
    }
  }
}

}  // namespace
}  // namespace dentsim
