// Neighbour encoding (reference/tooth/neighbors.h): exact codes on small shapes, the surface area
// they encode, and local re-encoding equal to a full re-encode after every removal.
#include "reference/tooth/neighbors.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <random>
#include <stdexcept>

#include "reference/tooth/octree.h"
#include "tooth_io/procedural_molar.h"

namespace dentsim {
namespace {

constexpr std::uint64_t kSeed = 4242;

int popcount6(std::uint8_t c) {
  int k = 0;
  for (int f = 0; f < 6; ++f) k += (c >> f) & 1;
  return k;
}

TEST(NeighborCodes, FaceNumberingAndNormals) {
  EXPECT_EQ(face_normal(kFaceMinusX), Vec3(-1, 0, 0));
  EXPECT_EQ(face_normal(kFacePlusX), Vec3(1, 0, 0));
  EXPECT_EQ(face_normal(kFaceMinusY), Vec3(0, -1, 0));
  EXPECT_EQ(face_normal(kFacePlusY), Vec3(0, 1, 0));
  EXPECT_EQ(face_normal(kFaceMinusZ), Vec3(0, 0, -1));
  EXPECT_EQ(face_normal(kFacePlusZ), Vec3(0, 0, 1));
}

TEST(NeighborCodes, SmallShapesExact) {
  VoxelGrid g(8, Vec3::Zero(), 1e-4);
  g.set(3, 3, 3, kEnamel);
  EXPECT_EQ(exposed_faces(g, 3, 3, 3), 0x3F);  // an isolated voxel: all six faces
  g.set(4, 3, 3, kDentin);                     // a 2x1x1 bar along x
  EXPECT_EQ(exposed_faces(g, 3, 3, 3), 0x3F & ~(1 << kFacePlusX));
  EXPECT_EQ(exposed_faces(g, 4, 3, 3), 0x3F & ~(1 << kFaceMinusX));
  EXPECT_EQ(exposed_faces(g, 2, 3, 3), 0);  // empty voxels carry no code
  // A voxel in the grid's corner: the faces on the grid boundary are exposed.
  g.set(0, 0, 0, kPulp);
  EXPECT_EQ(exposed_faces(g, 0, 0, 0), 0x3F);
}

TEST(NeighborCodes, BlockEncodesItsSurfaceArea) {
  // A 4x5x6 block inside a 16^3 grid: exposed faces = 2 (4*5 + 5*6 + 4*6) = 148, interior = 0.
  VoxelGrid g(16, Vec3::Zero(), 1e-4);
  for (int k = 2; k < 8; ++k) {
    for (int j = 3; j < 8; ++j) {
      for (int i = 5; i < 9; ++i) g.set(i, j, k, kDentin);
    }
  }
  const NeighborCodes codes = encode_neighbors(g);
  int faces = 0, surface_voxels = 0;
  for (const std::uint8_t c : codes.code) {
    faces += popcount6(c);
    surface_voxels += c != 0;
  }
  EXPECT_EQ(faces, 148);
  EXPECT_EQ(surface_voxels, 4 * 5 * 6 - 2 * 3 * 4);
  EXPECT_EQ(codes.code[g.index(6, 5, 4)], 0);  // interior
  EXPECT_EQ(codes.code[g.index(5, 3, 2)],
            (1 << kFaceMinusX) | (1 << kFaceMinusY) | (1 << kFaceMinusZ));  // a corner voxel
}

TEST(NeighborCodes, LocalReencodeEqualsFullReencodeAfterEveryRemoval) {
  std::printf("seed %llu\n", static_cast<unsigned long long>(kSeed));
  std::mt19937_64 rng(kSeed);
  VoxelGrid g(16, Vec3::Zero(), 1e-4);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (auto& v : g.voxels) v = u(rng) < 0.7 ? kDentin : kEmpty;
  FullOctree tree(g);
  NeighborCodes codes = encode_neighbors(tree.grid());
  std::uniform_int_distribution<int> cell(0, 15);
  int removals = 0;
  for (int step = 0; step < 3000; ++step) {
    const int i = cell(rng), j = cell(rng), k = cell(rng);
    if (tree.remove_voxel(i, j, k) == kEmpty) continue;
    ++removals;
    reencode_local(tree.grid(), i, j, k, &codes);
    ASSERT_EQ(codes.code, encode_neighbors(tree.grid()).code) << "after removal " << removals;
  }
  EXPECT_GT(removals, 1000);
}


// The sparse codes (issue #30) against the dense definition: the same code at every voxel after
// construction and after every removal re-encoded locally, bricks taken only from the storage
// reserved at construction (never more), and a brick only where a code is non-zero.
TEST(NeighborCodes, SparseCodesEqualTheDenseOnesAfterEveryRemoval) {
  std::printf("seed %llu\n", static_cast<unsigned long long>(kSeed));
  std::mt19937_64 rng(kSeed);
  for (const int n : {4, 16, 32}) {
    VoxelGrid g(n, Vec3::Zero(), 1e-4);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    // A solid ball with random holes: bricks far from it hold no solid voxel.
    for (int k = 0; k < n; ++k) {
      for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
          const double r2 = (i - 0.4 * n) * (i - 0.4 * n) + (j - 0.45 * n) * (j - 0.45 * n) +
                            (k - 0.5 * n) * (k - 0.5 * n);
          if (r2 < 0.1 * n * n && u(rng) < 0.9) g.set(i, j, k, kDentin);
        }
      }
    }
    FullOctree tree(g);
    SparseNeighborCodes sparse(tree.grid());
    ASSERT_EQ(sparse.dense().code, encode_neighbors(tree.grid()).code) << "n " << n;
    const std::size_t reserved = sparse.reserved_bricks();
    std::uniform_int_distribution<int> cell(0, n - 1);
    int removals = 0;
    for (int step = 0; step < 40 * n; ++step) {
      const int i = cell(rng), j = cell(rng), k = cell(rng);
      if (tree.remove_voxel(i, j, k) == kEmpty) continue;
      ++removals;
      ASSERT_TRUE(reencode_local(tree.grid(), i, j, k, &sparse));
      const NeighborCodes dense = encode_neighbors(tree.grid());
      for (std::size_t v = 0; v < dense.code.size(); ++v) {
        ASSERT_EQ(sparse.code(v), dense.code[v]) << "n " << n << " removal " << removals;
      }
    }
    EXPECT_GT(removals, n);
    EXPECT_EQ(sparse.reserved_bricks(), reserved);
    EXPECT_LE(sparse.brick_count(), reserved);
    // Each brick in use holds or held a non-zero code: at most the bricks that ever had a
    // surface voxel, here every brick with a solid voxel at most.
    std::size_t with_solid = 0;
    const int nb = (n + 7) / 8;
    for (int bz = 0; bz < nb; ++bz) {
      for (int by = 0; by < nb; ++by) {
        for (int bx = 0; bx < nb; ++bx) {
          bool any = false;
          for (int k = 8 * bz; k < std::min(n, 8 * bz + 8); ++k) {
            for (int j = 8 * by; j < std::min(n, 8 * by + 8); ++j) {
              for (int i = 8 * bx; i < std::min(n, 8 * bx + 8); ++i) any = any || g.solid(i, j, k);
            }
          }
          with_solid += any ? 1 : 0;
        }
      }
    }
    EXPECT_EQ(reserved, with_solid) << "n " << n;
  }
}

// The sparse codes at construction are exposed_faces of every voxel (encode_neighbors), on grids
// solid up to their faces and edges (the constructor reads the rows around a voxel and takes the
// layers beyond the grid as empty, issue #30), from one voxel to 32^3.
TEST(NeighborCodes, SparseCodesAtConstructionAreTheDenseOnesOnFullAndRandomGrids) {
  std::printf("seed %llu\n", static_cast<unsigned long long>(kSeed));
  std::mt19937_64 rng(kSeed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (const int n : {1, 2, 8, 32}) {
    for (const double fill : {0.0, 0.2, 0.7, 1.0}) {
      VoxelGrid g(n, Vec3::Zero(), 1e-4);
      for (auto& v : g.voxels) v = u(rng) < fill ? kDentin : kEmpty;
      const SparseNeighborCodes sparse(g);
      const NeighborCodes dense = encode_neighbors(g);
      ASSERT_EQ(sparse.dense().code, dense.code) << "n " << n << " fill " << fill;
      if (fill == 1.0) {  // a full cube: only its faces are exposed, each to the outside
        EXPECT_EQ(dense.code[g.index(0, 0, 0)], n == 1 ? 0x3f : 0x15) << "n " << n;
      }
    }
  }
}

// A slot without a solid voxel at construction has no room: a zero stores (reads 0), a non-zero
// code is refused; a grid whose N is not a power of two is refused.
TEST(NeighborCodes, SparseCodesRefuseWhatRemovalsCannotMake) {
  VoxelGrid g(16, Vec3::Zero(), 1e-4);
  g.set(2, 2, 2, kEnamel);
  SparseNeighborCodes sparse(g);
  EXPECT_EQ(sparse.code(g.index(2, 2, 2)), 0x3F);
  EXPECT_EQ(sparse.brick_count(), 1u);
  EXPECT_EQ(sparse.reserved_bricks(), 1u);
  EXPECT_TRUE(sparse.set(g.index(12, 12, 12), 0));
  EXPECT_FALSE(sparse.set(g.index(12, 12, 12), 1));
  EXPECT_EQ(sparse.code(g.index(12, 12, 12)), 0);
  EXPECT_THROW(SparseNeighborCodes(VoxelGrid(12, Vec3::Zero(), 1e-4)), std::invalid_argument);
}

// A copy keeps the reserve: drilling a copied tooth takes bricks as the original does.
TEST(NeighborCodes, SparseCodesCopyKeepsTheReserve) {
  VoxelGrid g(32, Vec3::Zero(), 1e-4);
  for (int k = 0; k < 32; ++k) {
    for (int j = 0; j < 32; ++j) {
      for (int i = 0; i < 32; ++i) g.set(i, j, k, kDentin);
    }
  }
  const SparseNeighborCodes original(g);
  // The cube's surface lies in 56 of its 64 bricks; the 8 inner ones are reserved, not taken.
  ASSERT_EQ(original.brick_count(), 56u);
  SparseNeighborCodes copy = original;
  SparseNeighborCodes assigned;
  assigned = original;
  EXPECT_EQ(copy.reserved_bricks(), 64u);
  EXPECT_EQ(assigned.reserved_bricks(), 64u);
  FullOctree tree(g);
  for (int i = 10; i < 22; ++i) {  // a cavity in the middle: surface in the inner bricks
    for (int j = 10; j < 22; ++j) {
      tree.remove_voxel(i, j, 16);
      ASSERT_TRUE(reencode_local(tree.grid(), i, j, 16, &copy));
      ASSERT_TRUE(reencode_local(tree.grid(), i, j, 16, &assigned));
    }
  }
  EXPECT_EQ(copy.brick_count(), 64u);
  EXPECT_EQ(copy.dense().code, encode_neighbors(tree.grid()).code);
  EXPECT_EQ(assigned.dense().code, encode_neighbors(tree.grid()).code);
}

// Memory: on the procedural molar only the bricks along the surface are taken, a small part of
// the grid's bytes (the dense codes: one byte a voxel).
TEST(NeighborCodes, SparseCodesHoldTheSurfaceNotTheGrid) {
  const VoxelGrid g = voxelize_procedural_molar(MolarParams{}, 128);
  const SparseNeighborCodes sparse(g);
  const NeighborCodes dense = encode_neighbors(g);
  ASSERT_EQ(sparse.dense().code, dense.code);
  std::size_t surface = 0;
  for (const std::uint8_t c : dense.code) surface += c != 0 ? 1 : 0;
  EXPECT_GT(surface, 10000u);
  // A taken brick holds at least one surface voxel.
  EXPECT_LE(sparse.brick_count(), surface);
  EXPECT_LT(sparse.memory_bytes(), dense.code.size() / 4);
  std::printf("128^3 molar: %zu surface voxels, %zu bricks in use of %zu reserved, %zu bytes "
              "(dense %zu)\n",
              surface, sparse.brick_count(), sparse.reserved_bricks(), sparse.memory_bytes(),
              dense.code.size());
}

}  // namespace
}  // namespace dentsim
