// `dentsim voxelize MESH|VOLUME|--procedural --resolution N [--size-mm S | --scale K] --json FILE
//  [--png FILE] [--material-thresholds enamel=LO:HI,dentin=LO:HI]`: builds the voxel tooth
// (tooth_io/voxelize.h, procedural_molar.h, volume.h) and reports it (issues #4, #21).
// JSON keys (a contract): voxels_by_material and volume_mm3_by_material (material name -> count,
// mm^3), volume_mm3 (solid), mesh_volume_mm3 (mesh input only), thresholds (volume input only),
// resolution, voxel_size_mm, octree_bytes, timing_ms (total wall time of the job); plus the echo
// of the scale and the mesh repairs, or of the volume's geometry and segmentation.
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "cli/outputs.h"
#include "cli/png_writer.h"
#include "cli/progress.h"
#include "cli/registry.h"
#include "reference/core/io.h"
#include "reference/tooth/materials.h"
#include "tooth_io/mesh.h"
#include "reference/tooth/octree.h"
#include "tooth_io/procedural_molar.h"
#include "tooth_io/render_png.h"
#include "tooth_io/volume.h"
#include "tooth_io/volume_write.h"
#include "tooth_io/voxelize.h"

namespace dentsim::cli {
namespace {

struct Options {
  std::string mesh;
  bool procedural = false;
  int resolution = 0;
  std::optional<double> size_mm;
  std::optional<double> scale;
  double enamel_mm = 2.5;
  std::string json;
  std::string png;
  int png_size = 512;
  std::string material_thresholds;  // volume input: "enamel=LO:HI,dentin=LO:HI"
  std::string write_volume;         // write a synthetic scan of the result here
  double scan_spacing_mm = 0.1;
  double scan_noise = 60;
};

nlohmann::json vec_mm(const Vec3& v) { return {v.x() * 1e3, v.y() * 1e3, v.z() * 1e3}; }

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

void run(const Options& o) {
  const auto t_start = std::chrono::steady_clock::now();
  if (o.procedural == !o.mesh.empty()) {
    throw InputError("voxelize: give either a MESH file or --procedural (one of them)");
  }
  if (o.size_mm && !(*o.size_mm > 0)) {
    throw InputError("--size-mm " + std::to_string(*o.size_mm) + ": expected a size > 0 (mm)");
  }
  if (o.scale && !(*o.scale > 0)) {
    throw InputError("--scale " + std::to_string(*o.scale) + ": expected a factor > 0");
  }
  if (!(o.enamel_mm >= 0)) throw InputError("--enamel-mm: expected a thickness >= 0 (mm)");
  if (o.png_size < 8 || o.png_size > 4096) throw InputError("--png-size: expected 8..4096 pixels");
  const bool volume = !o.mesh.empty() && is_volume_path(o.mesh);
  if (!o.material_thresholds.empty() && !volume) {
    throw InputError("--material-thresholds: only for a scan volume (DICOM folder, .nii, .nii.gz, "
                     ".nrrd, .nhdr); '" + (o.mesh.empty() ? std::string("--procedural") : o.mesh) +
                     "' is not one");
  }
  if (volume && (o.scale || o.size_mm)) {
    throw InputError("volume '" + o.mesh + "' carries its voxel spacing: --scale and --size-mm "
                     "are for meshes and the procedural molar");
  }
  if (!(o.scan_spacing_mm > 0)) throw InputError("--scan-spacing-mm: expected a spacing > 0 (mm)");
  if (!(o.scan_noise >= 0)) throw InputError("--scan-noise: expected a standard deviation >= 0");
  VolumeToothOptions vto;
  if (!o.material_thresholds.empty()) {
    vto.automatic_thresholds = false;
    vto.thresholds = parse_material_thresholds(o.material_thresholds, "--material-thresholds");
  }
  {
    // --write-volume: a NIfTI/NRRD file by its extension, else a DICOM series folder.
    std::string wv = o.write_volume;
    std::transform(wv.begin(), wv.end(), wv.begin(),
                   [](unsigned char c) { return std::tolower(c); });
    const bool wv_file = wv.ends_with(".nii") || wv.ends_with(".nii.gz") || wv.ends_with(".nrrd") ||
                         wv.ends_with(".nhdr");
    check_outputs(
        {{"--json", o.json}, {"--png", o.png}, {"--write-volume", wv_file ? o.write_volume : ""}},
        {{"--write-volume", wv_file ? "" : o.write_volume}}, {{"MESH", o.mesh}});
  }
  // Voxelising at 1024^3 takes about a minute: say so on stderr every few seconds, terminal or not.
  const Heartbeat heartbeat("dentsim voxelize: voxelizing at " + std::to_string(o.resolution) +
                            "^3");
  nlohmann::json j;
  VoxelGrid grid;
  VoxelizeReport rep;
  double t_load = 0;
  const auto t_vox = std::chrono::steady_clock::now();
  if (o.procedural) {
    MolarParams p;
    const double default_size_m = molar_bounds(p).extent().maxCoeff();
    if (o.scale) p.scale = *o.scale;
    if (o.size_mm) p.scale = *o.size_mm * 1e-3 / default_size_m;
    j["source"] = "procedural lower first molar";
    j["scale"] = p.scale;
    j["size_mm"] = vec_mm(molar_bounds(p).extent());
    grid = voxelize_procedural_molar(p, o.resolution, &rep);
    j["enamel_cusp_mm"] = p.enamel_cusp_m * p.scale * 1e3;
  } else if (volume) {
    std::string unit_note;
    const ScanVolume v = load_volume(o.mesh, &unit_note);
    if (!unit_note.empty()) std::fprintf(stderr, "dentsim voxelize: WARNING: %s\n", unit_note.c_str());
    t_load = ms_since(t_vox);
    vto.resolution = o.resolution;
    VolumeToothReport vr;
    grid = build_volume_tooth(v, vto, &vr);
    rep.crown.axis = enamel_axis(grid);
    const MaterialThresholds& t = vr.thresholds;
    j["source"] = o.mesh;
    j["volume"] = {{"format", v.format},
                   {"dims", v.dims},
                   {"spacing_mm", vec_mm(v.spacing)},
                   {"origin_mm", vec_mm(v.origin)},
                   {"direction_columns",
                    {{v.direction(0, 0), v.direction(1, 0), v.direction(2, 0)},
                     {v.direction(0, 1), v.direction(1, 1), v.direction(2, 1)},
                     {v.direction(0, 2), v.direction(1, 2), v.direction(2, 2)}}},
                   {"unit_note", unit_note}};
    j["thresholds"] = {{"method", t.automatic ? "otsu-3-class" : "--material-thresholds"},
                       {"enamel", {t.enamel_lo, t.enamel_hi}},
                       {"dentin", {t.dentin_lo, t.dentin_hi}}};
    j["class_means"] = {{"background", vr.class_means[0]},
                        {"dentin", vr.class_means[1]},
                        {"enamel", vr.class_means[2]}};
    j["segmentation"] = {{"interpolation", "trilinear"},
                         {"partial_volume_voxels", vr.partial_volume_voxels},
                         {"partial_volume_radius_voxels", vr.interpolation_radius_voxels},
                         {"island_components", vr.island_components},
                         {"island_voxels", vr.island_voxels},
                         {"min_island_voxels", vto.min_island_voxels}};
  } else {
    if (!o.scale && !o.size_mm) {
      throw InputError("mesh '" + o.mesh +
                       "' has no unit: give --scale K (metres per mesh unit) or --size-mm S "
                       "(largest bounding-box extent in millimetres)");
    }
    LoadedMesh m = load_mesh(o.mesh);
    for (const std::string& r : m.report.repairs) {
      std::fprintf(stderr, "dentsim voxelize: WARNING: repaired mesh '%s': %s\n", o.mesh.c_str(),
                   r.c_str());
    }
    const double k = o.scale ? *o.scale : scale_for_size(m.mesh, *o.size_mm * 1e-3);
    scale_mesh(m.mesh, k);
    std::fprintf(stderr, "dentsim voxelize: mesh '%s' scaled by %.6g m per unit (%s)\n",
                 o.mesh.c_str(), k, o.scale ? "--scale" : "from --size-mm");
    t_load = ms_since(t_vox);
    VoxelizeOptions vo;
    vo.resolution = o.resolution;
    vo.enamel_cusp_m = o.enamel_mm * 1e-3;
    grid = voxelize_mesh(m.mesh, vo, &rep);
    j["source"] = o.mesh;
    j["scale_m_per_unit"] = k;
    j["size_mm"] = vec_mm(mesh_bounds(m.mesh).extent());
    j["mesh_volume_mm3"] = solid_volume(m.mesh) * 1e9;
    j["volume_bound_mm3"] = rep.solid.surface_voxels * grid.voxel_volume() * 1e9;
    j["surface_voxels"] = rep.solid.surface_voxels;
    j["repairs"] = m.report.repairs;
    j["pulp_groups"] = rep.pulp_groups;
    j["mesh"] = {{"vertices", m.mesh.vertices.size()},
                 {"triangles", m.mesh.triangles.size()},
                 {"shells", m.report.shells},
                 {"welded_vertices", m.report.welded_vertices}};
    j["enamel_cusp_mm"] = o.enamel_mm;
  }
  const double t_voxelize = ms_since(t_vox) - t_load;

  const auto counts = count_materials(grid);
  nlohmann::json by_material = nlohmann::json::object();
  nlohmann::json mm3_by_material = nlohmann::json::object();
  long solid = 0;
  for (int m = kEnamel; m < kMaterialCount; ++m) {
    const char* name = material_properties(static_cast<std::uint8_t>(m)).name;
    by_material[name] = counts[m];
    mm3_by_material[name] = counts[m] * grid.voxel_volume() * 1e9;
    solid += counts[m];
  }
  j["voxels_by_material"] = by_material;
  j["volume_mm3_by_material"] = mm3_by_material;
  j["volume_mm3"] = solid * grid.voxel_volume() * 1e9;
  j["resolution"] = grid.n;
  j["voxel_size_mm"] = grid.voxel_size * 1e3;
  j["origin_mm"] = vec_mm(grid.origin);
  j["crown"] = {{"axis", {rep.crown.axis.x(), rep.crown.axis.y(), rep.crown.axis.z()}},
                {"cej_mm", rep.crown.cej * 1e3},
                {"height_mm", rep.crown.crown_height * 1e3}};

  double t_png = 0;
  if (!o.png.empty()) {
    const auto t0 = std::chrono::steady_clock::now();
    RenderOptions ro;
    ro.panel_size = o.png_size;
    ro.up = rep.crown.axis;
    write_png(o.png, render_voxels(grid, ro));
    j["png"] = o.png;
    t_png = ms_since(t0);
  }
  if (!o.write_volume.empty()) {
    // A synthetic scan of this tooth (tooth_io/volume_write.h), seed 1.
    const ScanVolume scan = render_scan(grid, Vec3::Constant(o.scan_spacing_mm * 1e-3), o.scan_noise, 1);
    write_volume(scan, o.write_volume);
    j["written_volume"] = {{"path", o.write_volume},
                           {"dims", scan.dims},
                           {"spacing_mm", o.scan_spacing_mm},
                           {"noise", o.scan_noise}};
  }
  // The full octree of the collision stage over this grid (it takes the grid over).
  const double grid_mib =
      static_cast<double>(grid.voxels.size() * sizeof(grid.voxels[0])) / (1024.0 * 1024.0);
  const double voxel_mm = grid.voxel_size * 1e3;
  const auto t_octree = std::chrono::steady_clock::now();
  const FullOctree octree(std::move(grid));
  j["octree_bytes"] = octree.memory_bytes();
  j["octree_levels"] = octree.levels();
  j["timing_breakdown_ms"] = {
      {"load", t_load}, {"voxelize", t_voxelize}, {"png", t_png}, {"octree", ms_since(t_octree)}};
  j["timing_ms"] = ms_since(t_start);
  write_json(o.json, j);
  // The summary on stdout (the heartbeat only says the work goes on).
  std::string materials;
  for (int m = kEnamel; m < kMaterialCount; ++m) {
    if (counts[m] == 0) continue;
    materials += (materials.empty() ? "" : ", ") +
                 std::string(material_properties(static_cast<std::uint8_t>(m)).name) + " " +
                 std::to_string(counts[m]);
  }
  std::printf(
      "voxelize: %s at %d^3 (voxel %.4f mm): %ld solid voxels (%s), %.2f mm^3; memory: grid "
      "%.1f MiB, octree %.1f MiB; %.1f s (load %.1f, voxelize %.1f, octree %.1f); wrote "
      "%s%s%s%s%s\n",
      j["source"].get<std::string>().c_str(), o.resolution, voxel_mm, solid, materials.c_str(),
      j["volume_mm3"].get<double>(), grid_mib,
      static_cast<double>(octree.memory_bytes()) / (1024.0 * 1024.0), 1e-3 * ms_since(t_start),
      1e-3 * t_load, 1e-3 * t_voxelize, 1e-3 * j["timing_breakdown_ms"]["octree"].get<double>(),
      o.json.c_str(), o.png.empty() ? "" : " ", o.png.c_str(), o.write_volume.empty() ? "" : " ",
      o.write_volume.c_str());
}

void setup_voxelize(CLI::App& app) {
  auto o = std::make_shared<Options>();
  CLI::App* sub = app.add_subcommand(
      "voxelize",
      "Build the voxel tooth from a mesh (STL/OBJ/PLY), a scan volume (DICOM/NIfTI/NRRD) or the "
      "procedural molar and report it");
  sub->add_option("mesh", o->mesh,
                  "Tooth mesh: .stl (binary or ASCII), .obj (group Nerve = pulp), .ply; or scan "
                  "volume: DICOM series folder, .nii, .nii.gz, .nrrd, .nhdr");
  sub->add_flag("--procedural", o->procedural, "Use the built-in procedural lower first molar");
  sub->add_option("--resolution", o->resolution, "Voxels per axis N (power of two, 32..1024)")
      ->required();
  auto* size = sub->add_option("--size-mm", o->size_mm,
                               "Scale so the largest bounding-box extent is S millimetres")
                   ->check(finite_range(1e-3, 100.0));
  auto* scale = sub->add_option("--scale", o->scale,
                                "Metres per mesh unit (procedural: factor on its real size)")
                    ->check(finite_range(1e-12, 10.0));
  size->excludes(scale);
  sub->add_option("--enamel-mm", o->enamel_mm,
                  "Enamel thickness over the crown top for meshes, mm (default 2.5)")
      ->check(finite_range(0.0, 10.0));
  sub->add_option("--material-thresholds", o->material_thresholds,
                  "Volume: intensity ranges enamel=LO:HI,dentin=LO:HI (default: three-class Otsu)");
  sub->add_option("--write-volume", o->write_volume,
                  "Also write a synthetic CT scan of the result: .nii(.gz), .nrrd/.nhdr or a "
                  "DICOM folder");
  sub->add_option("--scan-spacing-mm", o->scan_spacing_mm,
                  "Sample spacing of --write-volume, mm (default 0.1)");
  sub->add_option("--scan-noise", o->scan_noise,
                  "Gaussian noise of --write-volume, intensity units (default 60; enamel 2200, "
                  "dentin 1200, pulp 100, air 0)");
  sub->add_option("--json", o->json, "Write the report here (JSON)")->required();
  sub->add_option("--png", o->png, "Write a shaded picture (whole tooth and cut-away) here");
  sub->add_option("--png-size", o->png_size, "Picture panel size in pixels (default 512)");
  sub->callback([o] { run(*o); });
}
DENTSIM_REGISTER_COMMAND(setup_voxelize);

}  // namespace
}  // namespace dentsim::cli
