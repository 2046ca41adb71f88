#include "sim/scene.h"

#include <cmath>
#include <filesystem>

#include "device/backend.h"
#include "reference/core/io.h"
#include "reference/core/json_reader.h"
#include "reference/tools.h"

namespace dentsim {
namespace {

// Upper limits of scene numbers (docs/scenes.md): generous for any dental scene and any gain
// study, small enough that every product in the pipeline stays finite.
constexpr double kMaxMeshScale = 1.0;            // [m per mesh unit]
constexpr double kMaxToothSizeMm = 100.0;        // [mm]
constexpr double kMaxBurRadiusMm = 5.0;          // [mm]
constexpr double kMaxBurRpm = 1e6;               // [rpm]
constexpr double kMaxCuttingCoefficient = 10.0;  // [-]
constexpr double kMaxFrictionMu = 10.0;          // [-]
constexpr double kMaxGraspMassScale = 10.0;      // [-]
constexpr double kMaxStiffness = 1e7;            // [N/m], [N m/rad]
constexpr double kMaxDamping = 1e5;              // [N s/m], [N m s/rad]
constexpr double kMaxMassKg = 100.0;             // [kg]
constexpr double kMaxInertia = 10.0;             // [kg m^2]
constexpr double kMaxOffsetMm = 1000.0;          // [mm]
constexpr const char* kWhyStiffness = "far beyond any stable haptic gain";

// A file a scene names (device.model_file), like a mesh, is relative to the scene file's folder
// (`origin`, when it is a file on disk; else, for a built-in scene's text, to the current
// directory); an absolute path is kept. The file must exist: the error names the scene, the field,
// the path as written and where it was looked for (issue #33).
std::string scene_relative_file(const JsonReader& rd, const std::string& origin,
                                const std::string& field, const std::string& path) {
  namespace fs = std::filesystem;
  std::string resolved = path;
  if (!fs::path(path).is_absolute() && fs::is_regular_file(origin)) {
    resolved = (fs::path(origin).parent_path() / path).string();
  }
  std::error_code ec;
  if (!fs::is_regular_file(resolved, ec)) {
    const fs::path abs = fs::absolute(resolved, ec);
    rd.fail(field, "no such file '" + path + "' (resolved to " +
                       (ec ? resolved : abs.lexically_normal().string()) + ")");
  }
  return resolved;
}

// The scene's relative file paths made absolute against its folder, for a document parsed under
// another origin (load_scene_patched): the files then resolve as in the file itself.
void absolutize_scene_paths(nlohmann::json& doc, const std::string& scene_file) {
  namespace fs = std::filesystem;
  if (!fs::is_regular_file(scene_file)) return;
  const fs::path dir = fs::absolute(fs::path(scene_file)).parent_path();
  auto fix = [&](const char* object, const char* key) {
    if (!doc.is_object() || !doc.contains(object) || !doc[object].is_object()) return;
    nlohmann::json& o = doc[object];
    if (!o.contains(key) || !o[key].is_string()) return;
    const std::string v = o[key].get<std::string>();
    if (!v.empty() && !fs::path(v).is_absolute()) o[key] = (dir / v).string();
  };
  fix("device", "model_file");
  fix("tooth", "mesh");
  fix("tooth", "volume");
}

// Built-in scenes. Positions in the hand script are offsets from the tooth's anchor (the top of
// the occlusal surface near the crown axis) in mm; the tool tip starts at the device's home pose,
// 6 mm above the anchor. Method: PMI + passive decomposition with the hand's mass in the model and
// the grip detector, K_vc = 1200 N/m, b_vc = 4 N s/m (docs/results/zwidth.md, the row "pmi-pd +
// hand mass + grip detector": stable and passive under the force, grip and release operators).
// K_tooth and method.encoder_kalman are chosen for quiet, by one rule over the candidates
// K_tooth {3000, 4500, 6000, 12000} N/m x encoder_kalman {off, on} applied alike to every built-in
// scene (`scripts/quiet_study.py gains`, docs/derivations/quiet_stiffness.md section 7): the
// stiffest candidate quiet by issue #29's measures, else the one failing the fewest of them
// (then fewest contact losses, then the smallest ripple). None is quiet on the simulated
// Phantom's encoders (the staircase bound of section 4: ripple ~0.7 K Delta_tip / F); the rule
// picks K_tooth = 3000 N/m (the issue's stiffness target) with the filter on for all three: the
// only candidates with the free-space force under 0.03 N RMS are the filter's, and the ripple and
// the losses grow with K_tooth. The observer gain L = 30 /s: with the Phantom's quantised
// encoders (velocity noise ~ quantum / T) L = 100 /s drives the decomposition feed-forward into a
// limit cycle in free space (docs/scenes.md shows the runs). Contact: the surface proxy
// (tooth.contact_model "sdf", reference/tooth/sdf.h). Forces a dentist uses: an explorer 0.5-2 N,
// a handpiece 0.3-1.5 N (docs/scenes.md cites them).
constexpr const char* kProbeScene = R"json({
  "dentsim_scene": 1,
  "name": "probe",
  "description": "Explorer probe: approach the molar, slide along the lingual cusp ridge pressing lightly, retract.",
  "duration_s": 5.0,
  "tick_hz": 1000,
  "tooth": {"source": "procedural", "resolution": 128, "k_tooth_n_per_m": 3000, "b_tooth_n_s_per_m": 5.0,
            "anchor_offset_mm": [0, 0, -6], "contact_model": "sdf"},
  "tool": {"preset": "explorer", "bur_radius_mm": 0.4, "bur_speed_rpm": 0},
  "device": {"type": "simulated-phantom", "jitter_us": 0, "quantize": true, "saturate": true},
  "method": {"name": "pmi-pd", "k_vc_n_per_m": 1200, "b_vc_n_s_per_m": 4, "k_vc_ang_n_m_per_rad": 0.3,
             "b_vc_ang_n_m_s_per_rad": 0.001, "observer_gain_per_s": 30, "friction_mu": 0.2,
             "grasp_mass_scale": 1.0, "grip_detector": true, "encoder_kalman": true},
  "proxy": {"mass_kg": 0.05, "inertia_kg_m2": 1e-5, "damping_n_s_per_m": 0.0, "damping_ang_n_m_s_per_rad": 0.0},
  "hand": {"script": [
    {"t_s": 0.0, "offset_mm": [0, 0, 6],     "force_n": [0, 0, 0],    "phase": "approach"},
    {"t_s": 1.0, "offset_mm": [-2, 2.5, 2],  "force_n": [0, 0, -0.5], "phase": "approach"},
    {"t_s": 1.5, "offset_mm": [-2, 2.5, 1],  "force_n": [0, 0, -0.5], "phase": "probe"},
    {"t_s": 3.5, "offset_mm": [2, 2.5, 1],   "force_n": [0, 0, -0.5], "phase": "probe"},
    {"t_s": 4.0, "offset_mm": [2, 2.5, 6],   "force_n": [0, 0, 0],    "phase": "retract"}
  ]}
})json";

// Across the central (mesiodistal) fissure, buccal to lingual, where the face model let the
// explorer fall into the tooth (issue #16).
constexpr const char* kProbeGrooveScene = R"json({
  "dentsim_scene": 1,
  "name": "probe-groove",
  "description": "Explorer across the central fissure: approach, slide buccal to lingual over the groove pressing 0.5 N, retract.",
  "duration_s": 5.0,
  "tick_hz": 1000,
  "tooth": {"source": "procedural", "resolution": 128, "k_tooth_n_per_m": 3000, "b_tooth_n_s_per_m": 5.0,
            "anchor_offset_mm": [0, 0, -6], "contact_model": "sdf"},
  "tool": {"preset": "explorer", "bur_radius_mm": 0.4, "bur_speed_rpm": 0},
  "device": {"type": "simulated-phantom", "jitter_us": 0, "quantize": true, "saturate": true},
  "method": {"name": "pmi-pd", "k_vc_n_per_m": 1200, "b_vc_n_s_per_m": 4, "k_vc_ang_n_m_per_rad": 0.3,
             "b_vc_ang_n_m_s_per_rad": 0.001, "observer_gain_per_s": 30, "friction_mu": 0.2,
             "grasp_mass_scale": 1.0, "grip_detector": true, "encoder_kalman": true},
  "proxy": {"mass_kg": 0.05, "inertia_kg_m2": 1e-5, "damping_n_s_per_m": 0.0, "damping_ang_n_m_s_per_rad": 0.0},
  "hand": {"script": [
    {"t_s": 0.0, "offset_mm": [0.5, 0, 6],    "force_n": [0, 0, 0],    "phase": "approach"},
    {"t_s": 1.0, "offset_mm": [0.5, -3, 3],   "force_n": [0, 0, -0.3], "phase": "approach"},
    {"t_s": 1.5, "offset_mm": [0.5, -3, 2],   "force_n": [0, 0, -0.5], "phase": "probe"},
    {"t_s": 3.5, "offset_mm": [0.5, 3, 2],    "force_n": [0, 0, -0.5], "phase": "probe"},
    {"t_s": 4.0, "offset_mm": [0.5, 3, 6],    "force_n": [0, 0, 0],    "phase": "retract"}
  ]}
})json";

constexpr const char* kDrillScene = R"json({
  "dentsim_scene": 1,
  "name": "drill",
  "description": "High-speed handpiece: approach the molar, drill into the carious fossa through enamel into dentin, retract.",
  "duration_s": 5.0,
  "tick_hz": 1000,
  "tooth": {"source": "procedural", "resolution": 128, "k_tooth_n_per_m": 3000, "b_tooth_n_s_per_m": 5.0,
            "anchor_offset_mm": [0, 0, -6], "contact_model": "sdf"},
  "tool": {"preset": "handpiece", "bur_radius_mm": 0.5, "bur_speed_rpm": 300000, "cutting_coefficient": 0.5},
  "device": {"type": "simulated-phantom", "jitter_us": 0, "quantize": true, "saturate": true},
  "method": {"name": "pmi-pd", "k_vc_n_per_m": 1200, "b_vc_n_s_per_m": 4, "k_vc_ang_n_m_per_rad": 0.3,
             "b_vc_ang_n_m_s_per_rad": 0.001, "observer_gain_per_s": 30, "friction_mu": 0.1,
             "grasp_mass_scale": 1.0, "grip_detector": true, "encoder_kalman": true},
  "proxy": {"mass_kg": 0.05, "inertia_kg_m2": 1e-5, "damping_n_s_per_m": 0.0, "damping_ang_n_m_s_per_rad": 0.0},
  "hand": {"script": [
    {"t_s": 0.0, "offset_mm": [0, 0, 6],    "force_n": [0, 0, 0],    "phase": "approach"},
    {"t_s": 1.0, "offset_mm": [-1, 0, 0.5], "force_n": [0, 0, -0.3], "phase": "approach"},
    {"t_s": 1.5, "offset_mm": [-1, 0, -0.3], "force_n": [0, 0, -0.8], "phase": "drill"},
    {"t_s": 3.5, "offset_mm": [1, 0, -0.6],  "force_n": [0, 0, -0.8], "phase": "drill"},
    {"t_s": 4.2, "offset_mm": [1, 0, 6],     "force_n": [0, 0, 0],    "phase": "retract"}
  ]}
})json";

}  // namespace

std::vector<std::string> builtin_scene_names() { return {"probe", "probe-groove", "drill"}; }

std::string builtin_scene_text(const std::string& name) {
  if (name == "probe") return kProbeScene;
  if (name == "probe-groove") return kProbeGrooveScene;
  if (name == "drill") return kDrillScene;
  throw InputError("unknown built-in scene '" + name + "' (built-in: probe, probe-groove, drill)");
}

Scene load_scene(const std::string& name_or_path) {
  for (const std::string& n : builtin_scene_names()) {
    if (n == name_or_path) return parse_scene(builtin_scene_text(n), "built-in scene '" + n + "'");
  }
  if (!std::filesystem::exists(name_or_path)) {
    throw InputError("scene '" + name_or_path +
                     "' is neither a built-in scene (probe, probe-groove, drill) nor a readable file");
  }
  return parse_scene(read_file(name_or_path), name_or_path);
}

Scene load_scene_patched(const std::string& name_or_path, const nlohmann::json& patch,
                         const std::string& what) {
  const Scene as_written = load_scene(name_or_path);
  bool builtin = false;
  for (const std::string& n : builtin_scene_names()) builtin = builtin || n == name_or_path;
  nlohmann::json doc =
      nlohmann::json::parse(builtin ? builtin_scene_text(name_or_path) : read_file(name_or_path));
  doc.merge_patch(patch);
  if (!builtin) absolutize_scene_paths(doc, name_or_path);
  return parse_scene(doc.dump(), as_written.origin + " " + what);
}

ToothSource tooth_source(const SceneTooth& tooth) {
  ToothSource t;
  t.source = tooth.source;
  t.path = tooth.source == "volume" ? tooth.volume_path : tooth.mesh_path;
  t.mesh_scale = tooth.mesh_scale;
  t.size_mm = tooth.size_mm;
  t.resolution = tooth.resolution;
  t.automatic_thresholds = tooth.material_thresholds.empty();
  if (!t.automatic_thresholds) {
    t.thresholds = parse_material_thresholds(tooth.material_thresholds, "tooth.material_thresholds");
  }
  return t;
}

Scene parse_scene(const std::string& text, const std::string& origin) {
  const JsonReader rd(origin);
  const JsonReader::Json doc = rd.parse(text);
  rd.only_keys(doc, "", {"dentsim_scene", "name", "description", "duration_s", "tick_hz", "tooth",
                         "tool", "device", "method", "proxy", "hand"});
  Scene s;
  s.origin = origin;
  s.text = text;
  s.version = static_cast<int>(rd.integer(doc, "", "dentsim_scene", -1, 0, 1000));
  if (s.version != 1) {
    rd.fail("dentsim_scene", "unsupported or missing scene format version (expected 1)");
  }
  s.name = rd.string(doc, "", "name");
  s.description = rd.string(doc, "", "description", "");
  s.duration = rd.number(doc, "", "duration_s");
  rd.positive("duration_s", s.duration);
  if (s.duration > 3600.0) rd.fail("duration_s", "must be at most 3600 s");
  s.tick_hz = rd.number(doc, "", "tick_hz", 1000.0);
  if (!(s.tick_hz >= 100.0 && s.tick_hz <= 20000.0)) {
    rd.fail("tick_hz", "must be within [100, 20000] Hz");
  }

  // Tooth.
  const auto& t = rd.object(doc, "", "tooth");
  rd.only_keys(t, "tooth", {"source", "mesh", "mesh_scale_m_per_unit", "size_mm", "resolution",
                            "k_tooth_n_per_m", "b_tooth_n_s_per_m", "anchor_offset_mm", "volume",
                            "material_thresholds", "contact_model", "field_spacing_mm"});
  s.tooth.source = rd.string(t, "tooth", "source", "procedural");
  if (s.tooth.source != "procedural" && s.tooth.source != "mesh" && s.tooth.source != "volume") {
    rd.fail("tooth.source", "expected \"procedural\", \"mesh\" or \"volume\", got \"" +
                                s.tooth.source + "\"");
  }
  // A scan volume (issue #21): a DICOM folder, .nii(.gz) or .nrrd/.nhdr, relative to the scene
  // file; optional "material_thresholds": "enamel=LO:HI,dentin=LO:HI" (default automatic).
  if (s.tooth.source == "volume") {
    s.tooth.volume_path = rd.string(t, "tooth", "volume");
    if (!std::filesystem::path(s.tooth.volume_path).is_absolute() &&
        std::filesystem::exists(origin)) {
      s.tooth.volume_path =
          (std::filesystem::path(origin).parent_path() / s.tooth.volume_path).string();
    }
    s.tooth.material_thresholds = rd.string(t, "tooth", "material_thresholds", "");
    if (!s.tooth.material_thresholds.empty()) {
      parse_material_thresholds(s.tooth.material_thresholds,
                                origin + ": tooth.material_thresholds");
    }
  } else if (t.contains("volume") || t.contains("material_thresholds")) {
    rd.fail(t.contains("volume") ? "tooth.volume" : "tooth.material_thresholds",
            "only allowed with \"source\": \"volume\"");
  }
  if (s.tooth.source == "mesh") {
    s.tooth.mesh_path = rd.string(t, "tooth", "mesh");
    s.tooth.mesh_scale = rd.number(t, "tooth", "mesh_scale_m_per_unit", 0.0);
    s.tooth.size_mm = rd.number(t, "tooth", "size_mm", 0.0);
    rd.non_negative("tooth.mesh_scale_m_per_unit", s.tooth.mesh_scale);
    rd.non_negative("tooth.size_mm", s.tooth.size_mm);
    rd.at_most("tooth.mesh_scale_m_per_unit", s.tooth.mesh_scale, kMaxMeshScale,
               "metres per mesh unit");
    rd.at_most("tooth.size_mm", s.tooth.size_mm, kMaxToothSizeMm, "a tooth, not a building");
    if ((s.tooth.mesh_scale > 0.0) == (s.tooth.size_mm > 0.0)) {
      rd.fail("tooth", "a mesh needs exactly one of mesh_scale_m_per_unit or size_mm (meshes are unitless)");
    }
    // A relative mesh path is relative to the scene file.
    if (!std::filesystem::path(s.tooth.mesh_path).is_absolute() &&
        std::filesystem::exists(origin)) {
      s.tooth.mesh_path =
          (std::filesystem::path(origin).parent_path() / s.tooth.mesh_path).string();
    }
  } else if (t.contains("mesh")) {
    rd.fail("tooth.mesh", "only allowed with \"source\": \"mesh\"");
  }
  s.tooth.resolution = static_cast<int>(rd.integer(t, "tooth", "resolution", 128, 32, 512));
  const int r = s.tooth.resolution;
  if ((r & (r - 1)) != 0) {
    rd.fail("tooth.resolution", "must be a power of two from 32 to 512 (got " + std::to_string(r) + ")");
  }
  s.tooth.k_tooth = rd.number(t, "tooth", "k_tooth_n_per_m");
  rd.positive("tooth.k_tooth_n_per_m", s.tooth.k_tooth);
  rd.at_most("tooth.k_tooth_n_per_m", s.tooth.k_tooth, kMaxStiffness, kWhyStiffness);
  s.tooth.b_tooth = rd.number(t, "tooth", "b_tooth_n_s_per_m", 0.0);
  rd.non_negative("tooth.b_tooth_n_s_per_m", s.tooth.b_tooth);
  rd.at_most("tooth.b_tooth_n_s_per_m", s.tooth.b_tooth, kMaxDamping, kWhyStiffness);
  s.tooth.anchor_offset = 1e-3 * rd.vec3(t, "tooth", "anchor_offset_mm", Vec3(0, 0, -6));
  rd.at_most("tooth.anchor_offset_mm", 1e3 * s.tooth.anchor_offset.cwiseAbs().maxCoeff(),
             kMaxOffsetMm, "every component, inside the device's workspace");
  s.tooth.contact_model = rd.string(t, "tooth", "contact_model", "sdf");
  if (s.tooth.contact_model != "sdf" && s.tooth.contact_model != "faces" &&
      s.tooth.contact_model != "field") {
    rd.fail("tooth.contact_model", "expected \"sdf\" (the default), \"faces\" or \"field\" (got \"" +
                                       s.tooth.contact_model + "\")");
  }
  // 0 or absent: automatic; not below the voxel size (checked when the tooth is built).
  const double spacing_mm = rd.number(t, "tooth", "field_spacing_mm", 0.0);
  if (!std::isfinite(spacing_mm)) {
    rd.fail("tooth.field_spacing_mm", "must be finite (0 or absent: automatic)");
  }
  rd.non_negative("tooth.field_spacing_mm", spacing_mm);
  s.tooth.field_spacing = 1e-3 * spacing_mm;

  // Tool.
  const auto& tl = rd.object(doc, "", "tool");
  rd.only_keys(tl, "tool", {"preset", "bur_radius_mm", "bur_speed_rpm", "cutting_coefficient"});
  s.tool.preset = rd.string(tl, "tool", "preset");
  try {
    (void)tool_preset(s.tool.preset);
  } catch (const std::exception&) {
    std::string names;
    for (const auto& n : tool_preset_names()) names += (names.empty() ? "" : ", ") + n;
    rd.fail("tool.preset", "unknown tool \"" + s.tool.preset + "\" (expected one of: " + names + ")");
  }
  s.tool.bur_radius = 1e-3 * rd.number(tl, "tool", "bur_radius_mm");
  rd.positive("tool.bur_radius_mm", s.tool.bur_radius);
  rd.at_most("tool.bur_radius_mm", 1e3 * s.tool.bur_radius, kMaxBurRadiusMm,
             "dental burs are 0.25-2.5 mm in radius");
  s.tool.bur_speed_rpm = rd.number(tl, "tool", "bur_speed_rpm", 0.0);
  rd.non_negative("tool.bur_speed_rpm", s.tool.bur_speed_rpm);
  rd.at_most("tool.bur_speed_rpm", s.tool.bur_speed_rpm, kMaxBurRpm,
             "air turbines run up to 450000 rpm");
  s.tool.cutting_coefficient = rd.number(tl, "tool", "cutting_coefficient", 0.5);
  rd.non_negative("tool.cutting_coefficient", s.tool.cutting_coefficient);
  rd.at_most("tool.cutting_coefficient", s.tool.cutting_coefficient, kMaxCuttingCoefficient,
             "tangential over normal force");

  // Device.
  const auto& dv = rd.object(doc, "", "device");
  rd.only_keys(dv, "device", {"type", "model_file", "jitter_us", "quantize", "saturate"});
  s.device.type = rd.string(dv, "device", "type");
  if (!find_device_backend(s.device.type)) {
    rd.fail("device.type", "expected " + device_backend_list("\"") + " (OpenHaptics), got \"" +
                               s.device.type + "\"");
  }
  s.device.model_file = rd.string(dv, "device", "model_file", "");
  if (!s.device.model_file.empty()) {
    s.device.model_file = scene_relative_file(rd, origin, "device.model_file", s.device.model_file);
  }
  s.device.jitter_us = rd.number(dv, "device", "jitter_us", 0.0);
  rd.non_negative("device.jitter_us", s.device.jitter_us);
  if (s.device.jitter_us * 1e-6 >= 0.5 / s.tick_hz) {
    rd.fail("device.jitter_us", "must be less than half the tick");
  }
  s.device.quantize = rd.boolean(dv, "device", "quantize", true);
  s.device.saturate = rd.boolean(dv, "device", "saturate", true);

  // Method and gains.
  const auto& m = rd.object(doc, "", "method");
  rd.only_keys(m, "method",
               {"name", "k_vc_n_per_m", "b_vc_n_s_per_m", "k_vc_ang_n_m_per_rad",
                "b_vc_ang_n_m_s_per_rad", "observer_gain_per_s", "friction_mu", "grasp_mass_scale",
                "grip_detector", "encoder_kalman", "encoder_kalman_friction",
                "encoder_kalman_friction_model", "lag_compensation", "saturation_passive"});
  const std::string mname = rd.string(m, "method", "name");
  try {
    s.method.method = parse_method(mname);
  } catch (const std::exception& e) {
    rd.fail("method.name", e.what());
  }
  auto& g = s.method.coupling;
  g.k_lin = rd.number(m, "method", "k_vc_n_per_m");
  rd.positive("method.k_vc_n_per_m", g.k_lin);
  g.b_lin = rd.number(m, "method", "b_vc_n_s_per_m", 0.3);
  rd.non_negative("method.b_vc_n_s_per_m", g.b_lin);
  g.k_ang = rd.number(m, "method", "k_vc_ang_n_m_per_rad", 0.3);
  rd.positive("method.k_vc_ang_n_m_per_rad", g.k_ang);
  g.b_ang = rd.number(m, "method", "b_vc_ang_n_m_s_per_rad", 0.001);
  rd.non_negative("method.b_vc_ang_n_m_s_per_rad", g.b_ang);
  s.method.observer_gain = rd.number(m, "method", "observer_gain_per_s", 100.0);
  rd.positive("method.observer_gain_per_s", s.method.observer_gain);
  if (s.method.observer_gain * (1.0 / s.tick_hz) >= 1.0) {
    rd.fail("method.observer_gain_per_s", "L T must be < 1 for the discrete observer to be stable");
  }
  s.method.grasp_mass_scale = rd.number(m, "method", "grasp_mass_scale", 0.0);
  rd.non_negative("method.grasp_mass_scale", s.method.grasp_mass_scale);
  rd.at_most("method.grasp_mass_scale", s.method.grasp_mass_scale, kMaxGraspMassScale,
             "a fraction of the hand's mass, 1 = all of it");
  s.method.grip_detector = rd.boolean(m, "method", "grip_detector", false);
  if (s.method.grip_detector &&
      (s.method.grasp_mass_scale <= 0.0 || s.method.method != Method::kPmiPd)) {
    rd.fail("method.grip_detector",
            "needs name \"pmi-pd\" and grasp_mass_scale > 0 (it chooses whether the model carries "
            "the hand's mass)");
  }
  s.method.encoder_kalman = rd.boolean(m, "method", "encoder_kalman", false);
  s.method.encoder_kalman_friction = rd.boolean(m, "method", "encoder_kalman_friction", true);
  if (m.contains("encoder_kalman_friction_model")) {
    const std::string fm = rd.string(m, "method", "encoder_kalman_friction_model");
    if (fm != "smooth" && fm != "none" && fm != "stick_slip") {
      rd.fail("method.encoder_kalman_friction_model",
              "'" + fm + "' is not one of \"smooth\", \"none\", \"stick_slip\"");
    }
    if (m.contains("encoder_kalman_friction") &&
        s.method.encoder_kalman_friction != (fm != "none")) {
      rd.fail("method.encoder_kalman_friction_model",
              "\"" + fm + "\" contradicts method.encoder_kalman_friction = " +
                  (s.method.encoder_kalman_friction ? "true" : "false"));
    }
    s.method.encoder_kalman_friction = fm != "none";
    s.method.encoder_kalman_stick_slip = fm == "stick_slip";
  }
  s.method.lag_compensation = rd.boolean(m, "method", "lag_compensation", false);
  s.method.saturation_passive = rd.boolean(m, "method", "saturation_passive", true);
  s.method.friction.mu = rd.number(m, "method", "friction_mu", 0.0);
  rd.non_negative("method.friction_mu", s.method.friction.mu);
  rd.at_most("method.friction_mu", s.method.friction.mu, kMaxFrictionMu, "a friction coefficient");
  for (const auto& [field, v] : {std::pair<const char*, double>{"k_vc_n_per_m", g.k_lin},
                                 {"b_vc_n_s_per_m", g.b_lin},
                                 {"k_vc_ang_n_m_per_rad", g.k_ang},
                                 {"b_vc_ang_n_m_s_per_rad", g.b_ang}}) {
    rd.at_most(std::string("method.") + field, v,
               field[0] == 'k' ? kMaxStiffness : kMaxDamping, kWhyStiffness);
  }
  s.method.friction.enabled = s.method.friction.mu > 0.0;

  // Proxy.
  const auto& p = rd.object(doc, "", "proxy");
  rd.only_keys(p, "proxy", {"mass_kg", "inertia_kg_m2", "damping_n_s_per_m",
                            "damping_ang_n_m_s_per_rad"});
  s.method.proxy.mass = rd.number(p, "proxy", "mass_kg");
  rd.positive("proxy.mass_kg", s.method.proxy.mass);
  rd.at_most("proxy.mass_kg", s.method.proxy.mass, kMaxMassKg, "a hand tool");
  const double J = rd.number(p, "proxy", "inertia_kg_m2");
  rd.positive("proxy.inertia_kg_m2", J);
  rd.at_most("proxy.inertia_kg_m2", J, kMaxInertia, "a hand tool");
  s.method.proxy.inertia = Mat3::Identity() * J;
  s.method.proxy.damping_lin = rd.number(p, "proxy", "damping_n_s_per_m", 0.0);
  rd.non_negative("proxy.damping_n_s_per_m", s.method.proxy.damping_lin);
  s.method.proxy.damping_ang = rd.number(p, "proxy", "damping_ang_n_m_s_per_rad", 0.0);
  rd.non_negative("proxy.damping_ang_n_m_s_per_rad", s.method.proxy.damping_ang);

  // Hand.
  const auto& h = rd.object(doc, "", "hand");
  rd.only_keys(h, "hand", {"impedance", "script"});
  if (h.contains("impedance")) {
    const auto& z = rd.object(h, "hand", "impedance");
    const std::string zp = "hand.impedance";
    rd.only_keys(z, zp, {"mass_kg", "inertia_kg_m2", "k_n_per_m", "b_n_s_per_m",
                         "k_ang_n_m_per_rad", "b_ang_n_m_s_per_rad"});
    s.hand.mass = rd.number(z, zp, "mass_kg", s.hand.mass);
    s.hand.inertia = rd.number(z, zp, "inertia_kg_m2", s.hand.inertia);
    s.hand.k_lin = rd.number(z, zp, "k_n_per_m", s.hand.k_lin);
    s.hand.b_lin = rd.number(z, zp, "b_n_s_per_m", s.hand.b_lin);
    s.hand.k_ang = rd.number(z, zp, "k_ang_n_m_per_rad", s.hand.k_ang);
    s.hand.b_ang = rd.number(z, zp, "b_ang_n_m_s_per_rad", s.hand.b_ang);
    rd.non_negative(zp + ".mass_kg", s.hand.mass);
    rd.non_negative(zp + ".inertia_kg_m2", s.hand.inertia);
    rd.non_negative(zp + ".k_n_per_m", s.hand.k_lin);
    rd.non_negative(zp + ".b_n_s_per_m", s.hand.b_lin);
    rd.non_negative(zp + ".k_ang_n_m_per_rad", s.hand.k_ang);
    rd.non_negative(zp + ".b_ang_n_m_s_per_rad", s.hand.b_ang);
    rd.at_most(zp + ".mass_kg", s.hand.mass, kMaxMassKg, "a hand");
    rd.at_most(zp + ".inertia_kg_m2", s.hand.inertia, kMaxInertia, "a hand");
    rd.at_most(zp + ".k_n_per_m", s.hand.k_lin, kMaxStiffness, kWhyStiffness);
    rd.at_most(zp + ".b_n_s_per_m", s.hand.b_lin, kMaxDamping, kWhyStiffness);
    rd.at_most(zp + ".k_ang_n_m_per_rad", s.hand.k_ang, kMaxStiffness, kWhyStiffness);
    rd.at_most(zp + ".b_ang_n_m_s_per_rad", s.hand.b_ang, kMaxDamping, kWhyStiffness);
  }
  if (!h.contains("script") || !h.at("script").is_array() || h.at("script").empty()) {
    rd.fail("hand.script", "expected a non-empty array of keyframes");
  }
  const auto& script = h.at("script");
  for (std::size_t i = 0; i < script.size(); ++i) {
    const std::string kp = "hand.script[" + std::to_string(i) + "]";
    const auto& k = script[i];
    rd.only_keys(k, kp, {"t_s", "offset_mm", "force_n", "phase"});
    SceneHandKey key;
    key.t = rd.number(k, kp, "t_s");
    rd.non_negative(kp + ".t_s", key.t);
    if (!s.script.empty() && !(key.t > s.script.back().t)) {
      rd.fail(kp + ".t_s", "keyframe times must increase strictly");
    }
    key.offset = 1e-3 * rd.vec3(k, kp, "offset_mm");
    rd.at_most(kp + ".offset_mm", 1e3 * key.offset.cwiseAbs().maxCoeff(), kMaxOffsetMm,
               "every component, inside the device's workspace");
    key.force = rd.vec3(k, kp, "force_n", Vec3::Zero());
    if (key.force.norm() > 20.0) rd.fail(kp + ".force_n", "must be at most 20 N");
    key.phase = rd.string(k, kp, "phase", "");
    s.script.push_back(key);
  }
  return s;
}

}  // namespace dentsim
