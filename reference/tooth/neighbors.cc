#include "reference/tooth/neighbors.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace dentsim {
namespace {

constexpr int kStep[6][3] = {{-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};

}  // namespace

std::uint8_t exposed_faces(const VoxelGrid& grid, int i, int j, int k) {
  if (!grid.solid(i, j, k)) return 0;
  std::uint8_t code = 0;
  for (int f = 0; f < 6; ++f) {
    // VoxelGrid::solid is false outside the grid, so boundary faces are exposed.
    if (!grid.solid(i + kStep[f][0], j + kStep[f][1], k + kStep[f][2])) {
      code |= static_cast<std::uint8_t>(1u << f);
    }
  }
  return code;
}

NeighborCodes encode_neighbors(const VoxelGrid& grid) {
  NeighborCodes codes;
  codes.n = grid.n;
  codes.code.assign(grid.voxels.size(), 0);
  for (int k = 0; k < grid.n; ++k) {
    for (int j = 0; j < grid.n; ++j) {
      for (int i = 0; i < grid.n; ++i)
        codes.code[grid.index(i, j, k)] = exposed_faces(grid, i, j, k);
    }
  }
  return codes;
}

SparseNeighborCodes::SparseNeighborCodes(const VoxelGrid& grid) : n_(grid.n) {
  if (grid.n < 1 || (grid.n & (grid.n - 1)) != 0) {
    throw std::invalid_argument("SparseNeighborCodes: grid resolution " + std::to_string(grid.n) +
                                ", expected a power of two");
  }
  while ((1 << bits_) < grid.n) ++bits_;
  const std::size_t n = static_cast<std::size_t>(grid.n);
  mask_ = n - 1;
  nb_ = (n + kBrick - 1) / kBrick;
  index_.assign(nb_ * nb_ * nb_, kNoRoom);
  std::size_t solid_slots = 0;
  for (std::size_t k = 0; k < n; ++k) {
    for (std::size_t j = 0; j < n; ++j) {
      const std::uint8_t* row = grid.voxels.data() + n * (j + n * k);
      for (std::size_t i = 0; i < n; ++i) {
        if (row[i] == 0) continue;
        std::int32_t& id = index_[i / kBrick + nb_ * (j / kBrick + nb_ * (k / kBrick))];
        if (id == kNoRoom) {
          id = kNone;
          ++solid_slots;
        }
      }
    }
  }
  bricks_.reserve(solid_slots * kBrickVoxels);  // untouched until a brick is taken
  // exposed_faces of every solid voxel, in the same order (so the bricks are taken in the same
  // order), read from the rows around it (issue #30: the setup of a 512^3 tooth); a row beyond
  // the grid reads as empty, as VoxelGrid::solid does.
  const std::vector<std::uint8_t> empty_row(n, 0);
  const auto row_at = [&](std::size_t j, std::size_t k) {
    return j < n && k < n ? grid.voxels.data() + n * (j + n * k) : empty_row.data();
  };
  for (std::size_t k = 0; k < n; ++k) {
    for (std::size_t j = 0; j < n; ++j) {
      const std::uint8_t* row = row_at(j, k);
      // j - 1 and k - 1 wrap to SIZE_MAX at 0: beyond the grid.
      const std::uint8_t* around[4] = {row_at(j - 1, k), row_at(j + 1, k), row_at(j, k - 1),
                                       row_at(j, k + 1)};
      for (std::size_t i = 0; i < n; ++i) {
        if (row[i] == 0) continue;
        std::uint8_t c = 0;
        if (i == 0 || row[i - 1] == 0) c |= 1u << 0;
        if (i + 1 == n || row[i + 1] == 0) c |= 1u << 1;
        for (int f = 0; f < 4; ++f) {
          if (around[f][i] == 0) c |= static_cast<std::uint8_t>(1u << (f + 2));
        }
        if (c != 0) set(n * (j + n * k) + i, c);
      }
    }
  }
}

SparseNeighborCodes::SparseNeighborCodes(const SparseNeighborCodes& other)
    : n_(other.n_), bits_(other.bits_), mask_(other.mask_), nb_(other.nb_), index_(other.index_) {
  bricks_.reserve(other.bricks_.capacity());
  bricks_.assign(other.bricks_.begin(), other.bricks_.end());
}

SparseNeighborCodes& SparseNeighborCodes::operator=(const SparseNeighborCodes& other) {
  if (this != &other) *this = SparseNeighborCodes(other);
  return *this;
}

bool SparseNeighborCodes::set(std::size_t v, std::uint8_t c) {
  std::int32_t& id = index_[slot_of(v)];
  if (id < 0) {
    if (c == 0) return true;  // an absent brick reads 0 already
    if (id == kNoRoom || bricks_.size() + kBrickVoxels > bricks_.capacity()) return false;
    id = static_cast<std::int32_t>(bricks_.size() / kBrickVoxels);
    bricks_.resize(bricks_.size() + kBrickVoxels, 0);  // within the reserve: no allocation
  }
  bricks_[static_cast<std::size_t>(id) * kBrickVoxels + local_of(v)] = c;
  return true;
}

bool SparseNeighborCodes::replace_brick(std::size_t s, const std::uint8_t* codes) {
  std::int32_t& id = index_[s];
  if (id < 0) {
    if (codes == nullptr) return true;  // an absent brick reads 0 already
    if (id == kNoRoom || bricks_.size() + kBrickVoxels > bricks_.capacity()) return false;
    id = static_cast<std::int32_t>(bricks_.size() / kBrickVoxels);
    bricks_.resize(bricks_.size() + kBrickVoxels);  // within the reserve: no allocation
  }
  std::uint8_t* to = &bricks_[static_cast<std::size_t>(id) * kBrickVoxels];
  if (codes == nullptr) {
    std::fill_n(to, kBrickVoxels, std::uint8_t{0});
  } else {
    std::copy_n(codes, kBrickVoxels, to);
  }
  return true;
}

NeighborCodes SparseNeighborCodes::dense() const {
  NeighborCodes out;
  out.n = n_;
  const std::size_t count = static_cast<std::size_t>(n_) * n_ * n_;
  out.code.assign(count, 0);
  for (std::size_t v = 0; v < count; ++v) out.code[v] = code(v);
  return out;
}

bool reencode_local(const VoxelGrid& grid, int i, int j, int k, SparseNeighborCodes* codes) {
  bool stored = true;
  if (grid.inside(i, j, k)) stored = codes->set(grid.index(i, j, k), exposed_faces(grid, i, j, k));
  for (int f = 0; f < 6; ++f) {
    const int a = i + kStep[f][0], b = j + kStep[f][1], c = k + kStep[f][2];
    if (grid.inside(a, b, c)) {
      stored = codes->set(grid.index(a, b, c), exposed_faces(grid, a, b, c)) && stored;
    }
  }
  return stored;
}

void reencode_local(const VoxelGrid& grid, int i, int j, int k, NeighborCodes* codes) {
  if (grid.inside(i, j, k)) codes->code[grid.index(i, j, k)] = exposed_faces(grid, i, j, k);
  for (int f = 0; f < 6; ++f) {
    const int a = i + kStep[f][0], b = j + kStep[f][1], c = k + kStep[f][2];
    if (grid.inside(a, b, c)) codes->code[grid.index(a, b, c)] = exposed_faces(grid, a, b, c);
  }
}

}  // namespace dentsim
