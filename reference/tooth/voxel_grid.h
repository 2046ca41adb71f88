// The voxel tooth's grid (thesis §2.5): a cube of N^3 voxels (N a power of two so the full octree
// of reference/tooth/octree.h sits on it exactly), each holding a material id (0 = empty).
//
// Frames and units: the grid is axis-aligned in the world frame {O}; `origin` is the world
// position of the grid's minimum corner [m]; voxel (i, j, k) spans
// origin + h * [i, i+1] x [j, j+1] x [k, k+1] with h = voxel_size [m]. Flat index
// i + N * (j + N * k).
#pragma once

#include <cstdint>
#include <vector>

#include "reference/core/types.h"
#include "reference/tooth/materials.h"

namespace dentsim {

struct VoxelGrid {
  int n = 0;                          // resolution N per axis (power of two)
  Vec3 origin = Vec3::Zero();         // world position of the minimum corner [m]
  double voxel_size = 0.0;            // h [m]
  std::vector<std::uint8_t> voxels;   // N^3 material ids (Material), 0 = empty

  VoxelGrid() = default;
  VoxelGrid(int n_, const Vec3& origin_, double h) : n(n_), origin(origin_), voxel_size(h),
      voxels(static_cast<std::size_t>(n_) * n_ * n_, 0) {}
  // A copy holds the same voxels, but a whole memory page of the copy that holds only empty
  // voxels is handed back to the system as soon as it is written (reference/tooth/grid_pages.h;
  // it reads as zeros again): a copy of a 512^3 tooth (128 MiB, the field edit worker's) never
  // has all its pages resident at once (issue #30). Defined in grid_pages.cc.
  VoxelGrid(const VoxelGrid& other);
  VoxelGrid& operator=(const VoxelGrid& other);
  VoxelGrid(VoxelGrid&&) noexcept = default;
  VoxelGrid& operator=(VoxelGrid&&) noexcept = default;
  ~VoxelGrid() = default;

  std::size_t index(int i, int j, int k) const {
    return static_cast<std::size_t>(i) + static_cast<std::size_t>(n) *
           (static_cast<std::size_t>(j) + static_cast<std::size_t>(n) * static_cast<std::size_t>(k));
  }
  bool inside(int i, int j, int k) const {
    return i >= 0 && j >= 0 && k >= 0 && i < n && j < n && k < n;
  }
  std::uint8_t at(int i, int j, int k) const { return inside(i, j, k) ? voxels[index(i, j, k)] : 0; }
  bool solid(int i, int j, int k) const { return at(i, j, k) != 0; }
  void set(int i, int j, int k, std::uint8_t m) { voxels[index(i, j, k)] = m; }
  // World position of the centre of voxel (i, j, k).
  Vec3 center(int i, int j, int k) const {
    return origin + voxel_size * Vec3(i + 0.5, j + 0.5, k + 0.5);
  }
  double voxel_volume() const { return voxel_size * voxel_size * voxel_size; }
};

}  // namespace dentsim
