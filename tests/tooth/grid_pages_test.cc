// The voxel grid's empty pages (reference/tooth/grid_pages.h): release_empty_pages hands back
// exactly the whole pages that hold only empty voxels (Linux: counted with mincore), the grid
// reads byte for byte as before, and writing a voxel there afterwards keeps it.
#include "reference/tooth/grid_pages.h"

#include "reference/tooth/voxel_runs.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#include <unistd.h>
#endif

namespace dentsim {
namespace {

#if defined(__linux__)
// The whole pages of v's storage: how many, how many resident, how many hold a non-zero byte.
struct Pages {
  std::size_t total = 0, resident = 0, nonzero = 0;
};
Pages whole_pages(const std::vector<std::uint8_t>& v) {
  const auto page = static_cast<std::uintptr_t>(sysconf(_SC_PAGESIZE));
  const auto begin = reinterpret_cast<std::uintptr_t>(v.data());
  const std::uintptr_t lo = (begin + page - 1) / page * page;
  const std::uintptr_t hi = (begin + v.size()) / page * page;
  Pages out;
  if (hi <= lo) return out;
  out.total = (hi - lo) / page;
  std::vector<unsigned char> in_core(out.total);
  EXPECT_EQ(mincore(reinterpret_cast<void*>(lo), hi - lo, in_core.data()), 0);
  for (std::size_t p = 0; p < out.total; ++p) {
    out.resident += in_core[p] & 1;
    const std::uint8_t* first = v.data() + (lo - begin) + p * page;
    out.nonzero += std::any_of(first, first + page, [](std::uint8_t x) { return x != 0; }) ? 1 : 0;
  }
  return out;
}
#endif

// A 128^3 grid (2 MiB, every page written when made) with a solid slab and single voxels at page
// edges and at both ends.
TEST(GridPages, EmptyPagesAreReleasedAndTheGridReadsTheSame) {
  VoxelGrid g(128, Vec3(0.01, 0.0, -0.02), 1e-4);
  for (int k = 40; k < 60; ++k) {
    for (int j = 10; j < 100; ++j) {
      for (int i = 30; i < 90; ++i) g.set(i, j, k, (i + j + k) % 3 == 0 ? kEnamel : kDentin);
    }
  }
  for (std::size_t x : {std::size_t{0}, std::size_t{4095}, std::size_t{4096}, std::size_t{12289},
                        std::size_t{1} << 20, g.voxels.size() - 1}) {
    g.voxels[x] = kPulp;
  }
  const std::vector<std::uint8_t> before = g.voxels;
  const std::size_t released = release_empty_pages(g);
#if defined(__linux__)
  // Counted before anything reads the released pages (a read maps the system's zero page, which
  // mincore counts as resident although the process's RSS does not; or, on a system without a
  // shared zero page, such as this project's VMs, a page of the process's own).
  const Pages p = whole_pages(g.voxels);
  ASSERT_GT(p.total, 500u);
  EXPECT_GT(p.nonzero, 50u);
  EXPECT_LT(p.nonzero, p.total / 2);
  // Exactly the empty whole pages went back; those with a solid voxel stayed.
  EXPECT_EQ(released, (p.total - p.nonzero) * static_cast<std::size_t>(sysconf(_SC_PAGESIZE)));
  EXPECT_EQ(p.resident, p.nonzero);
#else
  EXPECT_EQ(released, 0u);
#endif
  EXPECT_EQ(g.voxels, before);
  // Written after: a released page is taken back and keeps what is written; a copy reads the same.
  std::vector<std::uint8_t> expected = before;
  for (std::size_t x = 7; x < expected.size(); x += 5003) {
    g.voxels[x] = kEnamel;
    expected[x] = kEnamel;
  }
  EXPECT_EQ(g.voxels, expected);
  const VoxelGrid copy = g;
  EXPECT_EQ(copy.voxels, expected);
  // An empty grid gives every whole page back; a small one has none to give or one.
  VoxelGrid empty(64, Vec3::Zero(), 1e-4);
  release_empty_pages(empty);
#if defined(__linux__)
  EXPECT_EQ(whole_pages(empty.voxels).resident, 0u);
#endif
  EXPECT_TRUE(std::all_of(empty.voxels.begin(), empty.voxels.end(),
                          [](std::uint8_t x) { return x == 0; }));
}

// A grid fully written (every page resident) with a slab and single voxels at page edges.
VoxelGrid written_grid() {
  VoxelGrid g(128, Vec3(0.01, 0.0, -0.02), 1e-4);
  for (int k = 70; k < 80; ++k) {
    for (int j = 5; j < 120; ++j) {
      for (int i = 0; i < 128; ++i) g.set(i, j, k, (i * 7 + j + k) % 4 == 0 ? kEnamel : kDentin);
    }
  }
  for (std::size_t x : {std::size_t{1}, std::size_t{8191}, std::size_t{8192}, std::size_t{40000},
                        g.voxels.size() - 2}) {
    g.voxels[x] = kPulp;
  }
  return g;
}

// A copy (constructed or assigned) reads byte for byte as its source, and it and its source hold
// only their pages with a solid voxel: each page of empty voxels went back once read and written
// (issue #30: on a system without a shared zero page, reading a released page takes it back).
TEST(GridPages, ACopyAndItsSourceKeepOnlyTheirNonEmptyPages) {
  VoxelGrid g = written_grid();
  const std::vector<std::uint8_t> expected = g.voxels;
#if defined(__linux__)
  const Pages source_before = whole_pages(g.voxels);
  ASSERT_EQ(source_before.resident, source_before.total);  // written whole when made
  ASSERT_LT(source_before.nonzero, source_before.total / 4);
#endif
  const VoxelGrid copy(g);
  VoxelGrid assigned(8, Vec3::Zero(), 1.0);
  assigned = g;
#if defined(__linux__)
  for (const VoxelGrid* v : std::array<const VoxelGrid*, 3>{&copy, &assigned, &g}) {
    SCOPED_TRACE(v == &copy ? "the copy" : v == &g ? "the source" : "the assigned copy");
    const Pages p = whole_pages(v->voxels);
    EXPECT_EQ(p.nonzero, source_before.nonzero);
    // The source's pages need not be aligned with the copy's: an empty one that shares a copy's
    // page with a solid voxel stays (at most two of the source's a copy's page).
    if (v == &g) {
      EXPECT_LE(p.resident, 2 * p.nonzero);
    } else {
      EXPECT_EQ(p.resident, p.nonzero);
    }
  }
#endif
  for (const VoxelGrid* v : std::array<const VoxelGrid*, 2>{&copy, &assigned}) {
    EXPECT_EQ(v->n, g.n);
    EXPECT_EQ(v->origin, g.origin);
    EXPECT_EQ(v->voxel_size, g.voxel_size);
    EXPECT_EQ(v->voxels, expected);
  }
  EXPECT_EQ(g.voxels, expected);
}

// VoxelRuns reads the whole grid: the grid's pages of empty voxels go back as they are read.
TEST(GridPages, RunsOfAGridGiveItsEmptyPagesBack) {
  const VoxelGrid g = written_grid();
  const std::vector<std::uint8_t> expected = g.voxels;
  const VoxelRuns runs(g);
#if defined(__linux__)
  const Pages p = whole_pages(g.voxels);
  EXPECT_LT(p.nonzero, p.total / 4);
  EXPECT_EQ(p.resident, p.nonzero);
#endif
  EXPECT_EQ(g.voxels, expected);
  EXPECT_EQ(runs.unpack().voxels, expected);
}

}  // namespace
}  // namespace dentsim
