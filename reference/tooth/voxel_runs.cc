#include "reference/tooth/voxel_runs.h"

#if defined(__linux__)
#include <sys/mman.h>
#include <unistd.h>
#endif

#include <cstdint>

namespace dentsim {

VoxelRuns::VoxelRuns(const VoxelGrid& grid)
    : n_(grid.n), origin_(grid.origin), voxel_size_(grid.voxel_size) {
  const std::vector<std::uint8_t>& v = grid.voxels;
  // Two passes: count the runs, then fill exactly that much (no slack kept in the result).
  std::size_t runs = 0;
  for (std::size_t x = 0; x < v.size();) {
    std::size_t end = x + 1;
    while (end < v.size() && v[end] == v[x] && end - x < kMaxRun) ++end;
    ++runs;
    x = end;
  }
  material_.reserve(runs);
  length_.reserve(runs);
  for (std::size_t x = 0; x < v.size();) {
    std::size_t end = x + 1;
    while (end < v.size() && v[end] == v[x] && end - x < kMaxRun) ++end;
    material_.push_back(v[x]);
    length_.push_back(static_cast<std::uint32_t>(end - x));
    x = end;
  }
}

namespace {

// Hands the whole memory pages inside [begin, end) back to the system (Linux): the caller wrote
// zeros there, which a private anonymous page reads as again once released (MADV_DONTNEED); a
// failed madvise leaves them as they are.
void release_zero_pages(const std::uint8_t* begin, const std::uint8_t* end) {
#if defined(__linux__)
  static const long page_size = sysconf(_SC_PAGESIZE);
  if (page_size <= 0) return;
  const auto page = static_cast<std::uintptr_t>(page_size);
  const std::uintptr_t lo = (reinterpret_cast<std::uintptr_t>(begin) + page - 1) / page * page;
  const std::uintptr_t hi = reinterpret_cast<std::uintptr_t>(end) / page * page;
  if (hi > lo) madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_DONTNEED);
#else
  (void)begin;
  (void)end;
#endif
}

}  // namespace

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
