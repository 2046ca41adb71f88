// One entry point from a tooth description (a scene's "tooth", docs/scenes.md) to the voxel tooth,
// so the simulator and tools build it the same way: the procedural molar, a surface mesh (STL,
// OBJ, PLY; voxelize.h) or a scan volume (DICOM series, NIfTI, NRRD; volume.h).
//
// Units: metres, the source's own frame (the procedural molar's, the mesh's after scaling, the
// scanner's); the caller places the grid.
#pragma once

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

}  // namespace dentsim
