// Neighbour encoding (reference/tooth/neighbors.h): exact codes on small shapes, the surface area
// they encode, and local re-encoding equal to a full re-encode after every removal.
#include "reference/tooth/neighbors.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "reference/tooth/octree.h"

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

}  // namespace
}  // namespace dentsim
