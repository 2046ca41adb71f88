// Fast drilling (fast/tooth/drilling.h) against the reference (reference/tooth/drilling.h), tick
// by tick: each tick both pipelines query their own tooth at the same pose, the contact sets must
// be equal, both drill, and the removed voxel lists, the grids, the neighbour codes and the removed
// volume per material must stay bitwise equal (docs/tolerance_policy.md 1). The fast tooth's own
// structures (surface masks, brick octree) must equal a rebuild from its grid, so the incremental
// update is checked too. Trajectories: a bur plunging into the molar and wandering (>= 1000 ticks),
// and a slab drilled down to walls one voxel thick.
#include "fast/tooth/drilling.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <random>
#include <string>

#include "reference/tooth/drilling.h"
#include "tooth_io/procedural_molar.h"
#include "tests/fast/tooth_diff.h"
#include "tests/support/stress.h"

namespace dentsim {
namespace {

using testing::ContactSet;
using testing::fast_set;
using testing::reference_set;
using testing::same_set;

constexpr std::uint64_t kSeed = 1414;

DrillParams drill_params() { return testing::fast_cutting(); }

struct Twin {
  VoxelTooth ref;
  fast::BrickTooth fst;
  DrillState ref_state, fast_state;
  explicit Twin(VoxelGrid grid)
      : ref(std::move(grid)),
        fst(ref),
        ref_state(make_drill_state(ref)),
        fast_state(make_drill_state(fst.grid())) {}
};

// The fast tooth's structures equal those built from scratch from its current grid.
void expect_structures_rebuilt(const fast::BrickTooth& fst) {
  const fast::BrickTooth rebuilt(fst.grid());
  EXPECT_EQ(fst.codes().code, rebuilt.codes().code);
  EXPECT_EQ(fst.surface_masks(), rebuilt.surface_masks());
  EXPECT_EQ(fst.brick_masks(), rebuilt.brick_masks());
}

// One tick on both: query at `pose`, compare, drill, compare. Returns false at the first
// difference (with a failure added).
bool tick(Twin& t, const Pose& pose, const ToolTip& tip, double T, const std::string& what,
          long* removed_total) {
  const ContactSet a = reference_set(t.ref, pose, tip);
  const ContactSet b = fast_set(t.fst, pose, tip);
  if (!same_set(a, b, what)) return false;
  std::vector<std::size_t> ra, rb;
  const int na = drill_tick(a.contacts, a.voxels, tip, drill_params(), T, &t.ref, &t.ref_state, &ra);
  const int nb =
      fast::drill_tick(b.contacts, b.voxels, tip, drill_params(), T, &t.fst, &t.fast_state, &rb);
  if (na != nb || ra != rb) {
    ADD_FAILURE() << what << ": reference removed " << na << ", fast " << nb;
    return false;
  }
  if (t.ref_state.removed_voxels != t.fast_state.removed_voxels) {
    ADD_FAILURE() << what << ": removed voxel counts per material differ";
    return false;
  }
  *removed_total += na;
  return true;
}

// The bur of testing::DrillPath on both teeth for `ticks` ticks; grids and codes compared every
// `check_every` ticks (0: at the end only). Returns the voxels removed, -1 at a difference.
long drill_along_path(Twin& t, long ticks, double rho, std::uint64_t seed, int check_every) {
  ToolTip tip;
  tip.radius = rho;
  testing::DrillPath path(t.ref.grid(), rho, 2e-3, seed);
  long removed = 0;
  for (long k = 0; k < ticks; ++k) {
    const Pose& pose = path.next(t.ref.grid());
    if (!tick(t, pose, tip, 1e-3, "tick " + std::to_string(k), &removed)) return -1;
    if (check_every > 0 && k % check_every == 0) {
      if (t.ref.codes.dense().code != t.fst.codes().code ||
          t.ref.grid().voxels != t.fst.grid().voxels) {
        ADD_FAILURE() << "tick " << k << ": grids or codes differ";
        return -1;
      }
    }
  }
  EXPECT_EQ(t.ref.grid().voxels, t.fst.grid().voxels);
  EXPECT_EQ(t.ref.codes.dense().code, t.fst.codes().code);
  for (int m = kEnamel; m < kMaterialCount; ++m) {
    EXPECT_EQ(t.ref_state.removed_volume_m3(m), t.fast_state.removed_volume_m3(m));
  }
  expect_structures_rebuilt(t.fst);
  return removed;
}

TEST(FastToothDrilling, ThousandTicksOnTheMolarEqualReference) {
  Twin t(voxelize_procedural_molar(MolarParams{}, 64));
  const long removed = drill_along_path(t, 1200, 0.6e-3, kSeed, 50);
  std::printf("removed %ld voxels (enamel %lld, dentin %lld, pulp %lld)\n", removed,
              static_cast<long long>(t.ref_state.removed_voxels[kEnamel]),
              static_cast<long long>(t.ref_state.removed_voxels[kDentin]),
              static_cast<long long>(t.ref_state.removed_voxels[kPulp]));
  EXPECT_GT(removed, 200);  // signal: the bur really cut
}

// A slab carved (by removal, on both teeth) down to a wall one voxel thick and a one-voxel
// pillar; the bur then sweeps across them at decreasing heights, cutting them, compared tick by
// tick.
TEST(FastToothDrilling, OneVoxelWallAndPillarEqualReference) {
  VoxelGrid g(32, Vec3::Zero(), 0.1e-3);
  for (int k = 0; k < 24; ++k) {
    for (int j = 0; j < 32; ++j) {
      for (int i = 0; i < 32; ++i) g.set(i, j, k, k < 12 ? kDentin : kEnamel);
    }
  }
  Twin t(std::move(g));
  for (int k = 12; k < 24; ++k) {
    for (int j = 0; j < 32; ++j) {
      for (int i = 0; i < 32; ++i) {
        if (j == 15 || (i == 24 && j == 24)) continue;  // the wall and the pillar
        t.ref.octree.remove_voxel(i, j, k);
        reencode_local(t.ref.octree.grid(), i, j, k, &t.ref.codes);
        t.fst.remove_voxel(i, j, k);
      }
    }
  }
  ASSERT_EQ(t.ref.codes.dense().code, t.fst.codes().code);
  expect_structures_rebuilt(t.fst);
  int thin = 0;  // voxels with both y faces exposed
  for (const std::uint8_t code : t.fst.codes().code) {
    if ((code & (1u << kFaceMinusY)) && (code & (1u << kFacePlusY))) ++thin;
  }
  EXPECT_EQ(thin, 32 * 12 + 12);
  ToolTip tip;
  tip.radius = 0.25e-3;
  long removed = 0, k = 0;
  for (int level = 0; level < 8; ++level) {
    for (int s = 0; s <= 120; ++s) {
      const double y = 0.4e-3 + 2.4e-3 * (level % 2 == 0 ? s : 120 - s) / 120.0;
      Pose pose;
      pose.x = Vec3(1.55e-3 + 0.9e-3 * (level % 3), y, 2.4e-3 + tip.radius - 0.12e-3 * level);
      ASSERT_TRUE(tick(t, pose, tip, 1e-3, "wall tick " + std::to_string(k), &removed));
      ++k;
    }
  }
  EXPECT_EQ(t.ref.grid().voxels, t.fst.grid().voxels);
  expect_structures_rebuilt(t.fst);
  std::printf("%ld ticks, removed %ld voxels of the wall\n", k, removed);
  EXPECT_GT(removed, 20);
}

TEST(FastToothDrilling, InvalidTickChangesNothing) {
  Twin t(voxelize_procedural_molar(MolarParams{}, 64));
  std::vector<Contact> contacts(2);
  std::vector<std::size_t> voxels = {0, 1};
  ToolTip tip;
  EXPECT_EQ(fast::drill_tick(contacts, voxels, tip, drill_params(), 0.0, &t.fst, &t.fast_state), 0);
  voxels.pop_back();
  EXPECT_EQ(fast::drill_tick(contacts, voxels, tip, drill_params(), 1e-3, &t.fst, &t.fast_state),
            0);
  EXPECT_EQ(t.fast_state.work_j.size(), 0u);
  EXPECT_EQ(t.fast_state.work_j.total(), 0.0);
}

// Long form: longer runs, larger bur, finer grid, a compare of grids every tick.
TEST(FastToothDrillingStress, LongRunsEqualReference) {
  const long ticks = testing::stress_count(2000, 50000);
  for (const double rho : {0.3e-3, 1.0e-3}) {
    Twin t(voxelize_procedural_molar(MolarParams{}, testing::stress_full() ? 128 : 64));
    const long removed = drill_along_path(t, ticks, rho, kSeed + 1, testing::stress_full() ? 1 : 0);
    EXPECT_GT(removed, 100);
  }
}

}  // namespace
}  // namespace dentsim
