// Tests for sim/scene.h: the built-in scenes parse, and every kind of bad field is rejected
// with a message that names the document and the field.
#include "sim/scene.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "reference/core/io.h"
#include "reference/phantom/phantom_params.h"
#include "sim/simulator.h"
#include "tests/support/cli.h"

namespace dentsim {
namespace {

TEST(Scene, BuiltinScenesParse) {
  for (const std::string& name : builtin_scene_names()) {
    const Scene s = load_scene(name);
    EXPECT_EQ(s.name, name);
    EXPECT_GT(s.duration, 0.0);
    EXPECT_GE(s.script.size(), 3u);
    EXPECT_EQ(s.tooth.source, "procedural");
  }
  EXPECT_TRUE(load_scene("drill").tool.drills());
  EXPECT_FALSE(load_scene("probe").tool.drills());
  EXPECT_EQ(load_scene("drill").method.method, Method::kPmiPd);
  EXPECT_DOUBLE_EQ(load_scene("drill").tool.bur_radius, 0.5e-3);
  // Every built-in: the surface proxy, PMI + PD with the hand's mass and the grip detector at the
  // Z-width headline's coupling (docs/results/zwidth.md: K_vc 1200, b_vc 4), and K_tooth 3000 with
  // the encoder Kalman filter, the quiet pick of docs/derivations/quiet_stiffness.md section 7.
  for (const std::string& name : builtin_scene_names()) {
    const Scene s = load_scene(name);
    EXPECT_EQ(s.tooth.contact_model, "sdf") << name;
    EXPECT_EQ(s.method.method, Method::kPmiPd) << name;
    EXPECT_TRUE(s.method.grip_detector) << name;
    EXPECT_DOUBLE_EQ(s.method.grasp_mass_scale, 1.0) << name;
    EXPECT_DOUBLE_EQ(s.method.coupling.k_lin, 1200.0) << name;
    EXPECT_DOUBLE_EQ(s.method.coupling.b_lin, 4.0) << name;
    EXPECT_DOUBLE_EQ(s.tooth.k_tooth, 3000.0) << name;
    EXPECT_TRUE(s.method.encoder_kalman) << name;
  }
  // A scene without the key gets the default model.
  std::string text = builtin_scene_text("probe");
  const std::string key = ", \"contact_model\": \"sdf\"";
  text.erase(text.find(key), key.size());
  EXPECT_EQ(parse_scene(text, "p.json").tooth.contact_model, "sdf");
}

// Replaces the first occurrence of `from` in the drill scene by `to` and returns the error text.
std::string error_of(const std::string& from, const std::string& to) {
  std::string text = builtin_scene_text("drill");
  const auto pos = text.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  text.replace(pos, from.size(), to);
  try {
    parse_scene(text, "bad.json");
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(Scene, BadFieldsAreNamed) {
  EXPECT_EQ(error_of("\"bur_radius_mm\": 0.5", "\"bur_radius_mm\": -1"),
            "bad.json: tool.bur_radius_mm: must be > 0 (got -0.001)");
  EXPECT_EQ(error_of("\"resolution\": 128", "\"resolution\": 100"),
            "bad.json: tooth.resolution: must be a power of two from 32 to 512 (got 100)");
  EXPECT_NE(error_of("\"preset\": \"handpiece\"", "\"preset\": \"hammer\"")
                .find("tool.preset: unknown tool \"hammer\""),
            std::string::npos);
  EXPECT_NE(error_of("\"name\": \"pmi-pd\"", "\"name\": \"rk4\"").find("method.name"),
            std::string::npos);
  EXPECT_NE(error_of("\"k_tooth_n_per_m\": 3000", "\"k_toth_n_per_m\": 3000")
                .find("tooth.k_toth_n_per_m: unknown field"),
            std::string::npos);
  EXPECT_NE(error_of("\"dentsim_scene\": 1", "\"dentsim_scene\": 7").find("dentsim_scene"),
            std::string::npos);
  EXPECT_NE(error_of("\"t_s\": 1.0,", "\"t_s\": 0.0,").find("hand.script[1].t_s"),
            std::string::npos);
  EXPECT_NE(error_of("\"offset_mm\": [0, 0, 6]", "\"offset_mm\": [0, 6]")
                .find("hand.script[0].offset_mm: expected an array of 3 numbers"),
            std::string::npos);
  EXPECT_NE(error_of("\"observer_gain_per_s\": 30", "\"observer_gain_per_s\": 5000")
                .find("method.observer_gain_per_s"),
            std::string::npos);
  EXPECT_NE(error_of("\"grasp_mass_scale\": 1.0", "\"grasp_mass_scale\": -1")
                .find("method.grasp_mass_scale"),
            std::string::npos);
  EXPECT_EQ(error_of("\"contact_model\": \"sdf\"", "\"contact_model\": \"voxels\""),
            "bad.json: tooth.contact_model: expected \"sdf\" (the default), \"faces\" or "
            "\"field\" (got \"voxels\")");
  // The field model drills (issue #30): the drill scene's spinning bur is accepted with it.
  EXPECT_EQ(error_of("\"contact_model\": \"sdf\"", "\"contact_model\": \"field\""),
            "(no error)");
  // The field's spacing (issue #30): 0 or absent automatic, a spacing in mm, never negative.
  EXPECT_EQ(error_of("\"contact_model\": \"sdf\"",
                     "\"contact_model\": \"field\", \"field_spacing_mm\": 0.12"),
            "(no error)");
  EXPECT_EQ(error_of("\"contact_model\": \"sdf\"",
                     "\"contact_model\": \"field\", \"field_spacing_mm\": -0.1"),
            "bad.json: tooth.field_spacing_mm: must be >= 0 (got -0.1)");
  EXPECT_NE(error_of("\"grasp_mass_scale\": 1.0", "\"grasp_mass_scale\": 0")
                .find("method.grip_detector: needs name \"pmi-pd\" and grasp_mass_scale > 0"),
            std::string::npos);
  EXPECT_NE(error_of("\"type\": \"simulated-phantom\"", "\"type\": \"omni\"").find("device.type"),
            std::string::npos);
  EXPECT_NE(error_of("\"duration_s\": 5.0", "\"duration_s\": \"long\"")
                .find("duration_s: expected a number"),
            std::string::npos);
}

// tooth.field_spacing_mm (issue #30): the field's stride from the bur (0.5 mm: H_max = 0.179 mm,
// k = 1 at the drill scene's h = 0.173 mm), from the key (0.35 mm: k = 2), and a spacing below
// the voxel size refused with the key named when the tooth is built (the voxel size known).
TEST(Scene, FieldSpacingSetsTheStrideAndBelowTheVoxelSizeIsNamed) {
  Scene scene = load_scene("drill");
  scene.tooth.contact_model = "field";
  const auto automatic = build_scene_rig(scene);
  ASSERT_NE(automatic->field, nullptr);
  EXPECT_EQ(automatic->field->stride(),
            field_stride_for(scene.tool.bur_radius, automatic->field->voxel_size()));
  EXPECT_EQ(automatic->field->stride(), 1);
  scene.tooth.field_spacing = 0.35e-3;
  EXPECT_EQ(build_scene_rig(scene)->field->stride(), 2);
  scene.tooth.field_spacing = 0.1e-3;
  try {
    build_scene_rig(scene);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("tooth.field_spacing_mm: 0.100000 mm is below the "
                                             "voxel size"));
  }
}

// Values that used to run to the end with null/inf in the report, or wrap silently (issue #18),
// are rejected at the door with the field named.
TEST(Scene, OutOfRangeValuesAreRejectedWithTheField) {
  EXPECT_EQ(error_of("\"grasp_mass_scale\": 1.0", "\"grasp_mass_scale\": 1e300"),
            "bad.json: method.grasp_mass_scale: must be at most 10 (a fraction of the hand's mass, "
            "1 = all of it; got 1e+300)");
  EXPECT_EQ(error_of("\"bur_radius_mm\": 0.5", "\"bur_radius_mm\": 1e5"),
            "bad.json: tool.bur_radius_mm: must be at most 5 (dental burs are 0.25-2.5 mm in "
            "radius; got 100000)");
  EXPECT_EQ(error_of("\"resolution\": 128", "\"resolution\": 4294967424"),
            "bad.json: tooth.resolution: expected an integer in [32, 512], got 4294967424");
  EXPECT_EQ(error_of("\"k_vc_n_per_m\": 1200", "\"k_vc_n_per_m\": 1e400"),
            "bad.json: method.k_vc_n_per_m: number '1e400' is outside the range of a double "
            "(|x| < 1.8e308)");
  EXPECT_EQ(error_of("\"k_vc_n_per_m\": 1200", "\"k_vc_n_per_m\": 1200, \"k_vc_n_per_m\": 70"),
            "bad.json: method.k_vc_n_per_m: key given twice in one object (JSON would silently "
            "keep the last)");
  EXPECT_THAT(error_of("\"k_tooth_n_per_m\": 3000", "\"k_tooth_n_per_m\": 1e200"),
              ::testing::HasSubstr("bad.json: tooth.k_tooth_n_per_m: must be at most 1e+07"));
  EXPECT_THAT(error_of("\"offset_mm\": [0, 0, 6]", "\"offset_mm\": [0, 0, 1e300]"),
              ::testing::HasSubstr("bad.json: hand.script[0].offset_mm: must be at most 1000"));
  EXPECT_THAT(error_of("\"mass_kg\": 0.05", "\"mass_kg\": 1e300"),
              ::testing::HasSubstr("bad.json: proxy.mass_kg: must be at most 100"));
  // Deep nesting: an error, not a crash.
  EXPECT_THAT(error_of("\"description\": \"", "\"x\": " + std::string(100000, '[') +
                                                 std::string(100000, ']') + ", \"description\": \""),
              ::testing::HasSubstr("bad.json: x"));
}

TEST(Scene, MeshToothNeedsExactlyOneScale) {
  std::string text = builtin_scene_text("probe");
  const std::string from = "\"source\": \"procedural\"";
  text.replace(text.find(from), from.size(), "\"source\": \"mesh\", \"mesh\": \"t.stl\"");
  try {
    parse_scene(text, "m.json");
    FAIL() << "accepted a unitless mesh without scale";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("exactly one of mesh_scale_m_per_unit or size_mm"),
              std::string::npos);
  }
}

TEST(Scene, NotJsonAndUnknownScene) {
  EXPECT_THROW(parse_scene("{ nope", "x.json"), InputError);
  try {
    load_scene("/no/such/scene.json");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("neither a built-in scene"), std::string::npos);
  }
}

// Found by the scene fuzz target: a method name with an escape byte was echoed raw in the
// message (a terminal control sequence); it is written \x1b.
TEST(Scene, ControlBytesOfTheFileAreEscapedInMessages) {
  const std::string e = error_of("\"name\": \"pmi-pd\"", "\"name\": \"pmi-p\\u001bd\"");
  EXPECT_NE(e.find("method.name"), std::string::npos) << e;
  EXPECT_NE(e.find("pmi-p\\x1bd"), std::string::npos) << e;
  for (const char c : e) EXPECT_FALSE(static_cast<unsigned char>(c) < 0x20) << e;
}


// device.model_file resolves like a mesh: relative to the scene file's folder, whatever the
// current directory (it used to be the current directory's); an absolute path is kept; a missing
// file is an error naming the scene, the field, the path as written and where it was looked for
// (issue #33). A patched scene (load_scene_patched, e.g. `run --tick-hz`) resolves alike.
TEST(Scene, DeviceModelFileIsRelativeToTheSceneFile) {
  namespace fs = std::filesystem;
  const fs::path dir = testing::fresh_temp_dir("dentsim_scene_model_file");
  fs::create_directories(dir / "sub");
  PhantomParams p = default_phantom_params();
  p.name = "the scene's own device";
  write_file_atomic((dir / "sub" / "dev.json").string(), phantom_params_to_text(p));
  std::string text = builtin_scene_text("probe");
  const std::string from = "\"type\": \"simulated-phantom\"";
  text.replace(text.find(from), from.size(), from + ", \"model_file\": \"dev.json\"");
  const fs::path scene = dir / "sub" / "scene.json";
  write_file_atomic(scene.string(), text);
  const fs::path cwd = fs::current_path();
  fs::current_path(dir);  // the model file is not in the current directory
  const Scene s = load_scene(scene.string());
  const Scene patched = load_scene_patched("sub/scene.json", {{"tick_hz", 500}}, "(patched)");
  fs::current_path(cwd);
  EXPECT_TRUE(fs::equivalent(s.device.model_file, dir / "sub" / "dev.json")) << s.device.model_file;
  EXPECT_TRUE(fs::equivalent(patched.device.model_file, dir / "sub" / "dev.json"))
      << patched.device.model_file;
  EXPECT_EQ(load_phantom_params(s.device.model_file).name, "the scene's own device");
  // Absolute: unchanged.
  std::string abs_text = text;
  const std::string abs_path = (dir / "sub" / "dev.json").string();
  abs_text.replace(abs_text.find("\"dev.json\""), 10, "\"" + abs_path + "\"");
  EXPECT_EQ(parse_scene(abs_text, (dir / "elsewhere.json").string()).device.model_file, abs_path);
  // Missing: the field and both paths named.
  std::string missing = text;
  missing.replace(missing.find("\"dev.json\""), 10, "\"x.json\"");
  write_file_atomic((dir / "sub" / "missing.json").string(), missing);
  try {
    load_scene((dir / "sub" / "missing.json").string());
    FAIL() << "accepted a missing model file";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              (dir / "sub" / "missing.json").string() +
                  ": device.model_file: no such file 'x.json' (resolved to " +
                  (dir / "sub" / "x.json").string() + ")");
  }
}

}  // namespace
}  // namespace dentsim
