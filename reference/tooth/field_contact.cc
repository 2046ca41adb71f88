// The "field" contact model (reference/tooth/field_contact.h). Beyond the thesis.
#include "reference/tooth/field_contact.h"

#include "reference/core/io.h"
#include "reference/tooth/mesh.h"
#include "reference/tooth/procedural_molar.h"
#include "reference/tooth/surface_proxy_core.h"

namespace dentsim {

SignedDistance FieldSolid::distance(const Vec3& x, double reach) const {
  if (field_.deep_inside(x)) return signed_distance(tooth_, x, reach);
  const FieldSample s = field_.sample(x);
  SignedDistance out;
  if (s.value >= reach) {
    out.phi = reach;
    out.found = false;
    return out;
  }
  out.phi = s.value;
  out.found = true;
  const double g = s.gradient.norm();
  out.nearest = g > 0.0 ? Vec3(x - (s.value / g) * s.gradient) : x;
  return out;
}

Vec3 FieldSolid::normal(const Vec3& x, const SignedDistance& sd) const {
  if (!field_.deep_inside(x)) {
    const Vec3 grad = field_.sample(x).gradient;
    const double g = grad.norm();
    if (g > 0.0) return grad / g;
  }
  // No gradient of the field here: the voxel distance's direction.
  const SignedDistance exact =
      field_.deep_inside(x) ? sd : signed_distance(tooth_, x, tooth_.grid().voxel_size * tooth_.grid().n);
  return distance_gradient(tooth_, x, exact);
}

const Vec3& SurfaceProxy::update(const FieldSolid& solid, const Vec3& c) {
  proxy_detail::update(constants(), solid, &valid_, &g_, c);
  return g_;
}

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
