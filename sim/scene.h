// Scene files of `dentsim run` (issue #6; format documented in docs/scenes.md).
//
// A scene is a JSON document, versioned by "dentsim_scene": 1, naming the tooth, the tool, the
// device, the rendering method and gains, the proxy, the scripted hand, the duration and the tick
// rate. Every field is validated on load; errors name the file (or built-in scene) and the field
// path, and unknown fields are errors. Built-in scenes (`probe`, `probe-groove`, `drill`) ship inside the binary
// (builtin_scene_text) so the simulator runs with no data file.
//
// Placement: the tooth is voxelised in its own frame and translated so that its "anchor" — the
// highest solid point of the occlusal surface near the crown's axis — sits at
// x_home + tooth.anchor_offset_mm, with x_home the device's tool-tip position at its home pose.
// Hand keyframe positions are offsets from that anchor [mm], so a script reads as "5 mm above the
// tooth", "0.5 mm into the occlusal surface".
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "device/scripted_hand.h"
#include "reference/core/params.h"
#include "reference/core/types.h"
#include "tooth_io/tooth_source.h"

namespace dentsim {

struct SceneTooth {
  std::string source = "procedural";   // "procedural", "mesh" or "volume"
  std::string mesh_path;               // for source = mesh (STL / OBJ / PLY)
  std::string volume_path;             // for source = volume (DICOM folder, NIfTI, NRRD)
  std::string material_thresholds;     // volume: "enamel=LO:HI,dentin=LO:HI"; empty = automatic
  double mesh_scale = 0.0;             // metres per mesh unit (mesh); 0 = use size_mm
  double size_mm = 0.0;                // target largest extent [mm] (mesh); 0 = use scale
  int resolution = 128;                // voxels per axis (power of two, 32..512)
  double k_tooth = 3000.0;             // K_tooth [N/m] (scaled per material)
  double b_tooth = 0.0;                // B_tooth [N s/m]
  Vec3 anchor_offset = Vec3(0.0, 0.0, -0.006);  // [m] anchor relative to the home tip position
  // "sdf" (surface proxy on the signed distance, reference/tooth/sdf.h: never tunnels; the
  // default) or "faces" (the thesis's face model, reference/tooth/collision.h).
  std::string contact_model = "sdf";
  // The "field" model's sample spacing H [m] (tooth.field_spacing_mm; issue #30): 0 = automatic
  // (the largest multiple of the voxel size within the tip's H_max, reference/tooth/
  // sampled_field.h field_stride_for); else at least the voxel size (checked when the tooth is
  // built: the voxel size is known then), the field then samples every floor(H / h)-th voxel.
  double field_spacing = 0.0;
};

struct SceneTool {
  std::string preset = "handpiece";    // explorer | scaler | handpiece (desired M_d, D_d)
  double bur_radius = 0.5e-3;          // tip sphere radius [m]
  double bur_speed_rpm = 0.0;          // > 0 only for a drilling tool
  double cutting_coefficient = 0.5;    // tangential/normal bur force (drilling model)
  bool drills() const { return bur_speed_rpm > 0.0; }
};

struct SceneDevice {
  std::string type = "simulated-phantom";
  std::string model_file;              // device model file; empty = the shipped default
  double jitter_us = 0.0;              // uniform tick jitter half-width [us]
  bool quantize = true;                // encoder quantisation
  bool saturate = true;                // motor torque saturation
};

struct SceneMethod {
  Method method = Method::kPmiPd;
  CouplingGains coupling;
  double observer_gain = 100.0;        // L [1/s], all joints
  // > 0: the pipeline's device model carries this fraction of the hand's mass and inertia at the
  // tip while it grips (reference/grasp_mass_model.h); 0 = the device alone.
  double grasp_mass_scale = 0.0;
  // With grasp_mass_scale > 0 and pmi-pd: a grip detector decides tick by tick whether the hand
  // is on the tool (reference/grip_detector.h) instead of assuming it always is.
  bool grip_detector = false;
  // Remedy of issue #29 (docs/derivations/quiet_stiffness.md): the pipeline estimates the joint
  // state between encoder counts with the device model (reference/encoder_kalman.h).
  bool encoder_kalman = false;
  // With encoder_kalman: whether its prediction includes the device model's joint friction
  // (reference/encoder_kalman.h; false leaves it to the process noise: quiet_stiffness.md 8.6).
  bool encoder_kalman_friction = true;
  // With encoder_kalman and encoder_kalman_friction: the friction set-valued (stick-slip) across
  // the coupled joints instead of the smooth tau_f (EncoderKalmanParams::stick_slip;
  // quiet_stiffness.md 8.7). Scene key method.encoder_kalman_friction_model: "smooth" (default),
  // "none" (= encoder_kalman_friction false) or "stick_slip".
  bool encoder_kalman_stick_slip = false;
  // Remedy of issue #29 for the stiff contact mode: the coupling and D_d see the device velocity
  // advanced over the loop's known lags with the device model (reference/lag_compensation.h).
  bool lag_compensation = false;
  // Issue #29: after a command the motors could not deliver, the virtual side sees only what the
  // device can deliver (reference/saturation_passive.h). Changes nothing while nothing saturates.
  // On by default (a safety property): the built-in scenes at their quiet gains never saturate,
  // so their runs are bitwise the same on and off (docs/derivations/quiet_stiffness.md section 6).
  bool saturation_passive = true;
  FrictionParams friction;
  ProxyParams proxy;
};

struct SceneHandKey {
  double t = 0.0;                      // [s]
  Vec3 offset = Vec3::Zero();          // reference position relative to the tooth anchor [m]
  Vec3 force = Vec3::Zero();           // feed-forward force [N] (world)
  std::string phase;                   // label ("approach", "probe", "drill", "retract")
};

struct Scene {
  int version = 1;
  std::string name;
  std::string description;
  std::string origin;                  // where it was loaded from (for messages)
  std::string text;                    // the JSON it was parsed from (recorded sessions keep it)
  double duration = 1.0;               // [s]
  double tick_hz = 1000.0;
  SceneTooth tooth;
  SceneTool tool;
  SceneDevice device;
  SceneMethod method;
  HandImpedance hand;
  std::vector<SceneHandKey> script;
};

// The tooth description tooth_io/tooth_source.h builds the voxel tooth from.
ToothSource tooth_source(const SceneTooth& tooth);

// Parses and validates a scene; `origin` names it in errors.
Scene parse_scene(const std::string& text, const std::string& origin);
// A built-in scene by name, or else a scene file by path. Throws InputError naming both
// possibilities when neither exists.
Scene load_scene(const std::string& name_or_path);
// The scene with some of its fields changed (e.g. {"tick_hz": 8000} for `run --tick-hz`, or a
// tooth resolution for `dentsim bench`): the scene as written is validated first, then again with
// `patch` merged into its JSON (RFC 7386 merge patch), so every check — a rate-dependent one
// such as the observer's L T < 1 included — names the field. `what` is added to the scene's origin
// in messages. Throws InputError like load_scene.
Scene load_scene_patched(const std::string& name_or_path, const nlohmann::json& patch,
                         const std::string& what);
std::vector<std::string> builtin_scene_names();
// The JSON text of a built-in scene (throws InputError for an unknown name).
std::string builtin_scene_text(const std::string& name);

}  // namespace dentsim
