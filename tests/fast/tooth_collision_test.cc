// The fast tooth query (fast/tooth/collision.h) against the reference (reference/tooth/
// collision.h): the same contact set -- members, order, voxel indices, every double bitwise --
// over seeded random poses and bur radii on the procedural molar and on a real mesh, and on
// adversarial poses: the tip centre on voxel faces, edges and corners, grazing contact, a tip deep
// inside, a one-voxel-thick wall, a full buffer, every material. Tolerance: exact (docs/tolerance_policy.md 1; the
// fast path evaluates the reference's expressions, see fast/tooth/collision.cc).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "fast/tooth/collision.h"
#include "reference/core/io.h"
#include "reference/tooth/materials.h"
#include "tooth_io/mesh.h"
#include "tooth_io/procedural_molar.h"
#include "tooth_io/voxelize.h"
#include "tests/fast/tooth_diff.h"
#include "tests/support/shared_meshes.h"
#include "tests/support/stress.h"

namespace dentsim {
namespace {

using testing::ContactSet;
using testing::fast_set;
using testing::random_pose_near;
using testing::reference_set;
using testing::same_set;
using testing::surface_voxels_of;

constexpr std::uint64_t kSeed = 20261124;

const VoxelTooth& molar(int n) {
  static const VoxelTooth t64(voxelize_procedural_molar(MolarParams{}, 64));
  static const VoxelTooth t128(voxelize_procedural_molar(MolarParams{}, 128));
  if (n == 64) return t64;
  return t128;
}

struct DiffStats {
  long poses = 0, contacts = 0, empty = 0, deep = 0;
};

// Random poses and radii rho in [0.1, 1.2] mm (up to several hundred contacts at 128^3), random
// tip offsets up to 2 mm: every pose's sets must be equal.
DiffStats random_poses(const VoxelTooth& ref, const fast::BrickTooth& fst, long count,
                       std::uint64_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> radius(0.1e-3, 1.2e-3), unit(-1.0, 1.0);
  const std::vector<std::size_t> surface = surface_voxels_of(ref.codes.dense());
  DiffStats stats;
  for (long p = 0; p < count; ++p) {
    ToolTip tip;
    tip.radius = radius(rng);
    tip.offset_body = 2e-3 * Vec3(unit(rng), unit(rng), unit(rng));
    const Pose pose = random_pose_near(ref.grid(), surface, tip.radius, tip.offset_body, rng);
    const ContactSet a = reference_set(ref, pose, tip);
    const ContactSet b = fast_set(fst, pose, tip);
    if (!same_set(a, b, "seed " + std::to_string(seed) + " pose " + std::to_string(p))) break;
    ++stats.poses;
    stats.contacts += static_cast<long>(a.contacts.size());
    if (a.contacts.empty()) ++stats.empty;
    for (const Contact& ct : a.contacts) {
      if (ct.depth > tip.radius) {  // centre behind a face plane
        ++stats.deep;
        break;
      }
    }
  }
  return stats;
}

TEST(FastToothCollision, DiskRectAreaBitwiseEqualsReference) {
  std::mt19937 rng(kSeed);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  int partial = 0;
  for (int t = 0; t < 200000; ++t) {
    const double a = t % 7 == 0 ? 0.0 : std::abs(u(rng));
    double x0 = u(rng), x1 = u(rng), y0 = u(rng), y1 = u(rng);
    if (x0 > x1) std::swap(x0, x1);
    if (y0 > y1) std::swap(y0, y1);
    const double ref = disk_rect_area(a, x0, x1, y0, y1);
    ASSERT_EQ(ref, fast::disk_rect_area(a, x0, x1, y0, y1))
        << "a " << a << " [" << x0 << ", " << x1 << "] x [" << y0 << ", " << y1 << "]";
    if (ref > 0.0 && ref < (x1 - x0) * (y1 - y0) * (1 - 1e-9)) ++partial;
  }
  EXPECT_GT(partial, 10000);  // the chord pieces were exercised, not only full squares
}

TEST(FastToothCollision, BricksHoldExactlyTheSurfaceVoxels) {
  const VoxelTooth& ref = molar(64);
  const fast::BrickTooth fst(ref);
  const int n = ref.grid().n;
  const int lo[3] = {0, 0, 0}, hi[3] = {n - 1, n - 1, n - 1};
  std::vector<std::size_t> visited;
  fst.for_each_surface_voxel(lo, hi, [&](int i, int j, int k, std::size_t v) {
    EXPECT_EQ(v, ref.grid().index(i, j, k));
    visited.push_back(v);
  });
  std::vector<std::size_t> expected = surface_voxels_of(ref.codes.dense());
  ASSERT_GT(expected.size(), 1000u);
  std::sort(visited.begin(), visited.end());
  EXPECT_EQ(visited, expected);
}

// The visiting order is the reference octree's: on a box around a random point, the fast walk's
// sequence equals query_sphere's sequence with the interior voxels (code 0) removed.
TEST(FastToothCollision, SurfaceOrderEqualsOctreeOrder) {
  const VoxelTooth& ref = molar(64);
  const fast::BrickTooth fst(ref);
  const int n = ref.grid().n;
  // A sphere covering the whole grid: every solid voxel is a candidate.
  const Vec3 mid = ref.grid().origin + 0.5 * n * ref.grid().voxel_size * Vec3::Ones();
  std::vector<std::size_t> octree;
  ref.octree.query_sphere(mid, 2.0 * n * ref.grid().voxel_size, &octree);
  std::vector<std::size_t> expected;
  for (const std::size_t v : octree) {
    if (ref.codes.code(v) != 0) expected.push_back(v);
  }
  std::vector<std::size_t> visited;
  const int lo[3] = {0, 0, 0}, hi[3] = {n - 1, n - 1, n - 1};
  fst.for_each_surface_voxel(lo, hi, [&](int, int, int, std::size_t v) { visited.push_back(v); });
  ASSERT_GT(expected.size(), 1000u);
  EXPECT_EQ(visited, expected);
}

TEST(FastToothCollision, RandomPosesOnTheMolarEqualReference) {
  for (const int n : {64, 128}) {
    const VoxelTooth& ref = molar(n);
    const fast::BrickTooth fst(ref);
    const DiffStats s = random_poses(ref, fst, 1500, kSeed + n);
    std::printf("%d^3: %ld poses, %ld contacts, %ld empty, %ld deep\n", n, s.poses, s.contacts,
                s.empty, s.deep);
    EXPECT_EQ(s.poses, 1500);
    // Signal guard: most poses touch, some do not, some are deep (centre behind a face).
    EXPECT_GT(s.contacts, 5 * s.poses);
    EXPECT_GT(s.empty, 10);
    EXPECT_GT(s.deep, 10);
  }
}

TEST(FastToothCollision, RealMeshEqualsReference) {
  const std::unique_ptr<VoxelTooth> tooth = test::shared_molar_tooth(64);
  if (tooth == nullptr) GTEST_SKIP() << "absent: " << test::shared_data_path("molar-cc0.stl");
  const VoxelTooth& ref = *tooth;
  const fast::BrickTooth fst(ref);
  const DiffStats s = random_poses(ref, fst, 1000, kSeed + 1);
  EXPECT_EQ(s.poses, 1000);
  EXPECT_GT(s.contacts, 10 * s.poses);
}

// A tip centred exactly on lattice points of the grid (voxel corners), on edge midpoints and face
// centres, at distances from the surface that are multiples of h/4 (grazing at exactly rho: no
// contact; below it: contact), radius a multiple of h as well.
TEST(FastToothCollision, TipOnFacesEdgesAndCornersEqualsReference) {
  const VoxelTooth& ref = molar(64);
  const fast::BrickTooth fst(ref);
  const VoxelGrid& g = ref.grid();
  const double h = g.voxel_size;
  const std::vector<std::size_t> surface = surface_voxels_of(ref.codes.dense());
  std::mt19937 rng(kSeed + 2);
  std::uniform_int_distribution<int> quarter(0, 4), pick_r(1, 8);
  long touching = 0, cases = 0;
  for (int t = 0; t < 3000; ++t) {
    const std::size_t v = surface[rng() % surface.size()];
    const int n = g.n;
    const int idx[3] = {static_cast<int>(v % n), static_cast<int>((v / n) % n),
                        static_cast<int>(v / (static_cast<std::size_t>(n) * n))};
    Pose pose;
    for (int a = 0; a < 3; ++a) {
      pose.x[a] = g.origin[a] + h * (idx[a] + 0.25 * quarter(rng) + (rng() % 3) - 1.0);
    }
    ToolTip tip;
    tip.radius = 0.25 * h * pick_r(rng);
    const ContactSet a = reference_set(ref, pose, tip);
    if (!same_set(a, fast_set(fst, pose, tip), "lattice case " + std::to_string(t))) return;
    ++cases;
    if (!a.contacts.empty()) ++touching;
  }
  EXPECT_GT(touching, cases / 4);
}

// Grazing: the tip at distance rho (1 +- k eps) from a flat exposed face (top of a slab).
TEST(FastToothCollision, GrazingAFaceEqualsReference) {
  VoxelGrid g(16, Vec3(-1e-3, -2e-3, 0.5e-3), 0.25e-3);
  for (int k = 0; k < 8; ++k) {
    for (int j = 0; j < 16; ++j) {
      for (int i = 0; i < 16; ++i) g.set(i, j, k, kDentin);
    }
  }
  const VoxelTooth ref(g);
  const fast::BrickTooth fst(ref);
  const double top = g.origin.z() + 8 * g.voxel_size;
  ToolTip tip;
  tip.radius = 0.6e-3;
  int touching = 0;
  for (int s = -4; s <= 4; ++s) {
    for (const double x : {0.0, 0.25e-3, 0.125e-3, 0.3e-3}) {
      Pose pose;
      pose.x = Vec3(x, -0.1e-3, top + tip.radius * (1.0 + s * 2.2e-16));
      const ContactSet a = reference_set(ref, pose, tip);
      EXPECT_TRUE(same_set(a, fast_set(fst, pose, tip), "grazing s " + std::to_string(s)));
      if (!a.contacts.empty()) ++touching;
    }
  }
  EXPECT_GT(touching, 0);
  EXPECT_LT(touching, 36);
}

// A tip deep inside the crown (centre several voxels below the surface) and a tip in free space.
TEST(FastToothCollision, DeepInsideAndFreeSpaceEqualReference) {
  const VoxelTooth& ref = molar(64);
  const fast::BrickTooth fst(ref);
  const VoxelGrid& g = ref.grid();
  const int c = g.n / 2;
  int top = 0;
  for (int k = 0; k < g.n; ++k) {
    if (g.solid(c, c, k)) top = k;
  }
  ToolTip tip;
  tip.radius = 4.0 * g.voxel_size;
  for (int depth = 0; depth <= 8; ++depth) {
    Pose pose;
    pose.x = g.center(c, c, top - depth) + Vec3(0.1, 0.3, 0.0) * g.voxel_size;
    EXPECT_TRUE(same_set(reference_set(ref, pose, tip), fast_set(fst, pose, tip),
                         "depth " + std::to_string(depth)));
  }
  Pose far;
  far.x = g.origin + Vec3(-5e-3, 0.0, 0.0);
  const ContactSet none = fast_set(fst, far, tip);
  EXPECT_TRUE(none.complete);
  EXPECT_TRUE(none.contacts.empty());
  far.x = Vec3(std::nan(""), 0.0, 0.0);
  EXPECT_TRUE(same_set(reference_set(ref, far, tip), fast_set(fst, far, tip), "NaN centre"));
}

// A wall one voxel thick (x = 8, solid in y, z): the tip on either side and inside it.
TEST(FastToothCollision, OneVoxelWallEqualsReference) {
  VoxelGrid g(16, Vec3::Zero(), 0.2e-3);
  for (int k = 0; k < 16; ++k) {
    for (int j = 2; j < 14; ++j) g.set(8, j, k, j < 8 ? kEnamel : kDentin);
  }
  const VoxelTooth ref(g);
  const fast::BrickTooth fst(ref);
  ToolTip tip;
  tip.radius = 0.5e-3;
  int touching = 0;
  for (int s = -12; s <= 12; ++s) {
    Pose pose;
    pose.x = Vec3(8.5 * 0.2e-3 + s * 0.05e-3, 7.3 * 0.2e-3, 6.0 * 0.2e-3);
    const ContactSet a = reference_set(ref, pose, tip);
    EXPECT_TRUE(same_set(a, fast_set(fst, pose, tip), "wall s " + std::to_string(s)));
    if (!a.contacts.empty()) ++touching;
  }
  EXPECT_GT(touching, 10);
}

// Every material (enamel, dentin, pulp, caries: each scales stiffness and damping differently):
// a ball whose voxels take a random material each, so every contact set mixes them.
TEST(FastToothCollision, EveryMaterialEqualsReference) {
  std::mt19937 rng(kSeed + 7);
  std::uniform_int_distribution<int> material(kEnamel, kCaries);
  VoxelGrid g(32, Vec3::Zero(), 0.1e-3);
  const Vec3 centre(1.6e-3, 1.6e-3, 1.6e-3);
  for (int k = 0; k < 32; ++k) {
    for (int j = 0; j < 32; ++j) {
      for (int i = 0; i < 32; ++i) {
        if ((g.center(i, j, k) - centre).norm() < 1.2e-3) {
          g.set(i, j, k, static_cast<std::uint8_t>(material(rng)));
        }
      }
    }
  }
  const VoxelTooth ref(g);
  const fast::BrickTooth fst(ref);
  const std::vector<std::size_t> surface = surface_voxels_of(ref.codes.dense());
  std::array<long, kMaterialCount> seen{};
  std::uniform_real_distribution<double> radius(0.1e-3, 0.6e-3);
  for (int p = 0; p < 300; ++p) {
    ToolTip tip;
    tip.radius = radius(rng);
    const Pose pose = random_pose_near(ref.grid(), surface, tip.radius, tip.offset_body, rng);
    const ContactSet a = reference_set(ref, pose, tip);
    ASSERT_TRUE(same_set(a, fast_set(fst, pose, tip), "pose " + std::to_string(p)));
    for (const Contact& c : a.contacts) ++seen[static_cast<std::size_t>(c.material)];
  }
  for (int m = kEnamel; m < kMaterialCount; ++m) {
    EXPECT_GT(seen[static_cast<std::size_t>(m)], 100)
        << material_properties(static_cast<std::uint8_t>(m)).name;
  }
}

// A buffer too small: both stop at the same member and report false.
TEST(FastToothCollision, FullBufferStopsAtTheSameMember) {
  const VoxelTooth& ref = molar(128);
  const fast::BrickTooth fst(ref);
  std::mt19937 rng(kSeed + 3);
  const std::vector<std::size_t> surface = surface_voxels_of(ref.codes.dense());
  ToolTip tip;
  tip.radius = 1e-3;
  int truncated = 0;
  for (int t = 0; t < 50; ++t) {
    const Pose pose = random_pose_near(ref.grid(), surface, tip.radius, Vec3::Zero(), rng);
    const ContactSet a = reference_set(ref, pose, tip, 17);
    EXPECT_TRUE(same_set(a, fast_set(fst, pose, tip, 17), "truncated " + std::to_string(t)));
    if (!a.complete) ++truncated;
  }
  EXPECT_GT(truncated, 10);
}

TEST(FastToothCollision, RejectsNonPositiveRadius) {
  const fast::BrickTooth fst(molar(64));
  ToolTip tip;
  tip.radius = 0.0;
  std::vector<Contact> contacts;
  EXPECT_THROW(fast::collide_tool_tip(fst, Pose{}, tip, 1.0, 1.0, &contacts), InputError);
}

// Long form: many more poses, and the 256^3 molar.
TEST(FastToothCollisionStress, RandomPosesEqualReference) {
  const long count = testing::stress_count(3000, 100000);
  const DiffStats s128 = random_poses(molar(128), fast::BrickTooth(molar(128)), count, kSeed + 4);
  EXPECT_EQ(s128.poses, count);
  if (testing::stress_full()) {
    const VoxelTooth ref(voxelize_procedural_molar(MolarParams{}, 256));
    const DiffStats s = random_poses(ref, fast::BrickTooth(ref), count / 4, kSeed + 5);
    EXPECT_EQ(s.poses, count / 4);
  }
}

}  // namespace
}  // namespace dentsim
