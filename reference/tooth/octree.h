// Full (pointerless) octree over the voxel tooth (thesis §2.5.2, ref [10]; docs/design.md
// "Voxel tooth").
//
// Levels: level 0 is the root (the whole N^3 grid), level L = log2(N) are the leaves (the voxels of
// the VoxelGrid, which the octree owns). A node at level l has integer position (x, y, z) in
// [0, 2^l)^3 and spans the voxels [x s, (x+1) s) x ... with s = 2^(L-l).
//
// Node index (never a pointer): the full-octree linear index
//   node_index(l, x, y, z) = (8^l - 1) / 7 + morton(x, y, z),
// morton interleaving the bits as ... z1 y1 x1 z0 y0 x0. The root is 0, the children of node g are
// 8 g + 1 + c with c = cx + 2 cy + 4 cz, the parent of node g > 0 is (g - 1) / 8.
//
// Occupancy per level: every internal node (levels 0..L-1) stores one byte, bit c set iff child c
// holds at least one solid voxel. Leaves are the grid's material bytes (0 = empty). Invariant
// (tested): the masks equal those rebuilt from the leaves after any sequence of removals.
//
// Memory: (8^L - 1) / 7 bytes of masks + N^3 bytes of grid (memory_bytes_for,
// docs/tooth_octree.md).
//
// Sphere query: all solid voxels whose closed box is at distance < rho from the centre c (world,
// metres), i.e. a sphere merely touching a voxel does not intersect it. The predicate is
// sphere_intersects_cells below, evaluated in world coordinates on box bounds origin + h * i; it is
// monotone in i, so a node's test never rejects a voxel inside it that the leaf test accepts and
// the octree result equals the brute force over the flat array exactly
// (validation/crosscheck_octree).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "reference/core/types.h"
#include "reference/tooth/voxel_grid.h"

namespace dentsim {

// True iff the closed axis-aligned box of cells [i0, i1) x [j0, j1) x [k0, k1) of `grid` is at
// Euclidean distance < rho from c. The one predicate shared by the octree and the brute force.
inline bool sphere_intersects_cells(const VoxelGrid& grid, int i0, int j0, int k0, int i1, int j1,
                                    int k1, const Vec3& c, double rho) {
  const int lo_idx[3] = {i0, j0, k0};
  const int hi_idx[3] = {i1, j1, k1};
  double dist2 = 0.0;
  for (int a = 0; a < 3; ++a) {
    const double lo = grid.origin[a] + grid.voxel_size * lo_idx[a];
    const double hi = grid.origin[a] + grid.voxel_size * hi_idx[a];
    double d = 0.0;
    if (c[a] < lo) {
      d = lo - c[a];
    } else if (c[a] > hi) {
      d = c[a] - hi;
    }
    dist2 += d * d;
  }
  return dist2 < rho * rho;
}

// Voxel (i, j, k) against the sphere (c, rho).
inline bool sphere_intersects_voxel(const VoxelGrid& grid, int i, int j, int k, const Vec3& c,
                                    double rho) {
  return sphere_intersects_cells(grid, i, j, k, i + 1, j + 1, k + 1, c, rho);
}

class FullOctree {
 public:
  FullOctree() = default;
  // Takes the grid (N a power of two, 1 <= N <= 1024, h > 0, N^3 voxels with ids < kMaterialCount);
  // throws InputError naming the field otherwise. Builds every level from the leaves.
  explicit FullOctree(VoxelGrid grid);

  const VoxelGrid& grid() const { return grid_; }
  int levels() const { return levels_; }  // L = log2(N)

  // Full-octree linear index of node (level, x, y, z), see the header comment.
  static std::size_t node_index(int level, int x, int y, int z);
  // Number of nodes of levels 0..L-1 ((8^L - 1) / 7).
  static std::size_t internal_node_count(int levels);
  // Bytes held for an N^3 grid: internal masks + leaf grid.
  static std::size_t memory_bytes_for(int n);
  std::size_t memory_bytes() const;

  // Whether node (level, x, y, z) holds a solid voxel (level L: the voxel itself).
  bool occupied(int level, int x, int y, int z) const;
  // Child-occupancy byte of internal node (level < L).
  std::uint8_t child_mask(int level, int x, int y, int z) const {
    return masks_[node_index(level, x, y, z)];
  }
  const std::vector<std::uint8_t>& masks() const { return masks_; }

  // Appends to `out` the flat indices (VoxelGrid::index) of the solid voxels intersecting the
  // sphere (c, rho) (see sphere_intersects_cells). Descends from the root into occupied children
  // whose boxes intersect the sphere; no allocation besides `out`'s growth (reserve it).
  void query_sphere(const Vec3& c, double rho, std::vector<std::size_t>* out) const;

  // Removes voxel (i, j, k): clears it and the occupancy bits on its path to the root as far as
  // they become empty. Returns the material it held (kEmpty if it was already empty: no change).
  std::uint8_t remove_voxel(int i, int j, int k);

  // A node's state as bytes (the field model's replay of the worker's removals on the servo's
  // tooth, fast/tooth/cut_set.h ToothBricks): the voxels of its box (edge e = 2^(L - level); x
  // fastest, then y, then z), the masks of its subtree (levels level..L-1, each level's e'^3 nodes
  // in Morton order, contiguous there), then its ancestors' masks (levels level-1 down to 0).
  // node_bytes(level) of them; level in [0, L].
  std::size_t node_bytes(int level) const;
  void save_node(int level, int x, int y, int z, std::uint8_t* out) const;
  // Node (level, x, y, z)'s box, subtree and ancestors take what save_node wrote from an octree of
  // the same size. Every mask is again that of the definition when, outside the node's box, the
  // two grids hold the same voxels. No allocation, no throw.
  void load_node(int level, int x, int y, int z, const std::uint8_t* in);
  // load_node of a node of 8^3 voxels (level L - 3; other levels: load_node) taking of its
  // voxels the rows (j, k) whose bit j + 8 k is set in `rows` only (servo51: the rows a removal
  // changed; the caller's claim is that the others hold save_node's bytes already), and every
  // mask. No allocation, no throw.
  void load_node_rows(int level, int x, int y, int z, const std::uint8_t* in,
                      std::uint64_t rows);

 private:
  VoxelGrid grid_;
  int levels_ = 0;
  std::vector<std::uint8_t> masks_;
};

}  // namespace dentsim
