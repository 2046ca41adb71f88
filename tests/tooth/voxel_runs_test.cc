// The run-length grid (reference/tooth/voxel_runs.h): byte-exact round trip, the run count the
// brute force gives, and storage proportional to the tooth's crossings rather than to N^3.
#include "reference/tooth/voxel_runs.h"

#include <gtest/gtest.h>

#include <random>

#include "tooth_io/procedural_molar.h"

namespace dentsim {
namespace {

std::size_t brute_force_runs(const std::vector<std::uint8_t>& v) {
  std::size_t runs = v.empty() ? 0 : 1;
  for (std::size_t x = 1; x < v.size(); ++x) runs += v[x] != v[x - 1] ? 1 : 0;
  return runs;
}

TEST(VoxelRuns, RoundTripsRandomBlocksExactly) {
  VoxelGrid g(16, Vec3(1e-3, -2e-3, 3e-3), 0.05e-3);
  std::mt19937 rng(11);
  for (std::size_t x = 0; x < g.voxels.size();) {
    const std::size_t len = 1 + rng() % 40;
    const auto m = static_cast<std::uint8_t>(rng() % kMaterialCount);
    for (std::size_t e = 0; e < len && x < g.voxels.size(); ++e) g.voxels[x++] = m;
  }
  const VoxelRuns runs(g);
  EXPECT_EQ(runs.run_count(), brute_force_runs(g.voxels));
  EXPECT_EQ(runs.bytes(), 5 * runs.run_count());  // no slack kept
  const VoxelGrid back = runs.unpack();
  EXPECT_EQ(back.n, g.n);
  EXPECT_EQ(back.origin, g.origin);
  EXPECT_EQ(back.voxel_size, g.voxel_size);
  EXPECT_EQ(back.voxels, g.voxels);
  EXPECT_EQ(runs.voxel_volume(), g.voxel_volume());
}

TEST(VoxelRuns, EmptyGridsAndSingleRuns) {
  EXPECT_TRUE(VoxelRuns().empty());
  EXPECT_TRUE(VoxelRuns().unpack().voxels.empty());
  const VoxelGrid empty(8, Vec3::Zero(), 1e-4);
  const VoxelRuns one(empty);
  EXPECT_EQ(one.run_count(), 1u);
  EXPECT_EQ(one.unpack().voxels, empty.voxels);
}

// unpack() hands the grid's all-empty pages back to the system after writing them (Linux): the
// grid still reads byte for byte as packed, read, written again and copied; on a 128^3 molar
// (2 MiB, whole pages of empty rows) and a grid of long empty spans between single voxels
// at page-straddling offsets.
TEST(VoxelRuns, ReleasedEmptyPagesReadAsZerosAndStayWritable) {
  VoxelGrid sparse(96, Vec3(0.0, 1e-3, 2e-3), 1e-4);
  for (std::size_t x : {std::size_t{0}, std::size_t{4095}, std::size_t{4096}, std::size_t{12289},
                        std::size_t{300000}, sparse.voxels.size() - 1}) {
    sparse.voxels[x] = kDentin;
  }
  for (const VoxelGrid& g : {voxelize_procedural_molar(MolarParams{}, 128), sparse}) {
    const VoxelRuns runs(g);
    VoxelGrid back = runs.unpack();
    EXPECT_EQ(back.voxels, g.voxels);
    // Written after the release: the new values stay; a copy reads the same.
    VoxelGrid edited = g;
    for (std::size_t x = 0; x < g.voxels.size(); x += 4093) {
      back.voxels[x] = kEnamel;
      edited.voxels[x] = kEnamel;
    }
    EXPECT_EQ(back.voxels, edited.voxels);
    const VoxelGrid copy = back;
    EXPECT_EQ(copy.voxels, edited.voxels);
  }
}

TEST(VoxelRuns, MolarStorageFollowsItsCrossingsNotTheVolume) {
  // The procedural molar at 64^3, whole and drilled (a column of voxels removed through the
  // crown): exact round trips, and runs = 1 + the id changes along the flat index, far below N^3.
  VoxelGrid g = voxelize_procedural_molar(MolarParams{}, 64);
  for (int k = 0; k < g.n; ++k) g.set(g.n / 2, g.n / 2, k, kEmpty);
  const VoxelRuns runs(g);
  EXPECT_EQ(runs.unpack().voxels, g.voxels);
  const std::size_t changes = brute_force_runs(g.voxels) - 1;
  EXPECT_EQ(runs.run_count(), 1 + changes);
  // Each x row crosses the solid and its material layers a few times: a run per change, five
  // bytes a run. Dense would be N^3 bytes; bound it by an eighth (measured ~1/30).
  EXPECT_LT(runs.bytes(), g.voxels.size() / 8);
}

}  // namespace
}  // namespace dentsim
