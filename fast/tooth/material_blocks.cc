// The pyramid of the blocks' materials (fast/tooth/material_blocks.h).
#include "fast/tooth/material_blocks.h"

#include <algorithm>
#include <cmath>
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
                                 int bx, int by, int bz, Witness* witness) const {
  // Each voxel of the level-0 block: solid now, of another material and D <= d2 fails; with a
  // witness, the block is read to its end for the least such D (the first in (k, j, i) order, the
  // grid's, among equals), named only if < d2.
  ++mixed_read_;
  using voxel_walk::gap2;
  using voxel_walk::plane;
  const int e = edge0_;
  // The block's per-axis terms (servo51): voxel (i, j, k)'s D is (tx[i] + ty[j]) + tz[k], the
  // same double as voxel_distance2 (the same terms summed in its order). The terms are >= 0 and
  // rounded addition is monotone, so D >= fl(ty[j] + tz[k]) >= tz[k]: a plane or a row whose
  // bound is > d2 holds no voxel with D <= d2 and is skipped unread (the same answer and witness).
  const int b[3] = {bx, by, bz};
  double t[3][kEdge];
  for (int a = 0; a < 3; ++a) {
    for (int u = 0; u < e; ++u) {
      const int i = e * b[a] + u;
      t[a][u] = gap2(x[a], plane(grid, a, i), plane(grid, a, i + 1));
    }
  }
  bool pass = true;
  double least = d2;
  std::size_t at = 0;
  for (int k = 0; k < e; ++k) {
    const double tz = t[2][k];
    if (tz > d2) continue;
    for (int j = 0; j < e; ++j) {
      const double ty = t[1][j];
      if (ty + tz > d2) continue;
      const std::size_t first = grid.index(e * bx, e * by + j, e * bz + k);
      const std::uint8_t* row = &grid.voxels[first];
      for (int i = 0; i < e; ++i) {
        if (row[i] == kEmpty || row[i] == m) continue;
        const double dv = (t[0][i] + ty) + tz;
        if (dv > d2) continue;
        if (witness == nullptr) return false;
        if (pass || dv < least) {
          least = dv;
          at = first + static_cast<std::size_t>(i);
        }
        pass = false;
      }
    }
  }
  if (!pass && least < d2) *witness = {true, at, least};
  return pass;
}

bool MaterialBlocks::only(const VoxelGrid& grid, const Vec3& x, double d2, std::uint8_t m,
                          Witness* witness) const {
  if (witness != nullptr) witness->found = false;
  if (levels() == 0) return true;  // no voxel at all
  if (levels() > kMaxLevels) return false;
  // A block's bound is its box's D at x: box_distance2's terms at the planes origin + h i, summed
  // as a voxel's are, no more than any of its voxels' D (header comment). A block is passed if its
  // bound is > d2 (none of its voxels has D <= d2) or it is kEmpty or m; a kMixed one above level
  // 0 (or of another material below kPureDescent) is passed if its children are; one of level 0
  // if its voxels are (voxels_only); anything else fails.
  using voxel_walk::gap2;
  using voxel_walk::plane;
  // The start: the finest level whose blocks are at least the ball's radius r = sqrt(d2) across
  // (the top if none), and there the blocks of the ball's box [x - r, x + r], a block of margin
  // each side: every voxel with D <= d2 has each axis term <= d2 (the terms are >= 0 and rounded
  // addition is monotone), so lies within r of x on each axis up to rounding far below a block.
  // At most 6 blocks per axis (the box is at most 2 blocks wide, its ends rounded, and the
  // margins), whatever n.
  const int top_level = levels() - 1;
  const double r = std::sqrt(d2);
  int start = 0;
  while (start < top_level && edge(start) * grid.voxel_size < r) ++start;
  const int e0 = edge(start);
  int lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    const double side = e0 * grid.voxel_size;
    const double u0 = std::floor((x[a] - r - grid.origin[a]) / side) - 1.0;
    const double u1 = std::floor((x[a] + r - grid.origin[a]) / side) + 1.0;
    if (!(u1 >= 0.0 && u0 <= across(start) - 1.0)) return true;  // the ball misses the grid
    lo[a] = static_cast<int>(std::max(u0, 0.0));
    hi[a] = static_cast<int>(std::min(u1, across(start) - 1.0));
    if (hi[a] - lo[a] >= kStartSpan) return false;  // (not for a finite x and d2 < 4 rho^2)
  }
  // The blocks whose children are still to be read, depth first: at most kStartSpan^3 from the
  // start, and 7 more at each level below it.
  struct Block {
    int level, x, y, z;
  };
  Block stack[kStartSpan * kStartSpan * kStartSpan + 8 * kMaxLevels];
  int top = 0;
  // Block (level, bx, by, bz) of bound `bound`: passed (true) or failed; pushed if its children
  // decide.
  auto visit = [&](int level, int bx, int by, int bz, double bound) {
    ++blocks_read_;
    if (bound > d2) return true;  // none of its voxels has D <= d2
    const std::uint8_t s = status(level, bx, by, bz);
    if (s == kEmpty || s == m) return true;
    // Another material: read as a kMixed block where small (its voxels may be gone).
    if (s != kMixed && level >= kPureDescent) return false;
    if (level == 0) return voxels_only(grid, x, d2, m, bx, by, bz, witness);
    stack[top++] = {level, bx, by, bz};
    return true;
  };
  double t[3][kStartSpan];
  for (int a = 0; a < 3; ++a) {
    for (int b = lo[a]; b <= hi[a]; ++b) {
      t[a][b - lo[a]] = gap2(x[a], plane(grid, a, e0 * b), plane(grid, a, e0 * (b + 1)));
    }
  }
  for (int bz = lo[2]; bz <= hi[2]; ++bz) {
    for (int by = lo[1]; by <= hi[1]; ++by) {
      for (int bx = lo[0]; bx <= hi[0]; ++bx) {
        const double bound = (t[0][bx - lo[0]] + t[1][by - lo[1]]) + t[2][bz - lo[2]];
        if (!visit(start, bx, by, bz, bound)) return false;
      }
    }
  }
  while (top > 0) {
    const Block b = stack[--top];
    const int level = b.level - 1, e = edge(level);
    const int at[3] = {2 * b.x, 2 * b.y, 2 * b.z};  // the first child's coordinates
    // Per axis the two children's terms (their planes e at[a], e (at[a] + 1), e (at[a] + 2):
    // each child's bound is the same double as from its own planes).
    double u[3][2];
    for (int a = 0; a < 3; ++a) {
      const double p0 = plane(grid, a, e * at[a]), p1 = plane(grid, a, e * (at[a] + 1));
      const double p2 = plane(grid, a, e * (at[a] + 2));
      u[a][0] = gap2(x[a], p0, p1);
      u[a][1] = gap2(x[a], p1, p2);
    }
    for (int c = 0; c < 8; ++c) {
      const int cx = c & 1, cy = (c >> 1) & 1, cz = c >> 2;
      if (!visit(level, at[0] + cx, at[1] + cy, at[2] + cz, (u[0][cx] + u[1][cy]) + u[2][cz])) {
        return false;
      }
    }
  }
  return true;
}

}  // namespace dentsim::fast
