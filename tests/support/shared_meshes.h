// The real tooth meshes of ../shared/data, beside the checkout and never copied into it: their
// paths, and the molar mesh voxelised as the fast tooth's differential tests use it. A test that
// needs one skips when it is absent (GTEST_SKIP naming the file); the procedural molar's cases
// always run.
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include "reference/tooth/collision.h"
#include "tooth_io/mesh.h"
#include "tooth_io/voxelize.h"

namespace dentsim::test {

// The path of a file of ../shared/data (it may not exist).
inline std::string shared_data_path(const std::string& file) {
  return std::string(DENTSIM_SOURCE_DIR) + "/../shared/data/" + file;
}

// molar-cc0.stl scaled to a molar 11 mm tall and voxelised at n^3 (null when the file is absent).
inline std::unique_ptr<VoxelTooth> shared_molar_tooth(int n) {
  const std::string path = shared_data_path("molar-cc0.stl");
  if (!std::filesystem::exists(path)) return nullptr;
  LoadedMesh mesh = load_mesh(path);
  scale_mesh(mesh.mesh, scale_for_size(mesh.mesh, 11e-3));
  VoxelizeOptions options;
  options.resolution = n;
  return std::make_unique<VoxelTooth>(voxelize_mesh(mesh.mesh, options));
}

}  // namespace dentsim::test
