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
//
// Storage: NeighborCodes holds one byte per voxel of the grid (the definition; the fast tooth's
// layout, fast/tooth/brick_tooth.h). SparseNeighborCodes, the reference tooth's (collision.h
// VoxelTooth), holds the same codes only in bricks of 8^3 voxels that hold a non-zero code (issue
// #30: the dense bytes are 128 MiB at 512^3, mostly zero). A code is non-zero only on a solid
// voxel, and removal never makes a voxel solid, so a brick is needed only where the grid held a
// solid voxel at construction: the brick storage is reserved for all of those then (virtual
// memory: only the bricks written become resident) and a brick is taken from it the first time
// one of its codes becomes non-zero. Nothing allocates or throws after construction.
#pragma once

#include <cstddef>
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

// The codes of NeighborCodes stored only in the 8^3 bricks that hold a non-zero one (header
// comment). code(v) equals NeighborCodes::code[v] for the same grid.
class SparseNeighborCodes {
 public:
  static constexpr int kBrick = 8;  // brick edge [voxels]

  SparseNeighborCodes() = default;
  // A copy keeps the reserve (a plain vector copy would not), so it can take bricks as well.
  SparseNeighborCodes(const SparseNeighborCodes& other);
  SparseNeighborCodes& operator=(const SparseNeighborCodes& other);
  SparseNeighborCodes(SparseNeighborCodes&&) = default;
  SparseNeighborCodes& operator=(SparseNeighborCodes&&) = default;
  // Encodes every voxel of `grid` (as encode_neighbors) and reserves a brick for every brick
  // slot holding a solid voxel. Throws std::invalid_argument unless N is a power of two.
  explicit SparseNeighborCodes(const VoxelGrid& grid);

  int n() const { return n_; }
  // The code of flat voxel index v (VoxelGrid::index), v < N^3.
  std::uint8_t code(std::size_t v) const {
    const std::int32_t id = index_[slot_of(v)];
    return id < 0 ? std::uint8_t{0}
                  : bricks_[static_cast<std::size_t>(id) * kBrickVoxels + local_of(v)];
  }
  std::uint8_t operator[](std::size_t v) const { return code(v); }
  // Stores code c for voxel v: takes a brick from the reserved storage if v's brick has none and
  // c != 0. Returns false, storing nothing, when that brick's slot had no solid voxel at
  // construction (no room reserved: a code there cannot arise from removals). No allocation.
  bool set(std::size_t v, std::uint8_t c);
  // Brick slots (i / 8 + nb (j / 8 + nb (k / 8)), nb = ceil(N / 8)), and slot s's 512 codes (local
  // index x + 8 (y + 8 z)), null when it holds no brick (all 0). The field model's replay of the
  // worker's removals copies them (fast/tooth/cut_set.h ToothBricks).
  std::size_t slot_count() const { return index_.size(); }
  const std::uint8_t* brick(std::size_t s) const {
    const std::int32_t id = index_[s];
    return id < 0 ? nullptr : &bricks_[static_cast<std::size_t>(id) * kBrickVoxels];
  }
  // Slot s's codes become `codes` (512 as brick() gives them; null: all 0), taking a brick from
  // the reserve if it has none. Returns false, storing nothing, when that brick cannot be taken
  // (as set()). No allocation.
  bool replace_brick(std::size_t s, const std::uint8_t* codes);
  // Every code as one byte per voxel (tests and the fast tooth's copy; allocates N^3 bytes).
  NeighborCodes dense() const;
  // Bricks in use, and reserved.
  std::size_t brick_count() const { return bricks_.size() / kBrickVoxels; }
  std::size_t reserved_bricks() const { return bricks_.capacity() / kBrickVoxels; }
  // Bytes resident at most: the index and the bricks in use.
  std::size_t memory_bytes() const {
    return index_.size() * sizeof(std::int32_t) + bricks_.size();
  }

 private:
  static constexpr std::size_t kBrickVoxels = kBrick * kBrick * kBrick;
  // N is a power of two (VoxelGrid): voxel coordinates by shifts and masks.
  std::size_t slot_of(std::size_t v) const {
    const std::size_t i = v & mask_, j = (v >> bits_) & mask_, k = v >> (2 * bits_);
    return (i >> 3) + nb_ * ((j >> 3) + nb_ * (k >> 3));
  }
  static std::size_t local_of_xyz(std::size_t i, std::size_t j, std::size_t k) {
    return (i & 7) + kBrick * ((j & 7) + kBrick * (k & 7));
  }
  std::size_t local_of(std::size_t v) const {
    return local_of_xyz(v & mask_, (v >> bits_) & mask_, v >> (2 * bits_));
  }

  int n_ = 0;
  int bits_ = 0;                      // log2 N
  std::size_t mask_ = 0;              // N - 1
  std::size_t nb_ = 0;                // brick slots per axis, ceil(N / 8)
  std::vector<std::int32_t> index_;  // per slot: brick id, kNone (no brick), kNoRoom (no solid)
  std::vector<std::uint8_t> bricks_;  // brick id * 512 + local index; capacity: the reserve
  static constexpr std::int32_t kNone = -1;
  static constexpr std::int32_t kNoRoom = -2;
};

// The 6-bit code of voxel (i, j, k) computed from the grid (0 for an empty voxel).
std::uint8_t exposed_faces(const VoxelGrid& grid, int i, int j, int k);

// Encodes every voxel.
NeighborCodes encode_neighbors(const VoxelGrid& grid);

// Re-encodes voxel (i, j, k) and its six face neighbours after (i, j, k) changed.
void reencode_local(const VoxelGrid& grid, int i, int j, int k, NeighborCodes* codes);
// The same on the sparse codes (no allocation). Returns false if a code could not be stored
// (SparseNeighborCodes::set; impossible while the grid only loses solid voxels).
bool reencode_local(const VoxelGrid& grid, int i, int j, int k, SparseNeighborCodes* codes);

}  // namespace dentsim
