// Stress: the full octree's sphere queries against brute force over the flat voxel array
// (validation/crosscheck_octree.h), exact set equality, on random and adversarial spheres (touching
// faces, edges, corners exactly; centred on octree cell boundaries; integer radii on grid points;
// one-ulp nudges; large spheres), with voxels removed between queries. Short form (CI): 1e5
// spheres at N = 16 plus 1e4 at N = 32; DENTSIM_STRESS=full: 2e6 and 5e5.
#include <gtest/gtest.h>

#include <cstdio>

#include "reference/tooth/voxel_grid.h"
#include "tests/support/stress.h"
#include "validation/crosscheck_octree.h"

namespace dentsim {
namespace {

void run(int n, long spheres, std::uint64_t seed) {
  OctreeCrosscheckOptions options;
  options.n = n;
  options.spheres = spheres;
  options.seed = seed;
  const OctreeCrosscheckResult r = crosscheck_octree(options);
  std::printf(
      "n=%d seed=%llu queries=%ld mismatches=%ld nonempty=%ld voxels_matched=%ld removals=%ld\n"
      "  re-run: dentsim crosscheck octree --n %d --spheres %ld --seed %llu\n",
      n, static_cast<unsigned long long>(seed), r.queries, r.mismatches, r.nonempty_queries,
      r.voxels_matched, r.removals, n, spheres, static_cast<unsigned long long>(seed));
  EXPECT_EQ(r.queries, spheres);
  EXPECT_EQ(r.mismatches, 0) << r.first_mismatch;
  // Not trivially passing: most queries hit voxels, every placement kind is exercised, and the
  // octree was updated by removals along the way.
  EXPECT_GT(r.nonempty_queries, spheres / 3);
  for (int p = 0; p < static_cast<int>(SpherePlacement::kCount); ++p) {
    EXPECT_GT(r.by_placement[p], spheres / 10)
        << sphere_placement_name(static_cast<SpherePlacement>(p));
  }
  EXPECT_GT(r.removals, 100);
}

TEST(OctreeStress, QueriesEqualBruteForceN16) {
  run(16, testing::stress_count(100000, 2000000), 1);
}

TEST(OctreeStress, QueriesEqualBruteForceN32) { run(32, testing::stress_count(10000, 500000), 2); }

}  // namespace
}  // namespace dentsim
