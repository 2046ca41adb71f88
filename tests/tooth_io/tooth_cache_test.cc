// The process's cache of built teeth (tooth_io/tooth_source.h build_tooth_grid_cached): a copy is
// the grid build_tooth_grid makes, a rewritten mesh file is built again, a bad file is named every
// time, and the kept voxels stay within their bound.
#include "tooth_io/tooth_source.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

#include "reference/core/io.h"

namespace dentsim {
namespace {

using ::testing::HasSubstr;

void expect_same_grid(const VoxelGrid& a, const VoxelGrid& b) {
  EXPECT_EQ(a.n, b.n);
  EXPECT_EQ(a.origin, b.origin);
  EXPECT_EQ(a.voxel_size, b.voxel_size);
  EXPECT_TRUE(a.voxels == b.voxels);
}

long solid_count(const VoxelGrid& g) {
  long n = 0;
  for (std::uint8_t v : g.voxels) n += v != 0;
  return n;
}

TEST(ToothCache, ProceduralCopyIsTheBuiltGrid) {
  clear_tooth_cache();
  ToothSource t;
  t.resolution = 32;
  const ToothCacheStats s0 = tooth_cache_stats();
  const VoxelGrid first = build_tooth_grid_cached(t);
  const VoxelGrid second = build_tooth_grid_cached(t);
  const ToothCacheStats s1 = tooth_cache_stats();
  EXPECT_EQ(s1.misses - s0.misses, 1);
  EXPECT_EQ(s1.hits - s0.hits, 1);
  EXPECT_EQ(s1.entries, 1);
  EXPECT_EQ(s1.bytes, first.voxels.size());
  expect_same_grid(first, second);
  expect_same_grid(first, build_tooth_grid(t));
  EXPECT_GT(solid_count(first), 0);
  // Another resolution is another tooth.
  t.resolution = 64;
  const VoxelGrid other = build_tooth_grid_cached(t);
  EXPECT_EQ(other.n, 64);
  EXPECT_EQ(tooth_cache_stats().misses - s0.misses, 2);
  EXPECT_EQ(tooth_cache_stats().entries, 2);
  EXPECT_LE(tooth_cache_stats().bytes, kToothCacheBytes);
  clear_tooth_cache();
  EXPECT_EQ(tooth_cache_stats().entries, 0);
  EXPECT_EQ(tooth_cache_stats().bytes, 0u);
}

// A box [0,a]x[0,b]x[0,c] as an OBJ of 6 quads (outward).
std::string box_obj(double a, double b, double c) {
  std::string s;
  for (int k = 0; k < 2; ++k) {
    for (int j = 0; j < 2; ++j) {
      for (int i = 0; i < 2; ++i) {
        s += "v " + std::to_string(i * a) + " " + std::to_string(j * b) + " " +
             std::to_string(k * c) + "\n";
      }
    }
  }
  // Vertex (i, j, k) is 1 + i + 2 j + 4 k.
  s += "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";
  return s;
}

TEST(ToothCache, ARewrittenMeshIsBuiltAgain) {
  clear_tooth_cache();
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("dentsim_tooth_cache_" + std::to_string(::getpid()) + ".obj"))
                               .string();
  ToothSource t;
  t.source = "mesh";
  t.path = path;
  t.size_mm = 10.0;
  t.resolution = 32;
  std::ofstream(path) << box_obj(1.0, 1.0, 1.0);
  const VoxelGrid cube = build_tooth_grid_cached(t);
  const long hits = tooth_cache_stats().hits;
  expect_same_grid(cube, build_tooth_grid_cached(t));
  EXPECT_EQ(tooth_cache_stats().hits, hits + 1);
  const long misses = tooth_cache_stats().misses;
  // A flat slab in the same file (other size in bytes): a new build, not the cube's copy.
  std::ofstream(path) << box_obj(1.0, 1.0, 0.25);
  const VoxelGrid slab = build_tooth_grid_cached(t);
  EXPECT_EQ(tooth_cache_stats().misses, misses + 1);
  expect_same_grid(slab, build_tooth_grid(t));
  EXPECT_LT(solid_count(slab), solid_count(cube) / 2);
  // The extent is part of the description.
  t.size_mm = 5.0;
  const VoxelGrid small = build_tooth_grid_cached(t);
  EXPECT_EQ(tooth_cache_stats().misses, misses + 2);
  EXPECT_NE(small.voxel_size, slab.voxel_size);
  std::filesystem::remove(path);
  // A missing file is named on every call (nothing kept for it).
  for (int i = 0; i < 2; ++i) {
    try {
      build_tooth_grid_cached(t);
      ADD_FAILURE() << "expected InputError";
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr(path));
    }
  }
  clear_tooth_cache();
}

}  // namespace
}  // namespace dentsim
