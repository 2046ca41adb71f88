#include "tooth_io/tooth_source.h"

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
  if (t.source == "volume") {
    VolumeToothOptions opt;
    opt.resolution = t.resolution;
    opt.automatic_thresholds = t.automatic_thresholds;
    opt.thresholds = t.thresholds;
    return build_volume_tooth(load_volume(t.path), opt);
  }
  throw InputError("tooth source '" + t.source + "': expected procedural, mesh or volume");
}

}  // namespace dentsim
