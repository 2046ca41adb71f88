#include "fast/tooth/brick_tooth.h"

namespace dentsim::fast {
namespace {

constexpr int kStep[6][3] = {{-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};

}  // namespace

BrickTooth::BrickTooth(const VoxelTooth& tooth) : grid_(tooth.grid()), codes_(tooth.codes.dense()) {
  const int n = grid_.n;
  bricks_ = n >= kBrick ? n / kBrick : 1;
  while ((1 << brick_levels_) < bricks_) ++brick_levels_;
  std::size_t offset = 0;
  for (int l = 0; l <= brick_levels_; ++l) {
    level_offset_[l] = offset;
    offset += std::size_t{1} << (3 * l);
  }
  // Levels 0..B_L-1 hold bytes; level_offset_[B_L] is their total.
  brick_masks_.assign(level_offset_[brick_levels_], 0);
  const std::size_t nb = static_cast<std::size_t>(bricks_);
  surface_.assign(nb * nb * nb, 0);
  solid_lo_ = {n, n, n};
  solid_hi_ = {-1, -1, -1};
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const std::size_t v = grid_.index(i, j, k);
        if (grid_.voxels[v] == kEmpty) continue;
        const int idx[3] = {i, j, k};
        for (int a = 0; a < 3; ++a) {
          if (idx[a] < solid_lo_[a]) solid_lo_[a] = idx[a];
          if (idx[a] > solid_hi_[a]) solid_hi_[a] = idx[a];
        }
        if (codes_.code[v] != 0) {
          surface_[brick_index(i / kBrick, j / kBrick, k / kBrick)] |=
              std::uint64_t{1} << local_bit(i % kBrick, j % kBrick, k % kBrick);
        }
      }
    }
  }
  const double h = grid_.voxel_size;
  inv_h_ = 1.0 / h;
  for (int a = 0; a < 3; ++a) {
    box_min_[a] = grid_.origin[a] + h * (solid_lo_[a] - 1);
    box_max_[a] = grid_.origin[a] + h * (solid_hi_[a] + 2);
  }
  // Brick octree bottom up: level B_L-1 from the bricks, each level from the one below.
  for (int l = brick_levels_ - 1; l >= 0; --l) {
    const int nl = 1 << l;
    for (int z = 0; z < nl; ++z) {
      for (int y = 0; y < nl; ++y) {
        for (int x = 0; x < nl; ++x) {
          std::uint8_t mask = 0;
          for (int c = 0; c < 8; ++c) {
            const int cx = 2 * x + (c & 1), cy = 2 * y + ((c >> 1) & 1), cz = 2 * z + (c >> 2);
            const bool occupied = l + 1 == brick_levels_
                                      ? surface_[brick_index(cx, cy, cz)] != 0
                                      : brick_masks_[node_index(l + 1, cx, cy, cz)] != 0;
            if (occupied) mask |= static_cast<std::uint8_t>(1u << c);
          }
          brick_masks_[node_index(l, x, y, z)] = mask;
        }
      }
    }
  }
}

void BrickTooth::set_surface(int i, int j, int k, bool on) {
  int x = i / kBrick, y = j / kBrick, z = k / kBrick;
  std::uint64_t& mask = surface_[brick_index(x, y, z)];
  const bool was_empty = mask == 0;
  const std::uint64_t bit = std::uint64_t{1} << local_bit(i % kBrick, j % kBrick, k % kBrick);
  mask = on ? (mask | bit) : (mask & ~bit);
  if (was_empty == (mask == 0)) return;  // the brick's emptiness did not change
  // Propagate up the brick octree while a node's emptiness changes.
  for (int l = brick_levels_ - 1; l >= 0; --l) {
    const unsigned child = static_cast<unsigned>((x & 1) | ((y & 1) << 1) | ((z & 1) << 2));
    x >>= 1;
    y >>= 1;
    z >>= 1;
    std::uint8_t& node = brick_masks_[node_index(l, x, y, z)];
    const bool node_was_empty = node == 0;
    node = static_cast<std::uint8_t>(on ? (node | (1u << child)) : (node & ~(1u << child)));
    if (node_was_empty == (node == 0)) return;
  }
}

std::uint8_t BrickTooth::remove_voxel(int i, int j, int k) {
  if (!grid_.inside(i, j, k)) return kEmpty;
  const std::size_t v = grid_.index(i, j, k);
  const std::uint8_t material = grid_.voxels[v];
  if (material == kEmpty) return kEmpty;
  grid_.voxels[v] = kEmpty;
  if (codes_.code[v] != 0) set_surface(i, j, k, false);
  codes_.code[v] = 0;
  // Each solid face neighbour now exposes the face toward (i, j, k): face f of the removed voxel
  // is face f ^ 1 of the neighbour across it.
  for (int f = 0; f < 6; ++f) {
    const int a = i + kStep[f][0], b = j + kStep[f][1], c = k + kStep[f][2];
    if (!grid_.inside(a, b, c)) continue;
    const std::size_t u = grid_.index(a, b, c);
    if (grid_.voxels[u] == kEmpty) continue;
    if (codes_.code[u] == 0) set_surface(a, b, c, true);
    codes_.code[u] = static_cast<std::uint8_t>(codes_.code[u] | (1u << (f ^ 1)));
  }
  return material;
}

}  // namespace dentsim::fast
