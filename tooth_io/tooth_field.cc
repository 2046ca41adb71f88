#include "tooth_io/tooth_field.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "reference/core/io.h"
#include "tooth_io/mesh.h"
#include "tooth_io/procedural_molar.h"

namespace dentsim {

TriangleMesh scan_surface(const ScanVolume& volume, const VoxelGrid& grid,
                          const VolumeSolidRule& rule, ScanSurfaceStats* stats) {
  const double h = grid.voxel_size;
  // The rule at p: the intensity as step 3 stores it (a float), step 4's flag of the voxel that
  // holds p; beyond the grid, background (the grid's outside).
  const auto solid = [&](const Vec3& p) {
    int ijk[3];
    for (int a = 0; a < 3; ++a) {
      const double u = std::floor((p[a] - grid.origin[a]) / h);
      if (!(u >= 0.0 && u < grid.n)) return false;
      ijk[a] = static_cast<int>(u);
    }
    const float value = static_cast<float>(sample_trilinear(volume, p, rule.background));
    return rule.classify(value, rule.edge[grid.index(ijk[0], ijk[1], ijk[2])] != 0) != kEmpty;
  };
  ScanSurfaceStats s;
  TriangleMesh mesh = triangulate_voxel_signs(grid, [&](const Vec3& in, const Vec3& out) {
    ++s.edges;
    if (!solid(in) || solid(out)) {
      ++s.midpoint;
      return Vec3(0.5 * (in + out));
    }
    Vec3 p_in = in, p_out = out;
    for (int it = 0; it < 40; ++it) {
      const Vec3 mid = 0.5 * (p_in + p_out);
      (solid(mid) ? p_in : p_out) = mid;
    }
    return Vec3(0.5 * (p_in + p_out));
  });
  if (stats != nullptr) *stats = s;
  return mesh;
}

SampledField build_volume_field(const ScanVolume& volume, const VolumeToothOptions& options,
                                const VoxelGrid& grid, const Vec3& offset, const FieldBand& band,
                                ScanSurfaceStats* stats) {
  VolumeSolidRule rule;
  const VoxelGrid own = build_volume_tooth(volume, options, nullptr, &rule);
  const std::string& name = volume.source;
  if (own.n != grid.n || own.voxel_size != grid.voxel_size || own.voxels != grid.voxels) {
    throw InputError(name + ": the voxel tooth given is not the one this scan gives (" +
                     std::to_string(grid.n) + "^3 against " + std::to_string(own.n) +
                     "^3, or other voxels: did the file change?)");
  }
  if (std::none_of(volume.values.begin(), volume.values.end(),
                   [&](float v) { return classify_intensity(rule.thresholds, v) == kEmpty; })) {
    throw InputError(name + ": no sample is background (every sample lies in the enamel or "
                     "dentin range: the thresholds are at or below the scan's lowest intensity); "
                     "the field needs a surface between tooth and background");
  }
  if (std::none_of(own.voxels.begin(), own.voxels.end(), [](std::uint8_t m) { return m != 0; })) {
    throw InputError(name + ": no voxel of the resampled tooth is solid at " +
                     std::to_string(own.n) + "^3 (the solid samples are fewer than an island); "
                     "the field has no surface");
  }
  TriangleMesh surface = scan_surface(volume, own, rule, stats);
  for (Vec3& v : surface.vertices) v += offset;
  return build_sampled_field(grid, surface, band);
}

SampledField build_tooth_field(const ToothSource& t, const VoxelGrid& grid, const Vec3& offset,
                               const FieldBand& band) {
  TriangleMesh surface;
  if (t.source == "procedural") {
    const MolarSolidTest molar_solid_at{MolarParams{}};  // molar_solid's answers, cheaper
    surface = triangulate_implicit(
        grid, [&](const Vec3& p) { return molar_solid_at(p - offset); });
  } else if (t.source == "mesh") {
    LoadedMesh loaded = load_mesh(t.path);
    const double k =
        t.mesh_scale > 0.0 ? t.mesh_scale : scale_for_size(loaded.mesh, 1e-3 * t.size_mm);
    scale_mesh(loaded.mesh, k);
    surface = std::move(loaded.mesh);
    for (Vec3& v : surface.vertices) v += offset;
  } else if (t.source == "volume") {
    return build_volume_field(load_volume(t.path), volume_tooth_options(t), grid, offset, band);
  } else {
    throw InputError("tooth.contact_model \"field\": tooth source '" + t.source +
                     "': expected procedural, mesh or volume");
  }
  return build_sampled_field(grid, surface, band);
}

}  // namespace dentsim
