#include "tooth_io/tooth_field.h"

#include <utility>

#include "reference/core/io.h"
#include "tooth_io/mesh.h"
#include "tooth_io/procedural_molar.h"

namespace dentsim {

SampledField build_tooth_field(const ToothSource& t, const VoxelGrid& grid, const Vec3& offset,
                               const FieldBand& band) {
  TriangleMesh surface;
  if (t.source == "procedural") {
    const MolarParams params;
    surface = triangulate_implicit(
        grid, [&](const Vec3& p) { return molar_solid(params, p - offset); });
  } else if (t.source == "mesh") {
    LoadedMesh loaded = load_mesh(t.path);
    const double k =
        t.mesh_scale > 0.0 ? t.mesh_scale : scale_for_size(loaded.mesh, 1e-3 * t.size_mm);
    scale_mesh(loaded.mesh, k);
    surface = std::move(loaded.mesh);
    for (Vec3& v : surface.vertices) v += offset;
  } else {
    throw InputError("tooth.contact_model \"field\": tooth source '" + t.source +
                     "' has no field yet (expected procedural or mesh; use \"sdf\" for a volume)");
  }
  return build_sampled_field(grid, surface, band);
}

}  // namespace dentsim
