// The nearest-first walk over the exposed voxels (fast/tooth/nearest_voxel_walk.h) against brute
// force: over every exposed voxel of the grid (and the seed), the least (D, index) with D below the
// starting bound, D by the reference's sdf_detail::box_distance2 of the voxel's box. Random grids
// (sparse to dense), adversarial ones (a slab and a cube: many voxels at the same D; one voxel in
// the grid's corner; an empty grid) and points: random ones about and beyond the grid, points on
// grid planes and grid nodes (ties between voxels), voxel centres; unseeded, seeded with an
// exposed voxel and with a buried one. Asserts the voxel and its D bitwise, the watch's bound
// (no exposed voxel other than the answer within the span is nearer than the least bound the walk
// ruled voxels out by), and the refusal of a span wider than the walk's arrays.
#include "fast/tooth/nearest_voxel_walk.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>

namespace dentsim {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The reference's D of voxel (i, j, k) at x.
double reference_d2(const VoxelGrid& grid, int i, int j, int k, const Vec3& x) {
  const int lo[3] = {i, j, k}, hi[3] = {i + 1, j + 1, k + 1};
  return sdf_detail::box_distance2(grid, lo, hi, x, nullptr);
}

struct Answer {
  bool found = false;
  std::size_t voxel = 0;
  double d2 = kInf;
};

// The least (D, index) over the exposed voxels and the seed (if any) with D < bound.
Answer brute_force(const VoxelGrid& grid, const fast::SurfaceVoxels& surface, const Vec3& x,
                   double bound, const Answer& seed) {
  Answer best;
  best.d2 = bound;
  auto offer = [&](std::size_t v, double d2) {
    if (d2 < best.d2 || (best.found && d2 == best.d2 && v < best.voxel)) {
      best = {true, v, d2};
    }
  };
  if (seed.found) offer(seed.voxel, seed.d2);
  for (int k = 0; k < grid.n; ++k) {
    for (int j = 0; j < grid.n; ++j) {
      for (int i = 0; i < grid.n; ++i) {
        if (surface.exposed(i, j, k)) offer(grid.index(i, j, k), reference_d2(grid, i, j, k, x));
      }
    }
  }
  return best;
}

struct Watch {
  double other = kInf;
  long tested = 0;
  void ruled_out(double d2) { other = std::min(other, d2); }
  void tested_one() { ++tested; }
};

struct Tally {
  long queries = 0, found = 0, seeded = 0, tested = 0, exposed = 0;
};

// One query at x with the starting bound `bound` and `seed`: the walk against brute force.
void check(const VoxelTooth& tooth, const fast::SurfaceVoxels& surface, const Vec3& x,
           double bound, const Answer& seed, const char* what, Tally* tally) {
  const VoxelGrid& grid = tooth.grid();
  fast::VoxelWalk<Watch> walk;
  walk.d2 = bound;
  if (seed.found) {
    ASSERT_LT(seed.d2, bound);
    walk.sd.found = true;
    walk.sd.voxel = seed.voxel;
    walk.d2 = seed.d2;
  }
  const double r = walk.sd.found ? std::sqrt(walk.d2) : std::sqrt(bound);
  ASSERT_TRUE(fast::walk_nearest_voxel(surface, grid, x, r, &walk)) << what;
  const SignedDistance& sd = walk.sd;
  const double best2 = walk.d2;
  const Watch& watch = walk.watch;
  const Answer want = brute_force(grid, surface, x, bound, seed);
  ++tally->queries;
  tally->found += want.found;
  tally->seeded += seed.found;
  tally->tested += watch.tested;
  ASSERT_EQ(sd.found, want.found) << what << " x " << x.transpose();
  if (!want.found) return;
  ASSERT_EQ(sd.voxel, want.voxel) << what << " x " << x.transpose();
  ASSERT_EQ(best2, want.d2) << what;  // bitwise: the reference's double
  // The watch: every exposed voxel other than the answer with D < r^2 (within the span) has D no
  // less than the least bound the walk ruled voxels out by (the sdf model's balls rest on it).
  for (int k = 0; k < grid.n; ++k) {
    for (int j = 0; j < grid.n; ++j) {
      for (int i = 0; i < grid.n; ++i) {
        const std::size_t v = grid.index(i, j, k);
        if (!surface.exposed(i, j, k) || v == want.voxel) continue;
        ++tally->exposed;
        const double d2 = reference_d2(grid, i, j, k, x);
        if (d2 < r * r) {
          ASSERT_GE(d2, watch.other) << what << " voxel " << v;
        }
      }
    }
  }
}

// A point of the grid's coordinates u (in voxels; may be beyond the grid).
Vec3 at(const VoxelGrid& grid, double ux, double uy, double uz) {
  return grid.origin + grid.voxel_size * Vec3(ux, uy, uz);
}

// Queries on `tooth`: random points (some beyond the grid), points on grid planes and nodes, and
// voxel centres; each unseeded, seeded with an exposed voxel, and seeded with a solid one.
void exercise(const VoxelTooth& tooth, std::mt19937* rng, int points, const char* what,
              Tally* tally) {
  const VoxelGrid& grid = tooth.grid();
  const fast::SurfaceVoxels surface(tooth);
  const int n = grid.n;
  const double h = grid.voxel_size;
  std::uniform_real_distribution<double> coord(-3.0, n + 3.0);
  std::uniform_int_distribution<int> cell(0, n - 1);
  std::uniform_real_distribution<double> reach(0.5, 12.0);
  std::vector<std::size_t> solid, exposed;
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        if (!grid.solid(i, j, k)) continue;
        solid.push_back(grid.index(i, j, k));
        if (surface.exposed(i, j, k)) exposed.push_back(grid.index(i, j, k));
      }
    }
  }
  for (int p = 0; p < points; ++p) {
    Vec3 x;
    switch (p % 4) {
      case 0:  // anywhere about the grid
        x = at(grid, coord(*rng), coord(*rng), coord(*rng));
        break;
      case 1:  // on a grid plane on one axis
        x = at(grid, coord(*rng), coord(*rng), coord(*rng));
        x[p % 3] = grid.origin[p % 3] + h * cell(*rng);
        break;
      case 2:  // a grid node (up to eight voxels at the same D)
        x = at(grid, cell(*rng), cell(*rng), cell(*rng));
        break;
      default:  // a voxel's centre
        x = at(grid, cell(*rng) + 0.5, cell(*rng) + 0.5, cell(*rng) + 0.5);
        break;
    }
    const double R = reach(*rng) * h;
    const double bound = R * R;
    check(tooth, surface, x, bound, Answer{}, what, tally);
    for (const std::vector<std::size_t>* from : {&exposed, &solid}) {
      if (from->empty()) continue;
      const std::size_t v = (*from)[std::uniform_int_distribution<std::size_t>(
          0, from->size() - 1)(*rng)];
      const int i = static_cast<int>(v % n), j = static_cast<int>((v / n) % n);
      const int k = static_cast<int>(v / (static_cast<std::size_t>(n) * n));
      const double d2 = reference_d2(grid, i, j, k, x);
      if (!(d2 < bound)) continue;
      check(tooth, surface, x, bound, Answer{true, v, d2}, what, tally);
    }
  }
}

VoxelGrid empty_grid(int n) { return VoxelGrid(n, Vec3(-1e-3, 2e-3, -0.5e-3), 0.1e-3); }

TEST(NearestVoxelWalk, RandomGridsAgreeWithBruteForce) {
  std::mt19937 rng(48);
  Tally tally;
  for (const int n : {8, 16, 32}) {
    for (const double density : {0.002, 0.05, 0.3, 0.8}) {
      VoxelGrid grid = empty_grid(n);
      std::bernoulli_distribution solid(density);
      for (std::uint8_t& v : grid.voxels) v = solid(rng) ? 1 : 0;
      exercise(VoxelTooth(std::move(grid)), &rng, 60, "random", &tally);
    }
  }
  std::printf("%ld queries (%ld seeded), %ld found, %ld voxels tested (of %ld exposed)\n",
              tally.queries, tally.seeded, tally.found, tally.tested, tally.exposed);
  EXPECT_GT(tally.found, tally.queries / 4);  // signal: answers, not only "none"
  EXPECT_LT(tally.tested, tally.exposed / 4);  // signal: the walk prunes
}

TEST(NearestVoxelWalk, AdversarialGridsAgreeWithBruteForce) {
  std::mt19937 rng(4848);
  Tally tally;
  {  // A slab one voxel thick across the grid: every query above it ties along whole rows.
    VoxelGrid grid = empty_grid(32);
    for (int j = 0; j < 32; ++j) {
      for (int i = 0; i < 32; ++i) grid.set(i, j, 13, 2);
    }
    exercise(VoxelTooth(std::move(grid)), &rng, 200, "slab", &tally);
  }
  {  // A solid cube across brick boundaries (buried voxels; faces of equal D).
    VoxelGrid grid = empty_grid(32);
    for (int k = 6; k < 22; ++k) {
      for (int j = 5; j < 19; ++j) {
        for (int i = 7; i < 25; ++i) grid.set(i, j, k, 1);
      }
    }
    exercise(VoxelTooth(std::move(grid)), &rng, 200, "cube", &tally);
  }
  {  // One voxel in the grid's far corner (the last brick's edge).
    VoxelGrid grid = empty_grid(16);
    grid.set(15, 15, 15, 1);
    exercise(VoxelTooth(std::move(grid)), &rng, 200, "corner", &tally);
  }
  {  // Nothing solid: never found.
    exercise(VoxelTooth(empty_grid(16)), &rng, 40, "empty", &tally);
  }
  EXPECT_GT(tally.found, tally.queries / 4);
}

TEST(NearestVoxelWalk, RefusesASpanBeyondItsArrays) {
  VoxelGrid grid = empty_grid(256);  // 32 bricks per axis
  grid.set(100, 100, 100, 1);
  const VoxelTooth tooth(std::move(grid));
  const fast::SurfaceVoxels surface(tooth);
  const VoxelGrid& g = tooth.grid();
  const Vec3 x = at(g, 128.3, 128.3, 128.3);
  fast::VoxelWalk<fast::NoVoxelWatch> walk;
  // 2 r / 8 h + 3 bricks: 23 for r = 80 h fits, 27 for r = 96 h does not.
  walk.d2 = 1e9;
  EXPECT_TRUE(fast::walk_nearest_voxel(surface, g, x, 80.0 * g.voxel_size, &walk));
  EXPECT_TRUE(walk.sd.found);
  EXPECT_EQ(walk.sd.voxel, g.index(100, 100, 100));
  fast::VoxelWalk<fast::NoVoxelWatch> untouched;
  untouched.d2 = 1e9;
  EXPECT_FALSE(fast::walk_nearest_voxel(surface, g, x, 96.0 * g.voxel_size, &untouched));
  EXPECT_FALSE(untouched.sd.found);
  const double bound = untouched.d2;
  EXPECT_EQ(bound, 1e9);
}

}  // namespace
}  // namespace dentsim
