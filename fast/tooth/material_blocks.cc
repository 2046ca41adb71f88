// The pyramid of the blocks' materials (fast/tooth/material_blocks.h).
#include "fast/tooth/material_blocks.h"

#include <algorithm>
#include <cstring>

#include "fast/tooth/nearest_voxel_walk.h"

namespace dentsim::fast {

namespace {

// The status of a block holding the voxels of status s and material v (kEmpty: none).
std::uint8_t merge(std::uint8_t s, std::uint8_t v) {
  if (v == kEmpty || s == v) return s;
  return s == kEmpty ? v : MaterialBlocks::kMixed;
}

}  // namespace

MaterialBlocks::MaterialBlocks(const VoxelGrid& grid) {
  const int n = grid.n;
  if (n <= 0) return;
  edge0_ = std::min(kEdge, n);
  for (int a = n / edge0_;; a /= 2) {
    offset_.push_back(status_.size());
    across_.push_back(a);
    status_.resize(status_.size() + static_cast<std::size_t>(a) * a * a, kEmpty);
    if (a == 1) break;
  }
  // Level 0: each row of the grid merged into its blocks, a run of edge0 voxels at a time (a run
  // of one material, the common case, in one step).
  const int a0 = across_[0];
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) {
      const std::uint8_t* row = &grid.voxels[grid.index(0, j, k)];
      std::uint8_t* blocks = &status_[static_cast<std::size_t>(a0) *
                                      (static_cast<std::size_t>(j / edge0_) +
                                       static_cast<std::size_t>(a0) * (k / edge0_))];
      for (int b = 0; b < a0; ++b) {
        const std::uint8_t* run = row + static_cast<std::size_t>(b) * edge0_;
        std::uint8_t s = blocks[b];
        if (s == kMixed) continue;
        if (std::all_of(run + 1, run + edge0_, [&](std::uint8_t v) { return v == run[0]; })) {
          s = merge(s, run[0]);
        } else {
          for (int t = 0; t < edge0_; ++t) s = merge(s, run[t]);
        }
        blocks[b] = s;
      }
    }
  }
  // Each level above from its children.
  for (int l = 1; l < levels(); ++l) {
    const int a = across(l);
    for (int z = 0; z < a; ++z) {
      for (int y = 0; y < a; ++y) {
        for (int x = 0; x < a; ++x) {
          std::uint8_t s = kEmpty;
          for (int c = 0; c < 8; ++c) {
            s = merge(s, status(l - 1, 2 * x + (c & 1), 2 * y + ((c >> 1) & 1), 2 * z + (c >> 2)));
          }
          const std::size_t au = static_cast<std::size_t>(a);
          status_[offset_[static_cast<std::size_t>(l)] + static_cast<std::size_t>(x) +
                  au * (static_cast<std::size_t>(y) + au * static_cast<std::size_t>(z))] = s;
        }
      }
    }
  }
}

bool MaterialBlocks::voxels_only(const VoxelGrid& grid, const Vec3& x, double d2, std::uint8_t m,
                                 int bx, int by, int bz) const {
  // Each voxel of the level-0 block: solid now, of another material and D <= d2 fails.
  ++mixed_read_;
  const int e = edge0_;
  for (int k = e * bz; k < e * (bz + 1); ++k) {
    for (int j = e * by; j < e * (by + 1); ++j) {
      const std::uint8_t* row = &grid.voxels[grid.index(0, j, k)];
      for (int i = e * bx; i < e * (bx + 1); ++i) {
        if (row[i] == kEmpty || row[i] == m) continue;
        if (!(voxel_walk::voxel_distance2(grid, i, j, k, x) > d2)) return false;
      }
    }
  }
  return true;
}

bool MaterialBlocks::only(const VoxelGrid& grid, const Vec3& x, double d2, std::uint8_t m) const {
  if (levels() == 0) return true;  // no voxel at all
  if (levels() > kMaxLevels) return false;
  // A block's bound is its box's D at x: box_distance2's terms at the planes origin + h i, summed
  // as a voxel's are, no more than any of its voxels' D (header comment). A block is passed if its
  // bound is > d2 (none of its voxels has D <= d2) or it is kEmpty or m; a kMixed one above level
  // 0 is passed if its children are; anything else fails.
  using voxel_walk::gap2;
  using voxel_walk::plane;
  const int top_level = levels() - 1;
  const int n = edge(top_level);
  ++blocks_read_;
  const double root = (gap2(x[0], plane(grid, 0, 0), plane(grid, 0, n)) +
                       gap2(x[1], plane(grid, 1, 0), plane(grid, 1, n))) +
                      gap2(x[2], plane(grid, 2, 0), plane(grid, 2, n));
  const std::uint8_t s0 = status(top_level, 0, 0, 0);
  if (root > d2 || s0 == kEmpty || s0 == m) return true;
  if (s0 != kMixed) return false;
  if (top_level == 0) return voxels_only(grid, x, d2, m, 0, 0, 0);
  // The kMixed blocks whose children are still to be read, depth first: at most 7 wait at each
  // level below the top, and the top.
  struct Block {
    int level, x, y, z;
  };
  Block stack[8 * kMaxLevels];
  int top = 0;
  stack[top++] = {top_level, 0, 0, 0};
  while (top > 0) {
    const Block b = stack[--top];
    const int level = b.level - 1, e = edge(level);
    const int at[3] = {2 * b.x, 2 * b.y, 2 * b.z};  // the first child's coordinates
    // Per axis the two children's terms (their planes e at[a], e (at[a] + 1), e (at[a] + 2):
    // each child's bound is the same double as from its own planes).
    double t[3][2];
    for (int a = 0; a < 3; ++a) {
      const double p0 = plane(grid, a, e * at[a]), p1 = plane(grid, a, e * (at[a] + 1));
      const double p2 = plane(grid, a, e * (at[a] + 2));
      t[a][0] = gap2(x[a], p0, p1);
      t[a][1] = gap2(x[a], p1, p2);
    }
    for (int c = 0; c < 8; ++c) {
      const int cx = c & 1, cy = (c >> 1) & 1, cz = c >> 2;
      ++blocks_read_;
      if ((t[0][cx] + t[1][cy]) + t[2][cz] > d2) continue;  // none of its voxels has D <= d2
      const std::uint8_t s = status(level, at[0] + cx, at[1] + cy, at[2] + cz);
      if (s == kEmpty || s == m) continue;
      if (s != kMixed) return false;
      if (level > 0) {
        stack[top++] = {level, at[0] + cx, at[1] + cy, at[2] + cz};
      } else if (!voxels_only(grid, x, d2, m, at[0] + cx, at[1] + cy, at[2] + cz)) {
        return false;
      }
    }
  }
  return true;
}

}  // namespace dentsim::fast
