// Neighbour encoding of the voxel tooth (thesis §2.5.2 "Neighbor Encoding"; docs/design.md
// "Voxel tooth"): 6 bits per voxel, bit f set iff the voxel is solid and its neighbour across f is
// empty or outside the grid, i.e. face f is exposed. Surface voxels are those with a nonzero code.
// Contact is built from exposed faces only (reference/tooth/collision.h), so the face shared by
// two face-adjacent solid voxels, and the edge between their exposed faces, give no force.
//
// Face numbering f = 2 a + s: axis a in {0: x, 1: y, 2: z}, s = 0 for the minus side, 1 for the
// plus side; the outward normal of face f is (2 s - 1) e_a (world frame).
//
// After a voxel changes, only its own code and its six neighbours' codes can change:
// reencode_local recomputes exactly those (tested against a full re-encode).
#pragma once

#include <cstdint>
#include <vector>

#include "reference/core/types.h"
#include "reference/tooth/voxel_grid.h"

namespace dentsim {

enum Face : int {
  kFaceMinusX = 0,
  kFacePlusX = 1,
  kFaceMinusY = 2,
  kFacePlusY = 3,
  kFaceMinusZ = 4,
  kFacePlusZ = 5,
};

inline int face_axis(int f) { return f / 2; }
inline int face_sign(int f) { return (f % 2 == 0) ? -1 : 1; }
inline Vec3 face_normal(int f) {
  Vec3 n = Vec3::Zero();
  n[face_axis(f)] = face_sign(f);
  return n;
}

struct NeighborCodes {
  int n = 0;                       // grid resolution N
  std::vector<std::uint8_t> code;  // N^3 codes, flat index as VoxelGrid::index
};

// The 6-bit code of voxel (i, j, k) computed from the grid (0 for an empty voxel).
std::uint8_t exposed_faces(const VoxelGrid& grid, int i, int j, int k);

// Encodes every voxel.
NeighborCodes encode_neighbors(const VoxelGrid& grid);

// Re-encodes voxel (i, j, k) and its six face neighbours after (i, j, k) changed.
void reencode_local(const VoxelGrid& grid, int i, int j, int k, NeighborCodes* codes);

}  // namespace dentsim
