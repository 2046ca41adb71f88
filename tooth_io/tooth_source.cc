#include "tooth_io/tooth_source.h"

#include <filesystem>
#include <list>
#include <mutex>
#include <optional>
#include <sstream>

#include "reference/core/io.h"
#include "tooth_io/mesh.h"
#include "tooth_io/procedural_molar.h"
#include "tooth_io/voxelize.h"

namespace dentsim {

VoxelGrid build_tooth_grid(const ToothSource& t) {
  if (t.source == "procedural") return voxelize_procedural_molar(MolarParams{}, t.resolution);
  if (t.source == "mesh") {
    LoadedMesh loaded = load_mesh(t.path);
    const double k =
        t.mesh_scale > 0.0 ? t.mesh_scale : scale_for_size(loaded.mesh, 1e-3 * t.size_mm);
    scale_mesh(loaded.mesh, k);
    VoxelizeOptions opt;
    opt.resolution = t.resolution;
    return voxelize_mesh(loaded.mesh, opt);
  }
  if (t.source == "volume") return build_volume_tooth(load_volume(t.path), volume_tooth_options(t));
  throw InputError("tooth source '" + t.source + "': expected procedural, mesh or volume");
}

VolumeToothOptions volume_tooth_options(const ToothSource& t) {
  VolumeToothOptions opt;
  opt.resolution = t.resolution;
  opt.automatic_thresholds = t.automatic_thresholds;
  opt.thresholds = t.thresholds;
  return opt;
}

namespace {

struct ToothCache {
  std::mutex mutex;
  std::list<std::pair<std::string, VoxelGrid>> grids;  // most recently used first
  std::size_t bytes = 0;
  long hits = 0, misses = 0;
};

ToothCache& tooth_cache() {
  static ToothCache cache;
  return cache;
}

// The description that decides the grid, or nothing when it must be built every time. Doubles
// are written in full (hexfloat), a mesh file by its path, byte size and modification time.
std::optional<std::string> cache_key(const ToothSource& t) {
  std::ostringstream k;
  k << std::hexfloat << t.source << '\n' << t.resolution << '\n';
  if (t.source == "procedural") return k.str();
  if (t.source != "mesh") return std::nullopt;
  std::error_code ec;
  const auto size = std::filesystem::file_size(t.path, ec);
  if (ec) return std::nullopt;  // build_tooth_grid names the file
  const auto time = std::filesystem::last_write_time(t.path, ec);
  if (ec) return std::nullopt;
  k << t.path << '\n'
    << size << '\n'
    << time.time_since_epoch().count() << '\n'
    << t.mesh_scale << '\n'
    << t.size_mm << '\n';
  return k.str();
}

}  // namespace

VoxelGrid build_tooth_grid_cached(const ToothSource& t) {
  const std::optional<std::string> key = cache_key(t);
  ToothCache& c = tooth_cache();
  if (key) {
    const std::lock_guard<std::mutex> lock(c.mutex);
    for (auto it = c.grids.begin(); it != c.grids.end(); ++it) {
      if (it->first != *key) continue;
      c.grids.splice(c.grids.begin(), c.grids, it);
      ++c.hits;
      return c.grids.front().second;
    }
  }
  VoxelGrid grid = build_tooth_grid(t);  // outside the lock: other teeth go on meanwhile
  const std::lock_guard<std::mutex> lock(c.mutex);
  ++c.misses;
  if (!key || grid.voxels.size() > kToothCacheBytes / 2) return grid;
  for (const auto& [k, g] : c.grids) {
    if (k == *key) return grid;  // another thread kept it meanwhile
  }
  c.grids.emplace_front(*key, grid);
  c.bytes += grid.voxels.size();
  while (c.bytes > kToothCacheBytes) {
    c.bytes -= c.grids.back().second.voxels.size();
    c.grids.pop_back();
  }
  return grid;
}

ToothCacheStats tooth_cache_stats() {
  ToothCache& c = tooth_cache();
  const std::lock_guard<std::mutex> lock(c.mutex);
  ToothCacheStats s;
  s.hits = c.hits;
  s.misses = c.misses;
  s.entries = static_cast<int>(c.grids.size());
  s.bytes = c.bytes;
  return s;
}

void clear_tooth_cache() {
  ToothCache& c = tooth_cache();
  const std::lock_guard<std::mutex> lock(c.mutex);
  c.grids.clear();
  c.bytes = 0;
}

}  // namespace dentsim
