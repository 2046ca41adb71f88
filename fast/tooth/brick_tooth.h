// The fast voxel tooth: the same grid and neighbour codes as the reference tooth
// (reference/tooth/collision.h VoxelTooth: FullOctree + NeighborCodes), plus a hierarchy over the
// SURFACE voxels only (code != 0), so that a query never visits an interior voxel (docs/design.md
// "Voxel tooth", "The reference and fast twins"; docs/tooth_octree.md "Fast tooth").
//
// Frames and units: as reference/tooth/voxel_grid.h (world frame, metres, flat index
// i + N (j + N k)).
//
// Layout:
// - bricks of 4^3 voxels, one 64-bit mask each, bit set iff the voxel is a surface voxel. Inside a
//   brick the bit of local voxel (x, y, z) in [0, 4)^3 is
//     bit = (x&1) | (y&1)<<1 | (z&1)<<2 | (x>>1)<<3 | (y>>1)<<4 | (z>>1)<<5,
//   so byte b = bit>>3 is the 2^3 block b = bx + 2 by + 4 bz (the reference octree's child number
//   at level L-1) and bit&7 the voxel's child number inside it (level L);
// - above the bricks a full octree of child-occupancy bytes over the B^3 bricks (B = max(1, N/4),
//   B_L = log2 B levels), level l stored as a flat (2^l)^3 array (x + 2^l (y + 2^l z)): bit c of
//   a node is set iff child c (c = cx + 2 cy + 4 cz) holds a surface voxel;
// - the bounding box of the solid voxels at construction (removal only shrinks the solid, so it
//   stays a bound): the free-space early out.
//
// Order: for_each_surface_voxel visits the surface voxels of a box in exactly the order in which
// FullOctree::query_sphere reports them (a depth-first walk that pops children 7..0 at every
// internal level and emits the leaves of a level-(L-1) node 0..7): descending child number at
// every level down to the 2^3 blocks, ascending inside a block. The contact sets of the fast and
// reference tooth therefore have the same members in the same order (tests/fast/tooth_*).
//
// Drilling: remove_voxel clears the voxel, sets the exposed-face bit toward it in each solid face
// neighbour (the only code bit that changes: the incremental twin of reencode_local) and keeps
// the surface masks and the brick octree consistent. No allocation, no throw.
#pragma once

#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "reference/tooth/collision.h"
#include "reference/tooth/neighbors.h"
#include "reference/tooth/voxel_grid.h"

namespace dentsim::fast {

class BrickTooth {
 public:
  static constexpr int kBrick = 4;           // brick edge [voxels]
  static constexpr int kMaxBrickLevels = 8;  // N <= 1024 -> B <= 256

  // Copies the grid and codes of a reference tooth (validated and encoded there; the codes one
  // byte a voxel, the layout fast::collide_tool_tip walks).
  explicit BrickTooth(const VoxelTooth& tooth);
  // Builds the reference tooth first (throws InputError as FullOctree does).
  explicit BrickTooth(VoxelGrid grid) : BrickTooth(VoxelTooth(std::move(grid))) {}

  const VoxelGrid& grid() const { return grid_; }
  const NeighborCodes& codes() const { return codes_; }
  int bricks_per_axis() const { return bricks_; }
  int brick_levels() const { return brick_levels_; }
  // Surface masks of the B^3 bricks (flat bx + B (by + B bz)) and the brick octree's bytes (level
  // 0 first): exposed so tests compare them with a rebuild.
  const std::vector<std::uint64_t>& surface_masks() const { return surface_; }
  const std::vector<std::uint8_t>& brick_masks() const { return brick_masks_; }
  // Inclusive voxel bounds of the solid at construction (lo > hi on every axis: no solid).
  const std::array<int, 3>& solid_lo() const { return solid_lo_; }
  const std::array<int, 3>& solid_hi() const { return solid_hi_; }
  // The same box in world coordinates, padded by one voxel [m] (empty solid: lo > hi), and 1 / h.
  const Vec3& solid_box_min() const { return box_min_; }
  const Vec3& solid_box_max() const { return box_max_; }
  double inv_voxel_size() const { return inv_h_; }
  // The queries' free-space early out (fast/tooth/collision.h; on by default). Off, a query far
  // from the solid still clips its box to the solid and finds it empty: the same (empty) set, a
  // few more flops (PipelineModel::skip_unneeded; tests/fast/skip_test.cc, bench/skip_bench.cc).
  bool free_space_early_out() const { return early_out_; }
  void set_free_space_early_out(bool on) { early_out_ = on; }

  // Removes voxel (i, j, k) (see the header comment). Returns the material it held; kEmpty (no
  // change) if it was empty or outside the grid.
  std::uint8_t remove_voxel(int i, int j, int k);

  // Calls visit(i, j, k, flat_index) for every surface voxel with lo[a] <= idx[a] <= hi[a]
  // (inclusive, within [0, N)), in the reference octree's order (header comment).
  template <class Visit>
  void for_each_surface_voxel(const int lo[3], const int hi[3], Visit&& visit) const;

 private:
  bool early_out_ = true;
  std::size_t brick_index(int bx, int by, int bz) const {
    return static_cast<std::size_t>(bx) +
           static_cast<std::size_t>(bricks_) *
               (static_cast<std::size_t>(by) +
                static_cast<std::size_t>(bricks_) * static_cast<std::size_t>(bz));
  }
  std::size_t node_index(int level, int x, int y, int z) const {
    const std::size_t s = std::size_t{1} << level;
    return level_offset_[level] + static_cast<std::size_t>(x) +
           s * (static_cast<std::size_t>(y) + s * static_cast<std::size_t>(z));
  }
  static int local_bit(int x, int y, int z) {
    return (x & 1) | ((y & 1) << 1) | ((z & 1) << 2) | ((x >> 1) << 3) | ((y >> 1) << 4) |
           ((z >> 1) << 5);
  }
  // Sets or clears the surface bit of voxel (i, j, k), updating the brick octree when the
  // brick's emptiness changes.
  void set_surface(int i, int j, int k, bool on);
  template <class Visit>
  void visit_brick(int bx, int by, int bz, const int lo[3], const int hi[3], Visit& visit) const;

  VoxelGrid grid_;
  NeighborCodes codes_;
  int bricks_ = 1;
  int brick_levels_ = 0;
  std::array<std::size_t, kMaxBrickLevels + 1> level_offset_{};
  std::vector<std::uint64_t> surface_;
  std::vector<std::uint8_t> brick_masks_;
  std::array<int, 3> solid_lo_{};
  std::array<int, 3> solid_hi_{};
  Vec3 box_min_ = Vec3::Zero();
  Vec3 box_max_ = Vec3::Zero();
  double inv_h_ = 0.0;
};

// Masks of the local voxels of a brick whose coordinate along `axis` lies in [lo, hi]
// (0 <= lo, hi <= 3; empty when lo > hi), table index 16 axis + 4 lo + hi.
inline constexpr std::array<std::uint64_t, 48> kBrickAxisRangeMasks = [] {
  std::array<std::uint64_t, 48> t{};
  for (int axis = 0; axis < 3; ++axis) {
    for (int lo = 0; lo < 4; ++lo) {
      for (int hi = 0; hi < 4; ++hi) {
        std::uint64_t m = 0;
        for (int bit = 0; bit < 64; ++bit) {
          const int coord = ((bit >> axis) & 1) | (((bit >> (3 + axis)) & 1) << 1);
          if (coord >= lo && coord <= hi) m |= std::uint64_t{1} << bit;
        }
        t[16 * axis + 4 * lo + hi] = m;
      }
    }
  }
  return t;
}();

template <class Visit>
void BrickTooth::visit_brick(int bx, int by, int bz, const int lo[3], const int hi[3],
                             Visit& visit) const {
  const int base[3] = {bx * kBrick, by * kBrick, bz * kBrick};
  std::uint64_t mask = surface_[brick_index(bx, by, bz)];
  for (int a = 0; a < 3 && mask != 0; ++a) {
    const int l = lo[a] > base[a] ? lo[a] - base[a] : 0;
    const int h = hi[a] - base[a] < kBrick - 1 ? hi[a] - base[a] : kBrick - 1;
    mask &= kBrickAxisRangeMasks[16 * a + 4 * l + h];
  }
  const std::size_t n = static_cast<std::size_t>(grid_.n);
  for (int block = 7; block >= 0 && mask != 0; --block) {
    unsigned bits = static_cast<unsigned>((mask >> (8 * block)) & 0xffu);
    while (bits != 0) {
      const int b = std::countr_zero(bits);
      bits &= bits - 1;
      const int i = base[0] + ((block & 1) << 1) + (b & 1);
      const int j = base[1] + (((block >> 1) & 1) << 1) + ((b >> 1) & 1);
      const int k = base[2] + (((block >> 2) & 1) << 1) + ((b >> 2) & 1);
      visit(i, j, k,
            static_cast<std::size_t>(i) +
                n * (static_cast<std::size_t>(j) + n * static_cast<std::size_t>(k)));
    }
  }
}

template <class Visit>
void BrickTooth::for_each_surface_voxel(const int lo[3], const int hi[3], Visit&& visit) const {
  int blo[3], bhi[3];
  for (int a = 0; a < 3; ++a) {
    blo[a] = lo[a] / kBrick;
    bhi[a] = hi[a] / kBrick;
  }
  if (brick_levels_ == 0) {  // one brick (N <= 4)
    visit_brick(0, 0, 0, lo, hi, visit);
    return;
  }
  struct Node {
    int level, x, y, z;
  };
  // Depth first: at most 7 pending siblings per level plus the node being expanded.
  std::array<Node, 8 * kMaxBrickLevels + 1> stack;
  int top = 0;
  stack[top++] = {0, 0, 0, 0};
  while (top > 0) {
    const Node node = stack[--top];
    const std::uint8_t mask = brick_masks_[node_index(node.level, node.x, node.y, node.z)];
    const int child_level = node.level + 1;
    if (child_level == brick_levels_) {
      // Children are bricks: visited now, 7..0 (the order in which the stack would pop them).
      for (int child = 7; child >= 0; --child) {
        if ((mask & (1u << child)) == 0) continue;
        const int cx = 2 * node.x + (child & 1);
        const int cy = 2 * node.y + ((child >> 1) & 1);
        const int cz = 2 * node.z + ((child >> 2) & 1);
        if (cx < blo[0] || cx > bhi[0] || cy < blo[1] || cy > bhi[1] || cz < blo[2] ||
            cz > bhi[2]) {
          continue;
        }
        visit_brick(cx, cy, cz, lo, hi, visit);
      }
      continue;
    }
    const int shift = brick_levels_ - child_level;  // child size 2^shift bricks
    for (int child = 0; child < 8; ++child) {
      if ((mask & (1u << child)) == 0) continue;
      const int cx = 2 * node.x + (child & 1);
      const int cy = 2 * node.y + ((child >> 1) & 1);
      const int cz = 2 * node.z + ((child >> 2) & 1);
      if ((cx << shift) > bhi[0] || ((cx + 1) << shift) <= blo[0] || (cy << shift) > bhi[1] ||
          ((cy + 1) << shift) <= blo[1] || (cz << shift) > bhi[2] ||
          ((cz + 1) << shift) <= blo[2]) {
        continue;
      }
      stack[top++] = {child_level, cx, cy, cz};
    }
  }
}

}  // namespace dentsim::fast
