// The sparse per-voxel drilling work (reference/tooth/voxel_work.h): the same values as a dense
// array on a scripted sequence with many probe collisions, the full-table status, and the drill
// tick's named status when a contact set does not fit.
#include "reference/tooth/voxel_work.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "reference/tooth/drilling.h"
#include "tooth_io/procedural_molar.h"

namespace dentsim {
namespace {

TEST(VoxelWorkTable, EqualsDenseStoreOnScriptedSequence) {
  // 64 keys in a table of 48 entries (128 slots): long probe runs, deletions inside them.
  constexpr std::size_t kKeys = 4096;
  std::vector<double> dense(kKeys, 0.0);
  VoxelWorkTable table;
  table.reserve(48);
  std::mt19937_64 rng(7);
  std::vector<std::size_t> keys;
  for (int i = 0; i < 64; ++i) keys.push_back(rng() % kKeys);
  std::size_t stored = 0;
  for (int step = 0; step < 20000; ++step) {
    const std::size_t v = keys[rng() % keys.size()];
    if (rng() % 4 == 0) {  // remove: the dense store zeroes the voxel
      if (dense[v] != 0.0) --stored;
      dense[v] = 0.0;
      table.erase(v);
    } else {
      const double w = 1e-6 * static_cast<double>(1 + rng() % 1000);
      const bool fits = dense[v] != 0.0 || stored < table.capacity();
      ASSERT_EQ(table.add(v, w), fits) << "step " << step;
      if (fits) {
        if (dense[v] == 0.0) ++stored;
        dense[v] += w;
      }
    }
    ASSERT_EQ(table.size(), stored) << "step " << step;
    for (const std::size_t k : keys) ASSERT_EQ(table.get(k), dense[k]) << "step " << step;
  }
  double sum = 0.0;
  for (const double w : dense) sum += w;
  double walked = 0.0;
  table.for_each([&](std::size_t v, double w) {
    EXPECT_EQ(w, dense[v]);
    walked += w;
  });
  EXPECT_DOUBLE_EQ(walked, sum);
}

TEST(VoxelWorkTable, FullTableRefusesNewVoxelsOnly) {
  VoxelWorkTable table;
  table.reserve(4);
  EXPECT_EQ(table.capacity(), 4u);
  for (std::size_t v = 0; v < 4; ++v) EXPECT_TRUE(table.add(100 * v, 1.0));
  EXPECT_FALSE(table.has_room(1));
  EXPECT_FALSE(table.add(7, 1.0));  // a new voxel: refused, nothing stored
  EXPECT_EQ(table.get(7), 0.0);
  EXPECT_TRUE(table.add(200, 0.5));  // an existing one still accumulates
  EXPECT_EQ(table.get(200), 1.5);
  table.erase(200);
  EXPECT_TRUE(table.add(7, 2.0));
  EXPECT_EQ(table.size(), 4u);
  EXPECT_EQ(table.total(), 5.0);
}

TEST(VoxelWorkTable, DrillTickReportsFullTableAndAddsNothing) {
  VoxelGrid g(8, Vec3::Zero(), 0.1e-3);
  for (int i = 0; i < 8; ++i) g.set(i, 4, 4, kEnamel);
  VoxelTooth tooth(std::move(g));
  DrillState state = make_drill_state(tooth.grid(), 2);  // room for two voxels
  Contact c;
  c.n = Vec3(0, 0, 1);
  c.depth = 1e-5;
  c.stiffness = 3000.0;
  c.weight = 1.0;
  c.material = kEnamel;
  const std::vector<Contact> contacts(3, c);
  const std::vector<std::size_t> voxels = {tooth.grid().index(1, 4, 4), tooth.grid().index(2, 4, 4),
                                           tooth.grid().index(3, 4, 4)};
  ToolTip tip;
  tip.radius = 0.5e-3;
  EXPECT_EQ(drill_tick(contacts, voxels, tip, DrillParams{}, 1e-3, &tooth, &state), 0);
  EXPECT_TRUE(state.work_table_full);
  EXPECT_EQ(state.work_j.size(), 0u);
  // Two fit.
  DrillState roomy = make_drill_state(tooth.grid(), 2);
  EXPECT_EQ(drill_tick(std::span(contacts).first(2), std::span(voxels).first(2), tip, DrillParams{},
                       1e-3, &tooth, &roomy),
            0);
  EXPECT_FALSE(roomy.work_table_full);
  EXPECT_EQ(roomy.work_j.size(), 2u);
}

TEST(VoxelWorkTable, SetupCapacityFollowsTheSurface) {
  VoxelGrid g(8, Vec3::Zero(), 0.1e-3);
  for (int k = 1; k < 7; ++k)
    for (int j = 1; j < 7; ++j)
      for (int i = 1; i < 7; ++i) g.set(i, j, k, kDentin);
  // A 6^3 cube: 6^3 - 4^3 = 152 voxels on its surface.
  EXPECT_EQ(count_surface_voxels(g), 152u);
  const DrillState state = make_drill_state(g);
  EXPECT_EQ(state.work_j.capacity(), drill_work_capacity(152));
  EXPECT_EQ(state.grid_voxels, g.voxels.size());
}

// The work's storage follows the tooth's surface, not its grid (issue #30): on the procedural
// molar at 64^3 and 128^3 the table's bytes are at most 12 bytes (a 32-bit key and a double) a
// slot in fewer than 4 (2 S_0 + 4096) slots (load <= 1/2, rounded up to a power of two), S_0 the
// surface voxels, which grow as N^2: at 128^3 that is under a quarter of a dense double per
// voxel (8 N^3 bytes, the store this table replaced).
TEST(VoxelWorkTable, StorageFollowsTheSurfaceNotTheGrid) {
  std::size_t surface[2] = {0, 0};
  for (int r = 0; r < 2; ++r) {
    const int n = r == 0 ? 64 : 128;
    const VoxelGrid g = voxelize_procedural_molar(MolarParams{}, n);
    surface[r] = count_surface_voxels(g);
    const DrillState state = make_drill_state(g);
    const std::size_t capacity = drill_work_capacity(surface[r]);
    EXPECT_EQ(state.work_j.capacity(), capacity);
    EXPECT_LE(state.work_j.bytes(), 12 * 4 * capacity) << "N = " << n;
    EXPECT_GE(state.work_j.bytes(), 12 * 2 * capacity) << "N = " << n;
    if (n == 128) {
      EXPECT_LT(4 * state.work_j.bytes(), 8 * g.voxels.size());
    }
  }
  // The surface about quadruples when N doubles (4.41 measured: 64^3 is coarse), the grid grows
  // eightfold.
  const double ratio = static_cast<double>(surface[1]) / static_cast<double>(surface[0]);
  EXPECT_GT(ratio, 3.5);
  EXPECT_LT(ratio, 5.0);
}

}  // namespace
}  // namespace dentsim
