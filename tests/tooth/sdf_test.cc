// The surface-proxy contact (reference/tooth/sdf.h): the signed distance equals the brute force
// over every voxel, the proxy never crosses a wall one voxel thick whatever the tool's step, a
// proxy found inside leaves along the shortest way, the push-out leaves a concave corner in a few
// queries (the corner step), the contact's depth on a flat face is the tool's exact depth, and
// the provider's model switch (faces / sdf).
#include "reference/tooth/sdf.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <random>
#include <vector>

#include "reference/core/io.h"
#include "reference/tooth/surface_proxy_core.h"
#include "reference/tooth/tooth_contacts.h"

namespace dentsim {
namespace {

constexpr double kK = 3000.0;     // K_tooth [N/m]
constexpr double kRho = 0.4e-3;   // explorer tip radius [m]
constexpr double kSide = 6.4e-3;  // grid edge [m]
constexpr std::uint64_t kSeed = 4242;

VoxelTooth make_tooth(int n, const std::function<bool(const Vec3&)>& inside) {
  VoxelGrid g(n, Vec3::Zero(), kSide / n);
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        if (inside(g.center(i, j, k))) g.set(i, j, k, kEnamel);
      }
    }
  }
  return VoxelTooth(std::move(g));
}

// Brute force: the distance from x to the nearest box among the voxels with solid == want, and
// (for want = empty) the outside of the grid.
double brute_distance(const VoxelGrid& g, const Vec3& x, bool want_solid) {
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k < g.n; ++k) {
    for (int j = 0; j < g.n; ++j) {
      for (int i = 0; i < g.n; ++i) {
        if (g.solid(i, j, k) != want_solid) continue;
        double d2 = 0.0;
        for (int a = 0; a < 3; ++a) {
          const int idx[3] = {i, j, k};
          const double lo = g.origin[a] + g.voxel_size * idx[a];
          const double hi = lo + g.voxel_size;
          const double q = std::clamp(x[a], lo, hi);
          d2 += (x[a] - q) * (x[a] - q);
        }
        best = std::min(best, std::sqrt(d2));
      }
    }
  }
  if (!want_solid) {
    for (int a = 0; a < 3; ++a) {
      best = std::min(best, x[a] - g.origin[a]);
      best = std::min(best, g.origin[a] + g.voxel_size * g.n - x[a]);
    }
  }
  return best;
}

TEST(SignedDistance, EqualsBruteForceInsideAndOutside) {
  // Random blobs on a 16^3 grid: three balls and a slab.
  std::mt19937_64 rng(kSeed);
  std::uniform_real_distribution<double> u(0.0, kSide);
  const VoxelTooth tooth = make_tooth(16, [](const Vec3& p) {
    return (p - Vec3(2e-3, 2e-3, 2e-3)).norm() < 1.5e-3 ||
           (p - Vec3(4.5e-3, 3e-3, 4e-3)).norm() < 1.2e-3 || p.z() < 0.5e-3;
  });
  const VoxelGrid& g = tooth.grid();
  int inside = 0, outside = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const Vec3 x(u(rng), u(rng), u(rng));
    const SignedDistance sd = signed_distance(tooth, x, 1.0);
    ASSERT_TRUE(sd.found);
    const int i = static_cast<int>(x.x() / g.voxel_size),
              j = static_cast<int>(x.y() / g.voxel_size),
              k = static_cast<int>(x.z() / g.voxel_size);
    if (g.solid(i, j, k)) {
      ++inside;
      EXPECT_NEAR(sd.phi, -brute_distance(g, x, false), 1e-15);
      EXPECT_NEAR((sd.nearest - x).norm(), -sd.phi, 1e-15);
    } else {
      ++outside;
      EXPECT_NEAR(sd.phi, brute_distance(g, x, true), 1e-15);
      EXPECT_NEAR((sd.nearest - x).norm(), sd.phi, 1e-15);
      EXPECT_NE(g.voxels[sd.voxel], kEmpty);
    }
  }
  EXPECT_GT(inside, 20);
  EXPECT_GT(outside, 200);
  // Beyond reach: not found, phi = reach.
  const SignedDistance far = signed_distance(tooth, Vec3(6e-3, 6e-3, 6.3e-3), 1e-4);
  EXPECT_FALSE(far.found);
  EXPECT_EQ(far.phi, 1e-4);
}

TEST(SurfaceProxy, NeverCrossesAWallOneVoxelThick) {
  // A wall x in [3.2, 3.3) mm (one voxel at 64^3: h = 0.1 mm); the tool moves from x = 2 mm to
  // x = 4.6 mm in steps from 0.05 mm to 3 mm (a step larger than the wall and the tip together).
  const VoxelTooth tooth =
      make_tooth(64, [](const Vec3& p) { return p.x() > 3.2e-3 && p.x() < 3.3e-3; });
  for (const double step : {0.05e-3, 0.3e-3, 0.9e-3, 3e-3}) {
    SurfaceProxy proxy(kRho, tooth.grid().voxel_size);
    Vec3 c(2e-3, 3.2e-3, 3.2e-3);
    proxy.update(tooth, c);  // first seen on the near side, free
    for (int tick = 0; tick < 200 && c.x() < 4.6e-3; ++tick) {
      c.x() = std::min(4.6e-3, c.x() + step);
      const Vec3 g = proxy.update(tooth, c);
      // g stays on the near side, its sphere clear of the wall (exact here: flat face).
      EXPECT_LE(g.x(), 3.2e-3 - kRho + 1e-12) << "step " << step;
      EXPECT_GE(signed_distance(tooth, g, 1.0).phi, kRho - 1e-12);
    }
    // The spring from the tool to g pushes the tool back towards the near side: K (g - c).
    EXPECT_NEAR(proxy.g().x(), 3.2e-3 - kRho, 1e-12);
  }
}

// A slot with parallel walls a little narrower than the tip (0.7 mm, seven voxels of 0.1 mm; tip
// radius 0.39 mm, skin s = 0.05 mm): its centre line has phi = 0.35 mm >= rho - s, so the swept
// proxy may follow the tool down into it, but no point of the slot is in A (phi >= rho). The
// push-out then alternates between the two walls and never leaves: from the centre it lands rho
// from one wall, 0.31 mm < rho - s from the other. The proxy must keep phi(g) >= rho - s anyway
// (the full contact sweep found g stuck at 0.73 rho in such a four-voxel slot of the molar at
// 128^3 before the guard), and stay out of the material.
TEST(SurfaceProxy, StaysOutOfTheSkinInASlotWhereThePushOutCannotConverge) {
  const double rho = 0.39e-3;
  const VoxelTooth tooth = make_tooth(
      64, [](const Vec3& p) { return p.z() < 3.2e-3 && !(p.x() > 3.0e-3 && p.x() < 3.7e-3); });
  SurfaceProxy proxy(rho, tooth.grid().voxel_size);
  ASSERT_NEAR(proxy.skin(), 0.05e-3, 1e-15);
  const double floor_phi = rho - proxy.skin();
  // Signal guard: from the slot's centre line the bare push-out cannot reach A.
  Vec3 centre(3.35e-3, 3.2e-3, 2.5e-3);
  EXPECT_NEAR(signed_distance(tooth, centre, 1.0).phi, 0.35e-3, 1e-12);
  EXPECT_LT(proxy.push_out(tooth, &centre), -proxy.skin());
  std::mt19937_64 rng(kSeed);
  std::uniform_real_distribution<double> across(-0.1e-3, 0.1e-3);
  Vec3 c(3.35e-3, 3.2e-3, 4.5e-3);
  proxy.update(tooth, c);
  double lowest = 1.0, worst = 1.0;
  for (int tick = 0; tick < 400; ++tick) {
    c.z() = std::max(1.8e-3, c.z() - 0.02e-3);  // down into the slot, to 1.4 mm below its mouth
    c.x() = 3.35e-3 + (tick > 150 ? across(rng) : 0.0);
    if (tick > 250) c.y() += 0.01e-3;  // and along it
    const Vec3 g = proxy.update(tooth, c);
    const double phi = signed_distance(tooth, g, 1.0).phi;
    worst = std::min(worst, phi);
    lowest = std::min(lowest, g.z());
    ASSERT_GE(phi, floor_phi - 1e-12) << "tick " << tick;
  }
  std::printf("slot: g down to z = %.3f mm (mouth 3.2 mm), min phi(g) = %.4f mm (rho - s = %.3f)\n",
              lowest * 1e3, worst * 1e3, floor_phi * 1e3);
}

TEST(SurfaceProxy, ProxyFoundInsideLeavesAlongTheShortestWay) {
  // A slab z < 3.2 mm; a tool first seen 0.7 mm under its top leaves straight up (not down
  // through 2.5 mm of material).
  const VoxelTooth tooth = make_tooth(64, [](const Vec3& p) { return p.z() < 3.2e-3; });
  SurfaceProxy proxy(kRho, tooth.grid().voxel_size);
  const Vec3 c(3.15e-3, 3.05e-3, 2.5e-3);
  const Vec3 g = proxy.update(tooth, c);
  EXPECT_NEAR(g.x(), c.x(), 1e-12);
  EXPECT_NEAR(g.y(), c.y(), 1e-12);
  EXPECT_NEAR(g.z(), 3.2e-3 + kRho, 1e-12);
}

// The push-out in a concave corner (docs/derivations/sdf_contact.md §2 step 1). A Solid of the
// proxy's core that counts its queries, over either an analytic corner (the free space is the
// intersection of the half-spaces n_i . y > 0: phi = min_i n_i . y, the nearest point along the
// wall of the least index among ties) or the voxel tooth.
struct CornerSolid {
  const VoxelTooth& empty;  // a grid with no solid voxel: the push-out never thinks it is inside
  std::vector<Vec3> normals;
  mutable int queries = 0;
  const VoxelTooth& tooth() const { return empty; }
  SignedDistance distance(const Vec3& x, double reach) const {
    ++queries;
    SignedDistance sd;
    std::size_t wall = 0;
    for (std::size_t i = 1; i < normals.size(); ++i) {
      if (normals[i].dot(x) < normals[wall].dot(x)) wall = i;
    }
    sd.phi = normals[wall].dot(x);
    sd.found = sd.phi < reach;
    if (!sd.found) sd.phi = reach;
    sd.nearest = x - sd.phi * normals[wall];
    sd.voxel = wall;
    return sd;
  }
  Vec3 normal(const Vec3&, const SignedDistance& sd) const { return normals[sd.voxel]; }
  double lipschitz() const { return 1.0; }
};

struct CountingVoxelSolid {
  const VoxelTooth& voxels;
  mutable int queries = 0;
  const VoxelTooth& tooth() const { return voxels; }
  SignedDistance distance(const Vec3& x, double reach) const {
    ++queries;
    return signed_distance(voxels, x, reach);
  }
  Vec3 normal(const Vec3& x, const SignedDistance& sd) const {
    return distance_gradient(voxels, x, sd);
  }
  double lipschitz() const { return 1.0; }
};

// The push-out before the corner step, for comparison: x <- q + rho u until phi >= rho - t_p, at
// most kSurfaceProxyPushOuts steps; returns its queries (cap + 1 when it did not get there).
template <class Solid>
int plain_push_out_queries(const proxy_detail::ProxyConstants& k, const Solid& solid, Vec3 x) {
  for (int it = 0; it < kSurfaceProxyPushOuts; ++it) {
    const SignedDistance sd = solid.distance(x, k.rho);
    if (!sd.found || sd.phi >= k.rho - k.push_tol) return it + 1;
    x = sd.nearest + k.rho * solid.normal(x, sd);
  }
  return kSurfaceProxyPushOuts + 1;
}

// Two walls of a V-groove with normals 127 deg apart (n1 . n2 = -0.6: the plain step closes the
// gap to A only by 0.6 a step) and three walls of a pyramidal pit (n_i . n_j = -0.4): from the
// skin's edge (phi = rho - s) the corner step reaches A in 3 and 4 queries, on the Euclidean
// nearest point of the offset corner (the groove's offset edge, the pit's offset apex), where the
// plain step needed 10-12 and 14 or more, and ended short of it.
TEST(SurfaceProxy, PushOutLeavesAConcaveCornerInAFewQueries) {
  const VoxelTooth empty = make_tooth(4, [](const Vec3&) { return false; });
  SurfaceProxy proxy(kRho, 0.1e-3);
  const proxy_detail::ProxyConstants k = proxy.constants();
  const double s = proxy.skin();
  {
    const double a = std::atan(2.0);  // walls of slope 2: n1 . n2 = cos(2a) = -0.6
    CornerSolid groove{empty, {Vec3(std::sin(a), 0, std::cos(a)), Vec3(-std::sin(a), 0, std::cos(a))}, 0};
    ASSERT_NEAR(groove.normals[0].dot(groove.normals[1]), -0.6, 1e-15);
    for (const double off : {0.0, 0.02e-3, -0.03e-3}) {
      // Start rho - s from wall 0 (the nearer), `off` along the groove's cross-section.
      const double z = (kRho - s + std::sin(a) * std::abs(off)) / std::cos(a);
      Vec3 x(off, 1e-3, z);
      ASSERT_NEAR(groove.distance(x, kRho).phi, kRho - s, 1e-15);
      const int plain = plain_push_out_queries(k, groove, x);
      groove.queries = 0;
      const double gap = proxy_detail::push_out(k, groove, &x);
      EXPECT_LE(groove.queries, 3) << off;
      EXPECT_GE(plain, 10) << off;
      EXPECT_GE(gap, -1e-12 * kRho);
      // The offset edge (n_i . y = rho for both) nearest to the start: x = 0, z = rho / cos a.
      EXPECT_NEAR(x.x(), 0.0, 1e-15);
      EXPECT_NEAR(x.y(), 1e-3, 1e-15);
      EXPECT_NEAR(x.z(), kRho / std::cos(a), 1e-15);
    }
  }
  {
    // n_i = (sin b cos t_i, sin b sin t_i, cos b), t_i = 0, 120, 240 deg: n_i . n_j = -0.4 when
    // 1.5 cos^2 b = 0.1.
    const double b = std::acos(std::sqrt(0.1 / 1.5));
    const double pi = std::acos(-1.0);
    CornerSolid pit{empty, {}, 0};
    for (int i = 0; i < 3; ++i) {
      const double t = 2.0 * pi * i / 3.0;
      pit.normals.emplace_back(std::sin(b) * std::cos(t), std::sin(b) * std::sin(t), std::cos(b));
    }
    ASSERT_NEAR(pit.normals[0].dot(pit.normals[2]), -0.4, 1e-14);
    // On the pit's axis rho - s from the walls; the offset apex is (0, 0, rho / cos b).
    Vec3 x(0, 0, (kRho - s) / std::cos(b));
    const int plain = plain_push_out_queries(k, pit, x);
    pit.queries = 0;
    const double gap = proxy_detail::push_out(k, pit, &x);
    EXPECT_LE(pit.queries, 4);
    EXPECT_GE(plain, 14);
    EXPECT_GE(gap, -1e-12 * kRho);
    EXPECT_NEAR(x.x(), 0.0, 1e-15);
    EXPECT_NEAR(x.y(), 0.0, 1e-15);
    EXPECT_NEAR(x.z(), kRho / std::cos(b), 1e-15);
  }
}

// The same on voxel walls: a V-groove of slope 2 cut in a block (a staircase of one voxel across
// per two up) and a pit with three such walls (the free space above z0 + 2 max_i u_i . (p - c),
// u_i horizontal at 120 deg); the tip is put in them at phi = rho - s (where the swept test
// leaves it) on a 5 x 5 pattern of vertical lines a quarter voxel apart. The staircase's nearest
// features are its step edges, so the walls are not planes: the push-out reaches A (phi >= rho -
// t_p) in at most 3 queries in the groove (the plain step: up to 5) and 7 in the pit (the plain
// step ran to its cap of 16 steps from 6 of the 25 starts), never in more than the plain step;
// the move stays outside the solid (the corner step's Lipschitz bound, §2).
TEST(SurfaceProxy, PushOutLeavesAVoxelCornerInAFewQueries) {
  const double h = kSide / 64;
  const Vec3 c(3.2e-3, 3.2e-3, 2.0e-3);
  const double pi = std::acos(-1.0);
  const VoxelTooth groove = make_tooth(64, [&](const Vec3& p) {
    return p.z() < std::min(c.z() + 2.0 * std::abs(p.x() - c.x()), 5.0e-3);
  });
  const VoxelTooth pit = make_tooth(64, [&](const Vec3& p) {
    double up = -1e9;
    for (int i = 0; i < 3; ++i) {
      const double t = 2.0 * pi * i / 3.0;
      up = std::max(up, (p.x() - c.x()) * std::cos(t) + (p.y() - c.y()) * std::sin(t));
    }
    return p.z() < std::min(c.z() + 2.0 * up, 5.0e-3);
  });
  SurfaceProxy proxy(kRho, h);
  const proxy_detail::ProxyConstants k = proxy.constants();
  int worst[2] = {0, 0}, worst_plain[2] = {0, 0}, slower = 0;
  for (const int w : {0, 1}) {
    const VoxelTooth* tooth = w == 0 ? &groove : &pit;
    CountingVoxelSolid solid{*tooth, 0};
    for (int i = -2; i <= 2; ++i) {
      for (int j = -2; j <= 2; ++j) {
        // Bisection down the vertical line for phi = rho - s (phi grows with z there).
        const Vec3 line(c.x() + 0.25 * i * h, c.y() + 0.25 * j * h, 0.0);
        double lo = c.z() - 1e-3, hi = c.z() + 3e-3;
        for (int b = 0; b < 60; ++b) {
          const double mid = 0.5 * (lo + hi);
          const double phi = signed_distance(*tooth, line + Vec3(0, 0, mid), 2 * kRho).phi;
          (phi > kRho - k.skin ? hi : lo) = mid;
        }
        Vec3 x = line + Vec3(0, 0, hi);
        const Vec3 start = x;
        const int plain = plain_push_out_queries(k, solid, x);
        solid.queries = 0;
        EXPECT_GE(proxy_detail::push_out(k, solid, &x), -k.push_tol);
        for (int t = 1; t <= 10; ++t) {
          EXPECT_GT(signed_distance(*tooth, start + (t / 10.0) * (x - start), kRho).phi, 0.0);
        }
        worst[w] = std::max(worst[w], solid.queries);
        worst_plain[w] = std::max(worst_plain[w], plain);
        if (solid.queries > plain) ++slower;
      }
    }
  }
  std::printf("push-out queries at most: groove %d (plain step %d), pit %d (plain step %d)\n",
              worst[0], worst_plain[0], worst[1], worst_plain[1]);
  EXPECT_LE(worst[0], 3);
  EXPECT_GE(worst_plain[0], 5);
  EXPECT_LE(worst[1], 7);
  EXPECT_EQ(worst_plain[1], kSurfaceProxyPushOuts + 1);  // the plain step ran to its cap
  EXPECT_EQ(slower, 0);
}

TEST(SurfaceProxy, FlatFaceContactIsTheToolsDepthAndSlidesWithoutRipple) {
  const VoxelTooth tooth = make_tooth(64, [](const Vec3& p) { return p.z() < 3.2e-3; });
  ToothContactProvider provider(const_cast<VoxelTooth&>(tooth), ToolTip{kRho, Vec3::Zero()}, kK,
                                0.0, nullptr, ContactModel::kSurfaceProxy);
  std::vector<Contact> out;
  out.reserve(kContactCapacity);
  Pose pose;
  pose.x = Vec3(1e-3, 3e-3, 3.2e-3 + 2 * kRho);  // free: no contact
  ASSERT_TRUE(provider.contacts(pose, out));
  EXPECT_TRUE(out.empty());
  // Pressed 1 mm under the offset surface (2.5 radii: the face model tunnels there), sliding in x
  // across 30 voxel boundaries: the force is K * 1 mm straight up everywhere.
  const double depth = 1e-3;
  for (int tick = 0; tick < 300; ++tick) {
    pose.x = Vec3(1e-3 + tick * 0.01e-3, 3e-3, 3.2e-3 + kRho - std::min(depth, tick * 0.1e-3));
    ASSERT_TRUE(provider.contacts(pose, out));
    if (tick < 10) continue;
    ASSERT_EQ(out.size(), 1u);
    EXPECT_NEAR(out[0].depth, depth, 1e-12);
    EXPECT_NEAR(out[0].n.z(), 1.0, 1e-12);
    EXPECT_NEAR((blended_contact_force(out) - Vec3(0, 0, kK * depth)).norm(), 0.0, 1e-9);
  }
}

// The anchor's held fraction h (reference/tooth/tooth_contacts.h, the stiffness the contact
// has across its normal, reference/contact.h): on a flat face the anchor follows the tool across
// n (h = 0: the force does not turn); in a concave corner (a floor and two walls: the admissible
// set's corner is a point) it does not move at all (h = 1: the full K across n, as in a drilled
// hole). The face model has no anchored spring.
TEST(SurfaceProxy, AnchorIsFreeOnAFaceAndHeldInACorner) {
  const VoxelTooth slab = make_tooth(64, [](const Vec3& p) { return p.z() < 3.2e-3; });
  ToothContactProvider face(const_cast<VoxelTooth&>(slab), ToolTip{kRho, Vec3::Zero()}, kK, 0.0,
                            nullptr, ContactModel::kSurfaceProxy);
  ASSERT_NE(anchored_spring(&face), nullptr);
  EXPECT_EQ(anchored_spring(&face), &face.anchored_spring());
  std::vector<Contact> out;
  out.reserve(kContactCapacity);
  Pose pose;
  double worst_face = 0.0;
  for (int tick = 0; tick < 200; ++tick) {
    pose.x = Vec3(1e-3 + tick * 0.01e-3, 3e-3 + 0.005e-3 * (tick % 3), 3.2e-3 + kRho -
                  std::min(0.3e-3, tick * 0.05e-3));
    ASSERT_TRUE(face.contacts(pose, out));
    if (tick >= 10) {
      ASSERT_EQ(out.size(), 1u);
      worst_face = std::max(worst_face, face.anchored_spring().held);
    }
  }
  EXPECT_LE(worst_face, 1e-6);

  const VoxelTooth corner = make_tooth(64, [](const Vec3& p) {
    return p.z() < 3.2e-3 || p.x() < 2.4e-3 || p.y() < 2.4e-3;
  });
  ToothContactProvider held(const_cast<VoxelTooth&>(corner), ToolTip{kRho, Vec3::Zero()}, kK,
                            0.0, nullptr, ContactModel::kSurfaceProxy);
  // Down the corner's diagonal from free space to 0.2 mm behind each of the three faces, then
  // moved across n back and forth.
  const Vec3 apex(2.8e-3, 2.8e-3, 3.6e-3);  // the corner of {phi >= rho}
  const Vec3 diag = Vec3(1, 1, 1).normalized();
  const Vec3 across = Vec3(1, -1, 0).normalized();
  double least_held = 1.0;
  for (int tick = 0; tick < 120; ++tick) {
    const double along = std::max(-0.2e-3 * std::sqrt(3.0), 0.5e-3 - tick * 0.02e-3);
    const double wiggle = tick >= 60 ? 0.02e-3 * ((tick % 2) ? 1.0 : -1.0) : 0.0;
    pose.x = apex + along * diag + wiggle * across;
    ASSERT_TRUE(held.contacts(pose, out));
    if (tick >= 62) {
      ASSERT_EQ(out.size(), 1u);
      least_held = std::min(least_held, held.anchored_spring().held);
    }
  }
  std::printf("anchor held fraction: face max %.3e, corner min %.6f\n", worst_face, least_held);
  EXPECT_GE(least_held, 0.99);

  ToothContactProvider faces(const_cast<VoxelTooth&>(slab), ToolTip{kRho, Vec3::Zero()}, kK, 0.0,
                             nullptr, ContactModel::kFaces);
  EXPECT_EQ(anchored_spring(&faces), nullptr);
  NoContacts none;
  EXPECT_EQ(anchored_spring(&none), nullptr);
}

TEST(SurfaceProxy, DrillingGoesThroughTheLayersInOrderAndOpensThePulp) {
  // A layered slab on 64^3 (h = 0.1 mm): enamel 2.6-3.2 mm, dentin 1.6-2.6 mm, pulp below.
  VoxelGrid g(64, Vec3::Zero(), kSide / 64);
  for (int k = 0; k < 64; ++k) {
    for (int j = 0; j < 64; ++j) {
      for (int i = 0; i < 64; ++i) {
        const double z = g.center(i, j, k).z();
        if (z < 3.2e-3) g.set(i, j, k, z > 2.6e-3 ? kEnamel : z > 1.6e-3 ? kDentin : kPulp);
      }
    }
  }
  VoxelTooth tooth(std::move(g));
  DrillParams drill;
  drill.bur_speed_rad_s *= 20.0;  // a fast bur so that 1500 ticks reach the pulp
  ToothContactProvider provider(tooth, ToolTip{kRho, Vec3::Zero()}, kK, 0.0, &drill,
                                ContactModel::kSurfaceProxy);
  std::vector<Contact> out;
  out.reserve(kContactCapacity);
  Pose pose;
  for (int tick = 0; tick < 1500; ++tick) {
    // The tool's centre is led down from 0.2 mm above the touching height at 2 um per tick.
    pose.x = Vec3(3.2e-3, 3.2e-3, 3.2e-3 + kRho + 0.2e-3 - 2e-6 * tick);
    ASSERT_TRUE(provider.contacts(pose, out));
    // The proxy stays clear of what is left (the bur never sinks into the tooth).
    ASSERT_GE(signed_distance(tooth, provider.surface_proxy().g(), 1.0).phi,
              kRho - provider.surface_proxy().skin());
    if (!out.empty()) provider.drill(out, 1e-3);
  }
  const std::vector<DrillRecord>& log = provider.drill_log();
  ASSERT_FALSE(log.empty());
  // The material under the bur goes enamel, dentin, pulp with depth (at a boundary both are
  // under the bur, so compare the mean depth per material), and dentin first shows once the cut
  // passed the 0.6 mm of enamel (less two voxels: the bur's cap reaches ahead).
  std::array<long, kMaterialCount> seen{};
  std::array<double, kMaterialCount> depth_sum{};
  double first_dentin = -1.0;
  for (const DrillRecord& r : log) {
    ++seen[r.material];
    depth_sum[r.material] += r.depth_m;
    if (r.material == kDentin && first_dentin < 0.0) first_dentin = r.depth_m;
  }
  ASSERT_GT(seen[kEnamel], 0);
  ASSERT_GT(seen[kDentin], 0);
  ASSERT_GT(seen[kPulp], 0);
  const auto mean = [&](int m) { return depth_sum[m] / seen[m]; };
  EXPECT_LT(mean(kEnamel), mean(kDentin));
  EXPECT_LT(mean(kDentin), mean(kPulp));
  EXPECT_GE(first_dentin, 0.6e-3 - 2 * tooth.grid().voxel_size);
  const DrillState& st = provider.drill_state();
  EXPECT_GT(st.removed_voxels[kEnamel], 0);
  EXPECT_GT(st.removed_voxels[kDentin], 0);
  EXPECT_TRUE(st.pulp_exposed);
  // The pulp opened on a logged tick, once the cut had passed the 1.6 mm of enamel and dentin.
  const long opened = provider.pulp_exposed_tick();
  ASSERT_GT(opened, 0);
  const auto at =
      std::find_if(log.begin(), log.end(), [&](const DrillRecord& r) { return r.tick == opened; });
  ASSERT_NE(at, log.end());
  EXPECT_GE(at->depth_m, 1.6e-3 - 2 * tooth.grid().voxel_size);
}

TEST(ContactModel, ParsesTheSceneNames) {
  EXPECT_EQ(parse_contact_model("faces"), ContactModel::kFaces);
  EXPECT_EQ(parse_contact_model("sdf"), ContactModel::kSurfaceProxy);
  EXPECT_STREQ(contact_model_name(ContactModel::kSurfaceProxy), "sdf");
  EXPECT_THROW(parse_contact_model("voxels"), InputError);
}

}  // namespace
}  // namespace dentsim
