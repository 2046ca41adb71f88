// Shared by the tooth benchmarks (bench/tooth_bench.cc, bench/tooth_vdb_bench.cc): the tip pose
// of BM_ToothCollision and teeth built once per resolution.
#pragma once

#include <map>
#include <memory>

#include "reference/tooth/voxel_grid.h"

namespace dentsim::bench {

// The pose of BM_ToothCollision (bench/reference_bench.cc): above the highest solid voxel of the
// grid's centre column, the tip of radius rho sunk 0.1 mm into the occlusal surface.
inline Pose occlusal_pose(const VoxelGrid& g, double rho) {
  const int c = g.n / 2;
  int top = 0;
  for (int k = 0; k < g.n; ++k) {
    if (g.solid(c, c, k)) top = k;
  }
  Pose pose;
  pose.x = g.center(c, c, top) + Vec3(0, 0, 0.5 * g.voxel_size + rho - 1e-4);
  return pose;
}

// One T(n) per resolution n for the whole process (a 512^3 molar takes ~10 s to build).
template <class T>
T& built_once(int n) {
  static std::map<int, std::unique_ptr<T>> cache;
  auto& slot = cache[n];
  if (!slot) slot = std::make_unique<T>(n);
  return *slot;
}

}  // namespace dentsim::bench
