// The fast signed distance (fast/tooth/sdf.h) against the reference's (reference/tooth/sdf.h,
// itself checked against brute force in tests/tooth/sdf_test.cc), on the procedural molar at 128^3
// and after drilling: phi, the nearest point and its voxel bitwise equal on every query (boxes
// exactly as near are decided by the same order-free rule, sdf_detail::sdf_nearer), on grid-aligned
// ties too; and the surface proxy driven by either along the same tool path stays on the same g,
// step by step.
#include "fast/tooth/sdf.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "reference/tooth/surface_proxy_core.h"

#include "sim/scene.h"
#include "sim/simulator.h"

namespace dentsim {
namespace {

struct Agreement {
  long queries = 0, found = 0, inside = 0, mismatches = 0;
};

// One query both ways: everything bitwise equal (phi, found, nearest, voxel).
void compare(const VoxelTooth& tooth, const Vec3& x, double reach, Agreement* a) {
  const SignedDistance r = signed_distance(tooth, x, reach);
  const SignedDistance f = fast::signed_distance(tooth, x, reach);
  ++a->queries;
  if (r.found) ++a->found;
  if (r.phi < 0.0) ++a->inside;
  if (r.phi != f.phi || r.found != f.found || r.nearest != f.nearest || r.voxel != f.voxel) {
    ++a->mismatches;
    ADD_FAILURE() << "phi " << r.phi << " vs " << f.phi << ", nearest " << r.nearest.transpose()
                  << " vs " << f.nearest.transpose() << " at " << x.transpose();
  }
}

std::unique_ptr<SceneRig> molar_rig() {
  SceneRigOptions o;
  o.pipeline = "reference";
  return build_scene_rig(load_scene("drill"), o);
}

TEST(FastSignedDistance, EqualsTheReferenceOnTheMolar) {
  auto rig = molar_rig();
  const VoxelTooth& tooth = *rig->tooth;
  const VoxelGrid& g = tooth.grid();
  const double side = g.voxel_size * g.n, h = g.voxel_size, rho = 0.5e-3;
  std::mt19937_64 rng(20261125);
  std::uniform_real_distribution<double> u(-0.1 * side, 1.1 * side);
  const double reaches[] = {1e-4, rho + 4 * h, 2 * rho, side};
  Agreement a;
  for (int trial = 0; trial < 4000; ++trial) {
    const Vec3 x = g.origin + Vec3(u(rng), u(rng), u(rng));
    compare(tooth, x, reaches[trial % 4], &a);
  }
  // Near the surface, where the proxy lives: points a little off the occlusal anchor's column.
  std::uniform_real_distribution<double> near(-2e-3, 2e-3);
  for (int trial = 0; trial < 4000; ++trial) {
    const Vec3 x = rig->anchor + Vec3(near(rng), near(rng), near(rng));
    compare(tooth, x, reaches[trial % 4], &a);
  }
  std::printf("%ld queries, %ld found, %ld inside, %ld mismatches\n", a.queries, a.found, a.inside,
              a.mismatches);
  EXPECT_EQ(a.mismatches, 0);
  EXPECT_GT(a.found, 3000);
  EXPECT_GT(a.inside, 500);
}

// Points exactly as near to several voxels: voxel centres' columns and the midpoints between them.
TEST(FastSignedDistance, TiesAreDecidedAlike) {
  auto rig = molar_rig();
  const VoxelTooth& tooth = *rig->tooth;
  const VoxelGrid& g = tooth.grid();
  const double h = g.voxel_size;
  Agreement a;
  for (int i = -20; i <= 20; ++i) {
    for (int k = -5; k <= 25; ++k) {
      // On voxel corners, edges and face centres above and around the anchor.
      const Vec3 corner = g.origin + h * Vec3(std::floor((rig->anchor.x() - g.origin.x()) / h) + i,
                                              std::floor((rig->anchor.y() - g.origin.y()) / h),
                                              std::floor((rig->anchor.z() - g.origin.z()) / h) + k);
      compare(tooth, corner, 2e-3, &a);
      compare(tooth, corner + Vec3(0.5 * h, 0, 0), 2e-3, &a);
      compare(tooth, corner + Vec3(0.5 * h, 0.5 * h, 0), 2e-3, &a);
    }
  }
  EXPECT_EQ(a.mismatches, 0);
  EXPECT_GT(a.found, 1000);
}

// RecallingVoxelSolid answers a point asked again from what it remembers: with every reach,
// shorter or longer than the remembered one's, found or not, its answer is the reference's.
TEST(FastSignedDistance, RememberedAnswersAreTheQuerysOwn) {
  auto rig = molar_rig();
  const VoxelTooth& tooth = *rig->tooth;
  const double h = tooth.grid().voxel_size;
  std::mt19937_64 rng(20261127);
  std::uniform_real_distribution<double> near(-2e-3, 2e-3);
  std::uniform_real_distribution<double> reach(0.2 * h, 12 * h);
  long asked = 0, mismatches = 0, found = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const fast::RecallingVoxelSolid solid(tooth);
    Vec3 points[3];
    for (Vec3& p : points) p = rig->anchor + Vec3(near(rng), near(rng), near(rng));
    for (int k = 0; k < 24; ++k) {  // the same few points, every reach in turn
      const Vec3& x = points[k % 3];
      const double r = reach(rng);
      const SignedDistance want = signed_distance(tooth, x, r);
      const SignedDistance got = solid.distance(x, r);
      ++asked;
      if (want.found) ++found;
      if (want.phi != got.phi || want.found != got.found || want.nearest != got.nearest ||
          want.voxel != got.voxel) {
        ++mismatches;
        ADD_FAILURE() << "phi " << want.phi << " vs " << got.phi << " at " << x.transpose()
                      << " reach " << r;
      }
    }
  }
  EXPECT_EQ(mismatches, 0);
  EXPECT_GT(found, asked / 4);
  EXPECT_LT(found, asked);
}

TEST(FastSignedDistance, SurfaceProxyFollowsTheSamePathAfterDrilling) {
  auto rig = molar_rig();
  VoxelTooth& tooth = *rig->tooth;
  const double rho = 0.4e-3, h = tooth.grid().voxel_size;
  // Drill a pit into the top of the crown under the anchor, so that the path meets the cut's walls
  // and floor too.
  const VoxelGrid& g = tooth.grid();
  const std::size_t n = static_cast<std::size_t>(g.n);
  const int ia = static_cast<int>((rig->anchor.x() - g.origin.x()) / h);
  const int ja = static_cast<int>((rig->anchor.y() - g.origin.y()) / h);
  int ka = g.n - 1;
  while (ka > 0 && !g.solid(ia, ja, ka)) --ka;
  const Vec3 top = g.center(ia, ja, ka);
  int removed = 0;
  for (int k = 0; k < tooth.grid().n; ++k) {
    for (int j = 0; j < tooth.grid().n; ++j) {
      for (int i = 0; i < tooth.grid().n; ++i) {
        const Vec3 c = tooth.grid().center(i, j, k);
        if ((c - top).norm() < 1.0e-3 && g.voxels[i + n * (j + n * k)] != 0) {
          tooth.octree.remove_voxel(i, j, k);
          ++removed;
        }
      }
    }
  }
  ASSERT_GT(removed, 100);
  SurfaceProxy ref(rho, h), fst(rho, h, &fast::signed_distance), rec(rho, h);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> step(0.0, 0.15e-3);
  Vec3 c = top + Vec3(0, 0, 2e-3);
  long steps = 0, in_contact = 0;
  for (int k = 0; k < 3000; ++k) {
    // A random walk pressed down into the tooth, with a jump now and then (a fast tool).
    c += Vec3(step(rng), step(rng), step(rng) - 0.05e-3);
    if (k % 500 == 499) c += Vec3(0, 0, -3e-3);
    if ((c - top).norm() > 4e-3) c = top + Vec3(0, 0, 1e-3);
    const Vec3 gr = ref.update(tooth, c);
    const Vec3 gf = fst.update(tooth, c);
    ASSERT_EQ(gr, gf) << "step " << k;
    // The fast pipeline's proxy update (fast::SdfContactProvider): the answers remembered.
    const Vec3 gm = rec.update_on(fast::RecallingVoxelSolid(tooth), c);
    ASSERT_EQ(gr, gm) << "step " << k;
    ++steps;
    if ((gr - c).norm() > 1e-9) ++in_contact;
  }
  std::printf("%ld steps, %ld with the proxy held outside\n", steps, in_contact);
  EXPECT_GT(in_contact, 1000);
}

}  // namespace
}  // namespace dentsim
