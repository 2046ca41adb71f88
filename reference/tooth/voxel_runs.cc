#include "reference/tooth/voxel_runs.h"

#include <cstdint>

#include "reference/tooth/grid_pages.h"

namespace dentsim {

VoxelRuns::VoxelRuns(const VoxelGrid& grid)
    : n_(grid.n), origin_(grid.origin), voxel_size_(grid.voxel_size) {
  const std::vector<std::uint8_t>& v = grid.voxels;
  // Reading a released empty page may take it back (a system without a shared zero page, such as
  // this project's VMs): each run of empty voxels gives its whole pages back once read (the grid
  // reads the same; issue #30: the 512^3 tooth's after-run copy took ~70 MB back).
  const auto release_empty = [&](std::size_t x, std::size_t end) {
    if (v[x] == 0) release_zero_pages(v.data() + x, v.data() + end);
  };
  // Two passes: count the runs, then fill exactly that much (no slack kept in the result).
  std::size_t runs = 0;
  for (std::size_t x = 0; x < v.size();) {
    std::size_t end = x + 1;
    while (end < v.size() && v[end] == v[x] && end - x < kMaxRun) ++end;
    release_empty(x, end);
    ++runs;
    x = end;
  }
  material_.reserve(runs);
  length_.reserve(runs);
  for (std::size_t x = 0; x < v.size();) {
    std::size_t end = x + 1;
    while (end < v.size() && v[end] == v[x] && end - x < kMaxRun) ++end;
    release_empty(x, end);
    material_.push_back(v[x]);
    length_.push_back(static_cast<std::uint32_t>(end - x));
    x = end;
  }
}


VoxelGrid VoxelRuns::unpack() const {
  VoxelGrid g;
  g.n = n_;
  g.origin = origin_;
  g.voxel_size = voxel_size_;
  std::size_t total = 0;
  for (const std::uint32_t l : length_) total += l;
  g.voxels.reserve(total);
  // A run of empty voxels releases its whole pages as soon as it is written, so the grid never
  // holds more than a page or two of them at once.
  for (std::size_t r = 0; r < material_.size(); ++r) {
    const std::size_t from = g.voxels.size();
    g.voxels.insert(g.voxels.end(), length_[r], material_[r]);
    if (material_[r] == 0)
      release_zero_pages(g.voxels.data() + from, g.voxels.data() + g.voxels.size());
  }
  return g;
}

}  // namespace dentsim
