// Tests for fast/coupling.h: both coupling wrenches of a tick in one pass against the reference's
// coupling_proxy_wrench_unchecked and coupling_device_wrench_unchecked (reference/coupling.h),
// bitwise (the same operations on the same doubles; a zero's sign counts), over random poses with
// relative angles from 0 to pi (the logarithm's branch near pi included, and R1 = R2 exactly),
// random velocities, gains (zeros included), ticks and both schemes. Seeds fixed.
#include "fast/coupling.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "reference/core/so3.h"
#include "reference/coupling.h"
#include "tests/fast/bitwise.h"
#include "tests/support/random.h"

namespace dentsim {
namespace {

using Rng = std::mt19937_64;

double uni(Rng& rng, double a, double b) { return testing::uniform(rng, a, b); }

Vec6 random_twist(Rng& rng, double scale) {
  Vec6 v;
  for (int i = 0; i < 6; ++i) v(i) = uni(rng, -scale, scale);
  return v;
}

TEST(FastCoupling, BothWrenchesAreTheReferencesBitwise) {
  Rng rng(4801);
  int trials = 0, shared = 0, log_branch = 0, unequal = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    Pose device, proxy_pose;
    device.R = exp_so3(testing::random_unit(rng) * uni(rng, 0.0, std::numbers::pi));
    device.x = Vec3(uni(rng, -0.1, 0.1), uni(rng, -0.1, 0.1), uni(rng, -0.1, 0.1));
    // The proxy's relative angle: anywhere in [0, pi], within 1e-3 of pi (the logarithm's
    // branch), or none at all (R2 = R1 exactly).
    const int kind = trial % 10;
    const double angle = kind == 0   ? 0.0
                         : kind == 1 ? std::numbers::pi - uni(rng, 0.0, 1e-3)
                                     : uni(rng, 0.0, std::numbers::pi);
    proxy_pose.R = kind == 0 ? device.R : Mat3(device.R * exp_so3(testing::random_unit(rng) * angle));
    proxy_pose.x = device.x + Vec3(uni(rng, -0.01, 0.01), uni(rng, -0.01, 0.01), 0.0);
    ProxyState proxy;
    proxy.pose = proxy_pose;
    proxy.V = random_twist(rng, 0.5);
    proxy.V_hat_prev = random_twist(rng, 0.5);
    const Vec6 V1 = random_twist(rng, 0.5);
    CouplingGains g;
    g.k_lin = trial % 7 == 0 ? 0.0 : uni(rng, 0.0, 3000.0);
    g.k_ang = trial % 11 == 0 ? 0.0 : uni(rng, 0.0, 1.0);
    g.b_lin = trial % 5 == 0 ? 0.0 : uni(rng, 0.0, 10.0);
    g.b_ang = trial % 3 == 0 ? 0.0 : uni(rng, 0.0, 0.01);
    const double T = std::pow(10.0, uni(rng, -4.5, -2.5));
    const Scheme scheme = trial % 2 == 0 ? Scheme::kMidpoint : Scheme::kExplicit;

    const AffineWrench ref2 = coupling_proxy_wrench_unchecked(g, device, V1, proxy, T, scheme);
    const Vec6 ref1 = coupling_device_wrench_unchecked(g, device, V1, proxy, T, scheme);
    AffineWrench fast2;
    Vec6 fast1;
    fast2.G.setConstant(1.0);  // every entry must be written
    fast::coupling_wrenches_unchecked(g, device, V1, proxy, T, scheme, &fast2, &fast1);
    unequal += testing::unequal_entries(fast2.f0, ref2.f0) +
               testing::unequal_entries(fast2.G, ref2.G) + testing::unequal_entries(fast1, ref1);
    ++trials;
    const Mat3 R21 = proxy.pose.R.transpose() * device.R;
    const Mat3 R12 = device.R.transpose() * proxy.pose.R;
    if (rotation_angle(R21) >= std::numbers::pi - 1e-3) {
      ++log_branch;
    } else if (R12 == R21.transpose()) {
      ++shared;
    }
  }
  std::printf("trials %d: shared spring vector %d, logarithm's branch %d\n", trials, shared,
              log_branch);
  EXPECT_EQ(unequal, 0);
  // Guards: both branches ran, the shared one in most trials.
  EXPECT_GT(shared, trials * 8 / 10);
  EXPECT_GT(log_branch, trials / 20);
}

}  // namespace
}  // namespace dentsim
