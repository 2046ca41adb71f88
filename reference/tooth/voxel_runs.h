// A voxel grid kept as runs of equal material ids along its flat index (issue #30: a run keeps the
// tooth before and after for its pictures; as plain grids that is 2 N^3 bytes, 268 MB at 512^3,
// while a tooth's rows cross its surface a few times each). Exact: unpack() gives back the grid
// byte for byte (tests/tooth/voxel_runs_test.cc).
//
// Layout: the grid's header (n, origin, voxel_size) and the runs in flat-index order
// (i + N (j + N k), voxel_grid.h), each a material id and a length >= 1 (a run longer than
// kMaxRun is split). Bytes: 5 per run, 1 + (the flat-index steps where the id changes) runs: a
// few per row that crosses the tooth (the procedural molar at 512^3: see bytes() in the test).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "reference/tooth/voxel_grid.h"

namespace dentsim {

class VoxelRuns {
 public:
  VoxelRuns() = default;
  // Packs `grid` (one pass over its voxels).
  explicit VoxelRuns(const VoxelGrid& grid);

  // The grid, byte for byte as packed. On Linux the memory pages of the grid that hold only
  // empty voxels are handed back to the system as they are written (madvise MADV_DONTNEED):
  // they read as zeros and take no memory until written again, so a 512^3 tooth's grid (128 MiB,
  // mostly empty rows) is resident only where the tooth is (issue #30: the pictures' peak).
  VoxelGrid unpack() const;

  int n() const { return n_; }
  const Vec3& origin() const { return origin_; }
  double voxel_size() const { return voxel_size_; }
  double voxel_volume() const { return voxel_size_ * voxel_size_ * voxel_size_; }
  bool empty() const { return n_ == 0; }
  std::size_t run_count() const { return material_.size(); }
  // Bytes of the runs' storage.
  std::size_t bytes() const {
    return material_.capacity() * sizeof(std::uint8_t) + length_.capacity() * sizeof(std::uint32_t);
  }

  static constexpr std::uint32_t kMaxRun = 0xffffffffu;

 private:
  int n_ = 0;
  Vec3 origin_ = Vec3::Zero();
  double voxel_size_ = 0.0;
  std::vector<std::uint8_t> material_;
  std::vector<std::uint32_t> length_;
};

}  // namespace dentsim
