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

bool MaterialBlocks::only(const VoxelGrid& grid, const Vec3& x, double d2, std::uint8_t m) const {
  if (levels() == 0) return true;  // no voxel at all
  if (levels() > kMaxLevels) return false;
  struct Block {
    int level, x, y, z;
  };
  // Depth first: at most 7 blocks wait at each level below the top, and the top.
  Block stack[8 * kMaxLevels];
  int top = 0;
  stack[top++] = {levels() - 1, 0, 0, 0};
  while (top > 0) {
    const Block b = stack[--top];
    const int e = edge(b.level);
    // The block's box's D at x (box_distance2's terms at the planes origin + h i, summed as a
    // voxel's are): no more than any of its voxels' D (header comment).
    const double bound = (voxel_walk::gap2(x[0], voxel_walk::plane(grid, 0, e * b.x),
                                           voxel_walk::plane(grid, 0, e * (b.x + 1))) +
                          voxel_walk::gap2(x[1], voxel_walk::plane(grid, 1, e * b.y),
                                           voxel_walk::plane(grid, 1, e * (b.y + 1)))) +
                         voxel_walk::gap2(x[2], voxel_walk::plane(grid, 2, e * b.z),
                                          voxel_walk::plane(grid, 2, e * (b.z + 1)));
    ++blocks_read_;
    if (bound > d2) continue;  // none of its voxels has D <= d2
    const std::uint8_t s = status(b.level, b.x, b.y, b.z);
    if (s == kEmpty || s == m) continue;
    if (s != kMixed || b.level == 0) return false;
    for (int c = 0; c < 8; ++c) {
      stack[top++] = {b.level - 1, 2 * b.x + (c & 1), 2 * b.y + ((c >> 1) & 1), 2 * b.z + (c >> 2)};
    }
  }
  return true;
}

}  // namespace dentsim::fast
