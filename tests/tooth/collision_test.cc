// Collision of the tip sphere with the voxel tooth (reference/tooth/collision.h): the closed-form
// disk/rectangle area, the contact-set contract, no force from edges between face-adjacent voxels,
// smoothness across voxel boundaries on a flat face, an edge and a corner, and resolution
// independence. Bounds measured and stated in docs/tooth_octree.md.
#include "reference/tooth/collision.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <random>

#include "reference/core/io.h"
#include "reference/core/so3.h"

namespace dentsim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kK = 3000.0;        // K_tooth [N/m]
constexpr double kB = 2.0;           // B_tooth [N s/m]
constexpr double kRho = 0.5e-3;      // bur radius [m]
constexpr double kSide = 3.2e-3;     // grid edge [m]
constexpr double kFeature = 1.6e-3;  // faces of the test solids lie on x, y, z = kFeature
constexpr std::uint64_t kSeed = 777;

// Voxelises {p : inside(p)} by the voxel-centre test on an n^3 grid over [0, kSide]^3.
VoxelTooth make_tooth(int n, const std::function<bool(const Vec3&)>& inside,
                      std::uint8_t material = kEnamel) {
  VoxelGrid g(n, Vec3::Zero(), kSide / n);
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        if (inside(g.center(i, j, k))) g.set(i, j, k, material);
      }
    }
  }
  return VoxelTooth(std::move(g));
}

bool half_space(const Vec3& p) { return p.z() < kFeature; }
bool edge_solid(const Vec3& p) { return p.x() < kFeature && p.z() < kFeature; }
bool corner_solid(const Vec3& p) {
  return p.x() < kFeature && p.y() < kFeature && p.z() < kFeature;
}
// A concave groove: floor z < kFeature and a wall x > 2.2 mm.
bool groove_solid(const Vec3& p) { return p.z() < kFeature || p.x() > 2.2e-3; }

std::vector<Contact> collide_at(const VoxelTooth& tooth, const Vec3& c,
                                std::vector<std::size_t>* voxels = nullptr) {
  Pose pose;
  pose.x = c;
  ToolTip tip;
  tip.radius = kRho;
  CollisionScratch scratch;
  std::vector<Contact> contacts;
  collide_tool_tip(tooth, pose, tip, kK, kB, &scratch, &contacts, voxels);
  return contacts;
}

Vec3 force_at(const VoxelTooth& tooth, const Vec3& c) {
  return blended_contact_force(collide_at(tooth, c));
}

// Numerical area of disk ∩ rectangle by the midpoint rule on the chord length (the oracle).
double disk_rect_area_numeric(double a, double x0, double x1, double y0, double y1) {
  const int m = 200000;
  const double lo = std::max(x0, -a), hi = std::min(x1, a);
  if (lo >= hi) return 0.0;
  const double dx = (hi - lo) / m;
  double area = 0.0;
  for (int i = 0; i < m; ++i) {
    const double x = lo + (i + 0.5) * dx;
    const double s = std::sqrt(a * a - x * x);
    area += std::max(0.0, std::min(y1, s) - std::max(y0, -s)) * dx;
  }
  return area;
}

TEST(DiskRectArea, ClosedFormsAndNumericOracle) {
  const double a = 1.3;
  EXPECT_NEAR(disk_rect_area(a, -2, 2, -2, 2), kPi * a * a, 1e-14);
  EXPECT_NEAR(disk_rect_area(a, -0.5, 0.5, -0.5, 0.5), 1.0, 1e-15);  // rectangle inside the disk
  EXPECT_NEAR(disk_rect_area(a, 0, 5, -5, 5), 0.5 * kPi * a * a, 1e-14);
  EXPECT_NEAR(disk_rect_area(a, 0, 5, 0, 5), 0.25 * kPi * a * a, 1e-14);
  EXPECT_EQ(disk_rect_area(a, 1.3, 5, -1, 1), 0.0);
  EXPECT_EQ(disk_rect_area(0.0, -1, 1, -1, 1), 0.0);
  std::mt19937_64 rng(kSeed);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  for (int t = 0; t < 200; ++t) {
    double x0 = u(rng), x1 = u(rng), y0 = u(rng), y1 = u(rng);
    if (x0 > x1) std::swap(x0, x1);
    if (y0 > y1) std::swap(y0, y1);
    const double exact = disk_rect_area(a, x0, x1, y0, y1);
    ASSERT_NEAR(exact, disk_rect_area_numeric(a, x0, x1, y0, y1), 2e-8) << "trial " << t;
    // Additivity: splitting the rectangle partitions the area.
    const double xm = 0.5 * (x0 + x1);
    ASSERT_NEAR(exact, disk_rect_area(a, x0, xm, y0, y1) + disk_rect_area(a, xm, x1, y0, y1),
                1e-14);
  }
}

TEST(Collision, ContactSetContract) {
  // Half-space z < kFeature, a rotated proxy whose tip is offset in the body frame.
  const VoxelTooth tooth = make_tooth(32, half_space, kDentin);
  std::mt19937_64 rng(kSeed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int t = 0; t < 50; ++t) {
    Pose pose;
    pose.R = exp_so3(Vec3(u(rng), u(rng), u(rng)) * 2.0);
    ToolTip tip;
    tip.radius = kRho;
    tip.offset_body = Vec3(u(rng), u(rng), u(rng)) * 1e-3;
    const double delta = 0.05e-3 + 0.3e-3 * (u(rng) + 1.0);
    const Vec3 c(1.6e-3 + 0.5e-3 * u(rng), 1.6e-3 + 0.5e-3 * u(rng), kFeature + kRho - delta);
    pose.x = c - pose.R * tip.offset_body;
    CollisionScratch scratch;
    std::vector<Contact> contacts;
    std::vector<std::size_t> voxels;
    collide_tool_tip(tooth, pose, tip, kK, kB, &scratch, &contacts, &voxels);
    ASSERT_FALSE(contacts.empty());
    ASSERT_EQ(voxels.size(), contacts.size());
    double total_weight = 0.0;
    for (const Contact& ct : contacts) {
      EXPECT_EQ(ct.n, Vec3::UnitZ());
      const Vec3 x_c = pose.x + pose.R * ct.r;  // x_c = x_2 + R_2 r
      EXPECT_LT((x_c - (c - kRho * ct.n)).norm(), 1e-15);
      EXPECT_NEAR(ct.depth, ct.n.dot(ct.x_o - x_c), 1e-15);  // (2.15)
      EXPECT_NEAR(ct.depth, delta, 1e-15);
      EXPECT_NEAR(ct.x_o.z(), kFeature, 1e-15);
      EXPECT_EQ(ct.stiffness, kK * 0.7);
      EXPECT_EQ(ct.damping, kB * 0.7);
      EXPECT_EQ(ct.material, kDentin);
      EXPECT_GT(ct.weight, 0.0);
      total_weight += ct.weight;
    }
    // The face weights partition the sphere's cross-section with the face plane.
    const double a2 = kRho * kRho - (kRho - delta) * (kRho - delta);
    EXPECT_NEAR(total_weight, kPi * a2, 1e-12 * kPi * a2);
  }
  // No contact when only touching, and a bad radius is an input error.
  EXPECT_TRUE(collide_at(tooth, Vec3(1.6e-3, 1.6e-3, kFeature + kRho)).empty());
  Pose pose;
  ToolTip bad;
  bad.radius = 0.0;
  CollisionScratch scratch;
  std::vector<Contact> contacts;
  EXPECT_THROW(collide_tool_tip(tooth, pose, bad, kK, kB, &scratch, &contacts), InputError);
}

TEST(Collision, EdgesBetweenFaceAdjacentVoxelsGiveNoForce) {
  // Over the shared edge (and the shared corner) of top-layer voxels only +z faces contribute.
  const VoxelTooth tooth = make_tooth(16, half_space);
  const double h = tooth.grid().voxel_size;
  for (const Vec3& c :
       {Vec3(8 * h, 8.5 * h, kFeature + kRho - 0.1e-3),
        Vec3(8 * h, 8 * h, kFeature + kRho - 0.1e-3), Vec3(8 * h, 8 * h, kFeature + kRho - 1e-9)}) {
    const std::vector<Contact> contacts = collide_at(tooth, c);
    ASSERT_FALSE(contacts.empty());
    for (const Contact& ct : contacts) EXPECT_EQ(ct.n, Vec3::UnitZ());
    const Vec3 f = blended_contact_force(contacts);
    const double delta = kFeature + kRho - c.z();
    EXPECT_NEAR(f.z(), kK * delta, 1e-15 * kK);  // delta itself carries round-off ~1e-19 m
    EXPECT_EQ(f.x(), 0.0);
    EXPECT_EQ(f.y(), 0.0);
  }
}

// Largest change of the force between consecutive samples of a path p(s), s in [0, 1], and the
// largest ratio |dF| / |dc| (a discrete Lipschitz constant).
struct Jumps {
  double max_jump = 0.0;
  double max_ratio = 0.0;
};
Jumps max_jump(const VoxelTooth& tooth, const std::function<Vec3(double)>& path, int samples) {
  Jumps j;
  Vec3 prev_c = path(0.0);
  Vec3 prev = force_at(tooth, prev_c);
  for (int i = 1; i <= samples; ++i) {
    const Vec3 c = path(static_cast<double>(i) / samples);
    const Vec3 f = force_at(tooth, c);
    j.max_jump = std::max(j.max_jump, (f - prev).norm());
    j.max_ratio = std::max(j.max_ratio, (f - prev).norm() / (c - prev_c).norm());
    prev = f;
    prev_c = c;
  }
  return j;
}

TEST(Collision, FlatFaceForceIsExactlyKDeltaAcrossVoxelBoundaries) {
  // Sliding at fixed depth across 8 voxel boundaries (and their corners, diagonally).
  const double delta = 0.1e-3;
  for (const int n : {16, 32, 64}) {
    const VoxelTooth tooth = make_tooth(n, half_space);
    double worst = 0.0;
    for (int i = 0; i <= 2000; ++i) {
      const double s = i / 2000.0;
      const Vec3 c(0.8e-3 + 1.6e-3 * s, 0.9e-3 + 1.3e-3 * s, kFeature + kRho - delta);
      worst = std::max(worst, (force_at(tooth, c) - kK * delta * Vec3::UnitZ()).norm());
    }
    std::printf("flat face n=%d: max |F - K delta n| = %.3g N (K delta = %.3g N)\n", n, worst,
                kK * delta);
    EXPECT_LT(worst, 1e-12 * kK * delta);
  }
}

TEST(Collision, EdgeAndCornerForcesAreContinuousAndResolutionIndependent) {
  const double delta = 0.1e-3;
  const double dist = kRho - delta;  // distance from the sphere centre to the edge / corner
  struct Case {
    const char* name;
    std::function<bool(const Vec3&)> solid;
    std::function<Vec3(double)> path;
  };
  const std::vector<Case> cases = {
      // Along the convex edge (x = z = kFeature, direction y) at 45 degrees: crosses 8 boundaries.
      {"edge, along", edge_solid,
       [&](double s) {
         return Vec3(kFeature + dist / std::sqrt(2.0), 0.8e-3 + 1.6e-3 * s,
                     kFeature + dist / std::sqrt(2.0));
       }},
      // Around the edge at fixed distance, from over the top face (-30 deg) to the side (120 deg).
      {"edge, around", edge_solid,
       [&](double s) {
         const double th = (-30.0 + 150.0 * s) * kPi / 180.0;
         return Vec3(kFeature + dist * std::cos(th), 1.53e-3, kFeature + dist * std::sin(th));
       }},
      // Over the corner at fixed distance from the corner point, in the diagonal plane x = y, from
      // over the top face (10 deg) past the corner (170 deg). The centre stays outside every face
      // plane whose patch it projects onto (penetration < rho): the smooth regime of
      // docs/tooth_octree.md; at 0 deg the centre lies on the top plane (penetration = rho).
      {"corner, around", corner_solid,
       [&](double s) {
         const double th = (10.0 + 160.0 * s) * kPi / 180.0;
         const double xy = kFeature - dist * std::cos(th) / std::sqrt(2.0);
         return Vec3(xy, xy, kFeature + dist * std::sin(th));
       }},
      // Straight across the corner region at constant height, crossing voxel boundaries.
      {"corner, across", corner_solid,
       [&](double s) { return Vec3(0.9e-3 + 1.4e-3 * s, 1.45e-3, kFeature + dist * 0.8); }},
      // Into a concave groove: over the floor, then against floor and wall together.
      {"groove, into", groove_solid,
       [&](double s) { return Vec3(1.2e-3 + 0.8e-3 * s, 1.55e-3, kFeature + dist); }},
  };
  for (const Case& cs : cases) {
    std::vector<VoxelTooth> teeth;
    for (const int n : {16, 32, 64}) teeth.push_back(make_tooth(n, cs.solid));
    // Resolution independence: the solids are voxel-aligned at every resolution, so the face
    // weights partition the same regions and the blended force is the same up to round-off.
    double res_dev = 0.0, f_max = 0.0;
    for (int i = 0; i <= 400; ++i) {
      const Vec3 c = cs.path(i / 400.0);
      const Vec3 f16 = force_at(teeth[0], c);
      f_max = std::max(f_max, f16.norm());
      for (int r = 1; r < 3; ++r) res_dev = std::max(res_dev, (force_at(teeth[r], c) - f16).norm());
    }
    // Continuity: a jump would not shrink with the step; here the largest step-to-step change
    // falls with the step (at least 3x for a 10x finer step) and stays below 1.25 K |dc|.
    const Jumps coarse = max_jump(teeth[1], cs.path, 200);
    const Jumps fine = max_jump(teeth[1], cs.path, 2000);
    std::printf(
        "%-15s |F|max %.4g N, resolution deviation %.3g N, max jump %.4g N (200 steps) "
        "-> %.4g N (2000 steps), max |dF|/|dc| = %.3f K\n",
        cs.name, f_max, res_dev, coarse.max_jump, fine.max_jump, fine.max_ratio / kK);
    EXPECT_GT(f_max, 0.5 * kK * delta) << cs.name;
    // Round-off, except that a face boundary one ulp apart at two resolutions moves the area of a
    // nearly tangent disk by ~sqrt(ulp): bound 1e-7 K delta (measured <= 1.1e-10 N = 4e-10 K
    // delta).
    EXPECT_LT(res_dev, 1e-7 * kK * delta) << cs.name;
    EXPECT_LT(fine.max_jump, coarse.max_jump / 3.0 + 1e-12) << cs.name;
    EXPECT_LT(fine.max_jump, 0.05 * kK * delta) << cs.name;
    // The stated bound: |dF| <= 1.25 K |dc| (a single penalty spring on a plane has exactly K;
    // the blend of floor and wall in the groove measures 1.11 K).
    EXPECT_LT(fine.max_ratio, 1.25 * kK) << cs.name;
  }
}

TEST(Collision, StaircaseBallConvergesWithResolution) {
  // A ball of radius R = 1.2 mm (not voxel-aligned): the tip pressed radially to depth delta below
  // the true surface. Two effects: the staircase (O(h)) and the footprint blend, which averages
  // the plane depths over the disk of radius a (a^2 = 2 rho delta - delta^2) and so sees the
  // surface curve away by up to a^2 / (2 R). Bound: ||F|/K - delta| <= a^2 / (2 R) + h; and the
  // force converges: max |F_2n - F_n| falls as n doubles.
  const double big = 1.2e-3, delta = 0.15e-3;
  const double a2 = 2.0 * kRho * delta - delta * delta;
  const Vec3 centre = Vec3::Constant(1.6e-3);
  std::mt19937_64 rng(kSeed);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<Vec3> dirs;
  for (int t = 0; t < 200; ++t) {
    const Vec3 d(g(rng), g(rng), g(rng));
    dirs.push_back(d.normalized());
  }
  std::vector<std::vector<Vec3>> forces;
  for (const int n : {32, 64, 128}) {
    const VoxelTooth tooth =
        make_tooth(n, [&](const Vec3& p) { return (p - centre).norm() < big; });
    const double h = kSide / n;
    double max_err = 0.0, max_angle = 0.0;
    forces.emplace_back();
    for (const Vec3& d : dirs) {
      const Vec3 c = centre + (big + kRho - delta) * d;
      const Vec3 f = force_at(tooth, c);
      forces.back().push_back(f);
      max_err = std::max(max_err, std::abs(f.norm() / kK - delta));
      max_angle = std::max(max_angle, std::acos(std::clamp(f.normalized().dot(d), -1.0, 1.0)));
    }
    std::printf(
        "ball n=%d h=%.3g mm: max ||F|/K - delta| = %.4g mm (bound a^2/2R + h = %.4g mm), "
        "max angle to the radius %.1f deg\n",
        n, h * 1e3, max_err * 1e3, (a2 / (2 * big) + h) * 1e3, max_angle * 180.0 / kPi);
    EXPECT_LT(max_err, a2 / (2 * big) + h) << "n=" << n;
  }
  double dev[2] = {0.0, 0.0};
  for (int r = 0; r < 2; ++r) {
    for (std::size_t t = 0; t < dirs.size(); ++t) {
      dev[r] = std::max(dev[r], (forces[r + 1][t] - forces[r][t]).norm());
    }
  }
  std::printf("ball: max |F64 - F32| = %.4g N, max |F128 - F64| = %.4g N (K delta = %.3g N)\n",
              dev[0], dev[1], kK * delta);
  EXPECT_LT(dev[1], dev[0]);
}

TEST(Collision, ContactVoxelsAndMaterialsPerFace) {
  // Flat top layer, enamel for x < 1.6 mm and dentin beyond: each contact reports the material
  // and stiffness of the voxel whose face it is, and `voxels` names that voxel.
  VoxelGrid g(32, Vec3::Zero(), kSide / 32);
  for (int k = 0; k < 16; ++k) {
    for (int j = 0; j < 32; ++j) {
      for (int i = 0; i < 32; ++i) g.set(i, j, k, i < 16 ? kEnamel : kDentin);
    }
  }
  const VoxelTooth tooth(std::move(g));
  std::vector<std::size_t> voxels;
  const std::vector<Contact> contacts =
      collide_at(tooth, Vec3(1.6e-3, 1.6e-3, kFeature + kRho - 0.1e-3), &voxels);
  ASSERT_EQ(voxels.size(), contacts.size());
  int enamel = 0, dentin = 0;
  double w_enamel = 0.0, w_dentin = 0.0;
  for (std::size_t i = 0; i < contacts.size(); ++i) {
    const std::size_t v = voxels[i];
    const int vk = static_cast<int>(v / 1024);
    EXPECT_EQ(vk, 15);  // the top layer's +z faces
    EXPECT_EQ(contacts[i].material, tooth.grid().voxels[v]);
    EXPECT_EQ(contacts[i].stiffness,
              kK * material_properties(tooth.grid().voxels[v]).stiffness_scale);
    // x_o is the nearest point of the face's flat patch: here the projection of c on the plane.
    EXPECT_NEAR(contacts[i].x_o.z(), kFeature, 1e-18);
    EXPECT_NEAR(contacts[i].x_o.x(), 1.6e-3, 1e-18);
    EXPECT_NEAR(contacts[i].x_o.y(), 1.6e-3, 1e-18);
    (contacts[i].material == kEnamel ? enamel : dentin)++;
    (contacts[i].material == kEnamel ? w_enamel : w_dentin) += contacts[i].weight;
  }
  EXPECT_GT(enamel, 0);
  EXPECT_GT(dentin, 0);
  // Centred on the material boundary: half the footprint each, so the blend is 0.85 K delta.
  EXPECT_NEAR(w_enamel, w_dentin, 1e-12 * w_enamel);
  EXPECT_NEAR(blended_contact_force(contacts).z(), 0.85 * kK * 0.1e-3, 1e-12);
}

TEST(Collision, SteadyStateDoesNotGrowItsBuffers) {
  // With reserved buffers, repeated queries keep their capacity (no reallocation per tick).
  const VoxelTooth tooth = make_tooth(32, corner_solid);
  Pose pose;
  ToolTip t;
  t.radius = kRho;
  CollisionScratch scratch;
  std::vector<Contact> contacts;
  std::vector<std::size_t> voxels;
  contacts.reserve(1024);
  voxels.reserve(1024);
  const std::size_t cap_scratch = scratch.candidates.capacity();
  std::mt19937_64 rng(kSeed);
  std::uniform_real_distribution<double> u(-0.5e-3, 0.5e-3);
  std::size_t most = 0;
  for (int tick = 0; tick < 2000; ++tick) {
    pose.x = Vec3::Constant(kFeature) + Vec3(u(rng), u(rng), u(rng));
    contacts.clear();
    voxels.clear();
    collide_tool_tip(tooth, pose, t, kK, kB, &scratch, &contacts, &voxels);
    most = std::max(most, contacts.size());
    ASSERT_EQ(contacts.capacity(), 1024u);
    ASSERT_EQ(voxels.capacity(), 1024u);
    ASSERT_EQ(scratch.candidates.capacity(), cap_scratch);
  }
  EXPECT_GT(most, 10u);
}

}  // namespace
}  // namespace dentsim
