// One entry point from a tooth description (a scene's "tooth", docs/scenes.md) to the voxel tooth,
// so the simulator and tools build it the same way: the procedural molar, a surface mesh (STL,
// OBJ, PLY; voxelize.h) or a scan volume (DICOM series, NIfTI, NRRD; volume.h).
//
// Units: metres, the source's own frame (the procedural molar's, the mesh's after scaling, the
// scanner's); the caller places the grid.
#pragma once

#include <cstddef>
#include <string>

#include "tooth_io/volume.h"
#include "reference/tooth/voxel_grid.h"

namespace dentsim {

struct ToothSource {
  std::string source = "procedural";  // "procedural", "mesh" or "volume"
  std::string path;                   // the mesh file or the volume (file or DICOM folder)
  double mesh_scale = 0.0;            // metres per mesh unit; 0 = use size_mm (mesh)
  double size_mm = 0.0;               // largest bounding-box extent [mm] (mesh)
  int resolution = 128;               // N (power of two)
  bool automatic_thresholds = true;   // volume: three-class Otsu, else `thresholds`
  MaterialThresholds thresholds;
};

// Throws InputError for an unknown source or bad input (naming the file).
VoxelGrid build_tooth_grid(const ToothSource& tooth);

// The options build_tooth_grid builds a volume tooth with (its resolution and thresholds).
VolumeToothOptions volume_tooth_options(const ToothSource& tooth);

// build_tooth_grid, remembered for the process. A run's setup builds its tooth, and the sweeps
// (zwidth, the stress suite, crosscheck, the closed-loop tests) run hundreds to thousands of runs
// on one tooth; the procedural molar at 128^3 is most of a short run's setup. A procedural molar,
// or a mesh file with the same path, byte size and modification time, scale, extent and
// resolution, built before is copied instead of built again: the copy is the grid
// build_tooth_grid returns (the build is deterministic; tests/tooth_io/tooth_cache_test.cc).
// Volumes are always built (a DICOM folder's files change without the folder's time changing).
// At most kToothCacheBytes of voxels are kept, the least recently used dropped first; a grid
// larger than half of that (finer than 256^3) is not kept, so a single run's memory grows by
// at most one 256^3 grid (16 MB) and a 512^3 tooth is never held twice. Thread-safe
// (concurrent first builds of one tooth each build it). Throws what build_tooth_grid throws.
inline constexpr std::size_t kToothCacheBytes = std::size_t{40} << 20;
VoxelGrid build_tooth_grid_cached(const ToothSource& tooth);

struct ToothCacheStats {
  long hits = 0;        // calls answered by a copy
  long misses = 0;      // calls that built (and kept, if it fits) their grid
  int entries = 0;      // grids kept now
  std::size_t bytes = 0;  // their voxels [bytes]
};
ToothCacheStats tooth_cache_stats();
// Forgets every kept grid (the counters stay).
void clear_tooth_cache();

}  // namespace dentsim
