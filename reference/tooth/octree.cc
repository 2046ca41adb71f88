#include "reference/tooth/octree.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <string>

#include "reference/core/io.h"

namespace dentsim {
namespace {

// Spreads the low 10 bits of v so that bit b lands on bit 3 b.
std::size_t spread_bits(int v) {
  std::size_t r = 0;
  for (int b = 0; b < 10; ++b) {
    r |= static_cast<std::size_t>((v >> b) & 1) << (3 * b);
  }
  return r;
}

std::size_t morton(int x, int y, int z) {
  return spread_bits(x) | (spread_bits(y) << 1) | (spread_bits(z) << 2);
}

int log2_exact(int n) {
  int l = 0;
  while ((1 << l) < n) ++l;
  return l;
}

}  // namespace

std::size_t FullOctree::internal_node_count(int levels) {
  std::size_t count = 0;
  std::size_t per_level = 1;
  for (int l = 0; l < levels; ++l) {
    count += per_level;
    per_level *= 8;
  }
  return count;
}

std::size_t FullOctree::node_index(int level, int x, int y, int z) {
  return internal_node_count(level) + morton(x, y, z);
}

std::size_t FullOctree::memory_bytes_for(int n) {
  const std::size_t nn = static_cast<std::size_t>(n);
  return internal_node_count(log2_exact(n)) * sizeof(std::uint8_t) + nn * nn * nn;
}

std::size_t FullOctree::memory_bytes() const {
  return masks_.size() * sizeof(std::uint8_t) + grid_.voxels.size() * sizeof(std::uint8_t);
}

FullOctree::FullOctree(VoxelGrid grid) : grid_(std::move(grid)) {
  const int n = grid_.n;
  if (n < 1 || n > 1024 || (n & (n - 1)) != 0) {
    throw InputError("voxel grid: n = " + std::to_string(n) +
                     ", expected a power of two in [1, 1024]");
  }
  if (!(grid_.voxel_size > 0.0) || !std::isfinite(grid_.voxel_size)) {
    throw InputError("voxel grid: voxel_size = " + std::to_string(grid_.voxel_size) +
                     ", expected a finite value > 0 [m]");
  }
  if (!grid_.origin.allFinite()) throw InputError("voxel grid: origin is not finite");
  const std::size_t nn = static_cast<std::size_t>(n);
  if (grid_.voxels.size() != nn * nn * nn) {
    throw InputError("voxel grid: " + std::to_string(grid_.voxels.size()) +
                     " voxels, expected n^3 = " + std::to_string(nn * nn * nn));
  }
  for (std::size_t v = 0; v < grid_.voxels.size(); ++v) {
    if (grid_.voxels[v] >= kMaterialCount) {
      throw InputError("voxel grid: voxel " + std::to_string(v) + " has material id " +
                       std::to_string(grid_.voxels[v]) + ", expected 0.." +
                       std::to_string(kMaterialCount - 1));
    }
  }
  levels_ = log2_exact(n);
  masks_.assign(internal_node_count(levels_), 0);
  if (levels_ == 0) return;
  // Level L-1 from the leaves, then each level from the one below. A level's nodes lie in Morton
  // order (header comment), so node m of level l has its children at 8 m + c of level l + 1; level
  // L-1 reads its children's voxels from four rows of the grid (issue #30: the setup of a 512^3
  // tooth; the masks are those of the definition, occupied() of the eight children, bit for bit:
  // tests/tooth/octree_test.cc).
  const int top = levels_ - 1;
  const int nl = 1 << top;
  std::vector<std::size_t> spread(static_cast<std::size_t>(nl));
  for (int v = 0; v < nl; ++v) spread[static_cast<std::size_t>(v)] = spread_bits(v);
  const std::uint8_t* voxels = grid_.voxels.data();
  std::uint8_t* leaves_parent = masks_.data() + internal_node_count(top);
  for (int z = 0; z < nl; ++z) {
    for (int y = 0; y < nl; ++y) {
      // The rows (2y + cy, 2z + cz) holding children c = cx + 2 cy + 4 cz.
      const std::uint8_t* row[4];
      for (int r = 0; r < 4; ++r) row[r] = voxels + grid_.index(0, 2 * y + (r & 1), 2 * z + (r >> 1));
      const std::size_t yz = (spread[static_cast<std::size_t>(y)] << 1) |
                             (spread[static_cast<std::size_t>(z)] << 2);
      for (int x = 0; x < nl; ++x) {
        std::uint8_t mask = 0;
        for (int c = 0; c < 8; ++c) {
          if (row[c >> 1][2 * x + (c & 1)] != 0) mask |= static_cast<std::uint8_t>(1u << c);
        }
        leaves_parent[spread[static_cast<std::size_t>(x)] | yz] = mask;
      }
    }
  }
  for (int l = top - 1; l >= 0; --l) {
    std::uint8_t* level = masks_.data() + internal_node_count(l);
    const std::uint8_t* below = masks_.data() + internal_node_count(l + 1);
    const std::size_t count = std::size_t{1} << (3 * l);
    for (std::size_t m = 0; m < count; ++m) {
      std::uint8_t mask = 0;
      for (int c = 0; c < 8; ++c) {
        if (below[8 * m + static_cast<std::size_t>(c)] != 0) mask |= static_cast<std::uint8_t>(1u << c);
      }
      level[m] = mask;
    }
  }
}

bool FullOctree::occupied(int level, int x, int y, int z) const {
  if (level == levels_) return grid_.solid(x, y, z);
  return masks_[node_index(level, x, y, z)] != 0;
}

void FullOctree::query_sphere(const Vec3& c, double rho, std::vector<std::size_t>* out) const {
  if (grid_.n == 0 || !occupied(0, 0, 0, 0)) return;
  const int n = grid_.n;
  if (!sphere_intersects_cells(grid_, 0, 0, 0, n, n, n, c, rho)) return;
  if (levels_ == 0) {  // a single voxel: the root is the leaf
    out->push_back(0);
    return;
  }
  struct Node {
    int level, x, y, z;
  };
  // Depth-first: at most 7 pending siblings per level plus the node being expanded.
  std::array<Node, 8 * 11> stack;
  int top = 0;
  stack[top++] = {0, 0, 0, 0};
  while (top > 0) {
    const Node node = stack[--top];
    const std::uint8_t mask = masks_[node_index(node.level, node.x, node.y, node.z)];
    const int child_level = node.level + 1;
    const int s = 1 << (levels_ - child_level);  // child size in voxels
    for (int child = 0; child < 8; ++child) {
      if ((mask & (1u << child)) == 0) continue;
      const int cx = 2 * node.x + (child & 1);
      const int cy = 2 * node.y + ((child >> 1) & 1);
      const int cz = 2 * node.z + ((child >> 2) & 1);
      if (!sphere_intersects_cells(grid_, cx * s, cy * s, cz * s, (cx + 1) * s, (cy + 1) * s,
                                   (cz + 1) * s, c, rho)) {
        continue;
      }
      if (child_level == levels_) {
        out->push_back(grid_.index(cx, cy, cz));
      } else {
        stack[top++] = {child_level, cx, cy, cz};
      }
    }
  }
}

std::uint8_t FullOctree::remove_voxel(int i, int j, int k) {
  if (!grid_.inside(i, j, k)) {
    throw InputError("remove_voxel: (" + std::to_string(i) + ", " + std::to_string(j) + ", " +
                     std::to_string(k) + ") outside the " + std::to_string(grid_.n) + "^3 grid");
  }
  const std::uint8_t material = grid_.at(i, j, k);
  if (material == kEmpty) return kEmpty;
  grid_.set(i, j, k, kEmpty);
  // Clear the child bit in each ancestor while the child has become empty.
  int x = i, y = j, z = k;
  for (int l = levels_ - 1; l >= 0; --l) {
    const int bit = (x & 1) | ((y & 1) << 1) | ((z & 1) << 2);
    x >>= 1;
    y >>= 1;
    z >>= 1;
    std::uint8_t& mask = masks_[node_index(l, x, y, z)];
    mask = static_cast<std::uint8_t>(mask & ~(1u << bit));
    if (mask != 0) break;
  }
  return material;
}

namespace {

// spread_bits of the bytes 0..255 (morton() of a node's coordinates without the loop).
constexpr std::array<std::size_t, 256> kSpread8 = [] {
  std::array<std::size_t, 256> t{};
  for (std::size_t v = 0; v < 256; ++v) {
    for (int b = 0; b < 8; ++b) t[v] |= ((v >> b) & 1) << (3 * b);
  }
  return t;
}();

// Copies a run of n bytes (a row of 8 voxels, a mask: one move).
inline void copy_run(const std::uint8_t* from, std::size_t n, std::uint8_t* to) {
  if (n == 8) {
    std::memcpy(to, from, 8);
  } else if (n == 1) {
    *to = *from;
  } else {
    std::copy_n(from, n, to);
  }
}

// A node's state as save_node lays it out, visited in order: f(pointer into the grid's voxels or
// the masks, count) for each run (the voxels' rows, then the masks' levels).
template <class Byte, class F>
void for_node_runs(Byte* voxels, Byte* masks, int n, int levels, int level, int x, int y, int z,
                   F f) {
  const std::size_t e = std::size_t{1} << (levels - level);
  const std::size_t nn = static_cast<std::size_t>(n);
  const std::size_t sx = static_cast<std::size_t>(x), sy = static_cast<std::size_t>(y);
  Byte* plane = voxels + e * (sx + nn * (sy + nn * static_cast<std::size_t>(z)));
  if (e == 8) {  // a brick of 8^3 (the field model's replay): rows of a constant 8 bytes
    for (std::size_t k = 0; k < 8; ++k, plane += nn * nn) {
      for (std::size_t j = 0; j < 8; ++j) f(plane + j * nn, std::size_t{8});
    }
  } else {
    for (std::size_t k = 0; k < e; ++k, plane += nn * nn) {
      for (std::size_t j = 0; j < e; ++j) f(plane + j * nn, e);
    }
  }
  const std::size_t m = kSpread8[x & 255] | (kSpread8[(x >> 8) & 3] << 24) |
                        ((kSpread8[y & 255] | (kSpread8[(y >> 8) & 3] << 24)) << 1) |
                        ((kSpread8[z & 255] | (kSpread8[(z >> 8) & 3] << 24)) << 2);
  // Level l's first node: (8^l - 1) / 7 (internal_node_count).
  const auto first = [](int l) { return ((std::size_t{1} << (3 * l)) - 1) / 7; };
  for (int l = level; l < levels; ++l) {
    const int shift = 3 * (l - level);
    f(masks + first(l) + (m << shift), std::size_t{1} << shift);
  }
  for (int l = level - 1; l >= 0; --l) f(masks + first(l) + (m >> (3 * (level - l))), 1);
}

}  // namespace

std::size_t FullOctree::node_bytes(int level) const {
  const std::size_t e = std::size_t{1} << (levels_ - level);
  return e * e * e + internal_node_count(levels_ - level) + static_cast<std::size_t>(level);
}

void FullOctree::save_node(int level, int x, int y, int z, std::uint8_t* out) const {
  for_node_runs(grid_.voxels.data(), masks_.data(), grid_.n, levels_, level, x, y, z,
                [&](const std::uint8_t* at, std::size_t n) {
                  copy_run(at, n, out);
                  out += n;
                });
}

void FullOctree::load_node(int level, int x, int y, int z, const std::uint8_t* in) {
  for_node_runs(grid_.voxels.data(), masks_.data(), grid_.n, levels_, level, x, y, z,
                [&](std::uint8_t* at, std::size_t n) {
                  copy_run(in, n, at);
                  in += n;
                });
}

void FullOctree::load_node_rows(int level, int x, int y, int z, const std::uint8_t* in,
                                std::uint64_t rows) {
  if (levels_ - level != 3) {
    load_node(level, x, y, z, in);
    return;
  }
  // save_node's runs of an 8^3 node: its 64 voxel rows (run j + 8 k: row (j, k)), then the masks.
  int run = 0;
  for_node_runs(grid_.voxels.data(), masks_.data(), grid_.n, levels_, level, x, y, z,
                [&](std::uint8_t* at, std::size_t n) {
                  if (run >= 64 || ((rows >> run) & 1U) != 0) copy_run(in, n, at);
                  in += n;
                  ++run;
                });
}

}  // namespace dentsim
