// `dentsim voxelize VOLUME` and a scene with a volume tooth, end to end (issue #21): the JSON
// contract (volume_mm3_by_material within 5 % of the layered sphere's analytic layers, the
// thresholds echoed, counts x h^3 = mm^3), the threshold override, bad input exiting 2 with the
// file or flag named and the output untouched, and `dentsim run` on a scene whose tooth is a
// NIfTI file named relative to the scene.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "sim/scene.h"
#include "reference/core/io.h"
#include "tests/support/cli.h"
#include "tests/tooth_io/volume_synth.h"

namespace dentsim {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using testing::LayeredSphere;
using testing::run_dentsim;

// The scan's spacing: 0.1 mm; 0.2 mm in the sanitizer pass (scripts/test.sh), where rendering
// the 131^3 scan in every test's process took most of these tests' time: the same reader, the
// same commands and the same 5 % bounds on 1/8 of the samples (docs/results/ci_time.md).
#if defined(__SANITIZE_ADDRESS__)
constexpr double kScanSpacingMm = 0.2;
#else
constexpr double kScanSpacingMm = 0.1;
#endif

class VolumeCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("dentsim_volume_cli_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    // Isotropic, axis-aligned: enough for 128^3 (h = 0.08 mm).
    const double h = kScanSpacingMm * 1e-3;
    const ScanVolume v =
        testing::render_sphere(LayeredSphere{}, Vec3(h, h, h), Mat3::Identity(), 5);
    write_nifti(v, path("scan.nii.gz"));
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static std::string path(const std::string& name) { return (dir_ / name).string(); }

  static fs::path dir_;
};
fs::path VolumeCli::dir_;

TEST_F(VolumeCli, AutomaticAndGivenThresholds) {
  const LayeredSphere s;
  const double truth[3] = {s.enamel_volume() * 1e9, s.dentin_volume() * 1e9, s.pulp_volume() * 1e9};
  const char* names[3] = {"enamel", "dentin", "pulp"};
  for (const std::string extra : {"", " --material-thresholds enamel=1700:5000,dentin=650:1699.9"}) {
    const auto r = run_dentsim("voxelize " + path("scan.nii.gz") + " --resolution 128 --json " +
                               path("v.json") + " --png " + path("v.png") + extra);
    ASSERT_EQ(r.status, 0) << r.output;
    const auto j = nlohmann::json::parse(read_file(path("v.json")));
    const double h = j["voxel_size_mm"].get<double>();
    for (int m = 0; m < 3; ++m) {
      const double mm3 = j["volume_mm3_by_material"][names[m]].get<double>();
      EXPECT_DOUBLE_EQ(mm3, j["voxels_by_material"][names[m]].get<long>() * h * h * h);
      EXPECT_NEAR(mm3 / truth[m], 1.0, 0.05) << names[m] << extra;
    }
    EXPECT_EQ(j["volume"]["format"], "NIfTI-1");
    EXPECT_GE(j["volume"]["dims"][0].get<int>(), std::lround(13.0 / kScanSpacingMm));  // 13 mm
    EXPECT_EQ(j["volume"]["dims"][0], j["volume"]["dims"][2]);
    if (extra.empty()) {
      EXPECT_EQ(j["thresholds"]["method"], "otsu-3-class");
      EXPECT_GT(j["thresholds"]["dentin"][0].get<double>(), s.pulp);
      EXPECT_LT(j["thresholds"]["enamel"][0].get<double>(), s.enamel);
    } else {
      EXPECT_EQ(j["thresholds"]["method"], "--material-thresholds");
      EXPECT_EQ(j["thresholds"]["enamel"], nlohmann::json::array({1700.0, 5000.0}));
      EXPECT_EQ(j["thresholds"]["dentin"], nlohmann::json::array({650.0, 1699.9}));
    }
    EXPECT_GT(fs::file_size(path("v.png")), 1000u);
  }
}

// The procedural molar written as a synthetic CT (a DICOM series; 0.15 mm, noise 60) and read back:
// each layer's volume within 5 % of the molar's own (measured: enamel +0.9 %, dentin +0.3 %,
// pulp -2.2 %; the pulp canals narrow to ~2 samples near the apices).
TEST_F(VolumeCli, ProceduralMolarThroughASyntheticScan) {
  const auto a = run_dentsim("voxelize --procedural --resolution 128 --json " + path("p.json") +
                             " --write-volume " + path("molar_ct") + " --scan-spacing-mm 0.15");
  ASSERT_EQ(a.status, 0) << a.output;
  const auto b = run_dentsim("voxelize " + path("molar_ct") + " --resolution 128 --json " +
                             path("c.json"));
  ASSERT_EQ(b.status, 0) << b.output;
  const auto p = nlohmann::json::parse(read_file(path("p.json")));
  const auto c = nlohmann::json::parse(read_file(path("c.json")));
  EXPECT_EQ(c["volume"]["format"], "DICOM");
  EXPECT_EQ(c["volume"]["dims"], p["written_volume"]["dims"]);
  for (const char* m : {"enamel", "dentin", "pulp"}) {
    EXPECT_NEAR(c["volume_mm3_by_material"][m].get<double>() /
                    p["volume_mm3_by_material"][m].get<double>(),
                1.0, 0.05)
        << m;
  }
}

TEST_F(VolumeCli, BadInputExitsTwoAndLeavesTheReport) {
  write_file_atomic(path("keep.json"), "{\"old\": true}");
  std::ofstream(path("junk.nii")) << "not a nifti";
  std::ofstream(path("junk.nrrd")) << "NRRD0004\ntype: short\n";
  fs::create_directories(path("dicom"));
  std::ofstream(path("dicom/a.dcm")) << "not dicom";
  std::ofstream(path("dicom/b.dcm")) << "not dicom";
  const std::string out = " --resolution 64 --json " + path("keep.json");
  const std::pair<std::string, std::string> cases[] = {
      {path("junk.nii") + out, path("junk.nii") + ": not a readable NIfTI"},
      {path("junk.nrrd") + out, path("junk.nrrd") + ": not a readable NRRD volume"},
      {path("dicom") + out, path("dicom/a.dcm") + ": not a readable DICOM image"},
      {path("scan.nii.gz") + out + " --material-thresholds enamel=1:2", "--material-thresholds"},
      {path("scan.nii.gz") + out + " --scale 1e-3", "carries its voxel spacing"},
      {"--procedural" + out + " --material-thresholds enamel=1:2,dentin=3:4",
       "only for a scan volume"},
  };
  for (const auto& [args, expected] : cases) {
    const auto r = run_dentsim("voxelize " + args);
    EXPECT_EQ(r.status, 2) << args << "\n" << r.output;
    EXPECT_THAT(r.output, HasSubstr(expected)) << args;
  }
  EXPECT_EQ(read_file(path("keep.json")), "{\"old\": true}");
}

std::string volume_scene(const std::string& tooth_fields) {
  std::string text = builtin_scene_text("probe");
  const std::string from = "\"source\": \"procedural\", \"resolution\": 128";
  text.replace(text.find(from), from.size(), tooth_fields);
  return text;
}

TEST_F(VolumeCli, SceneWithAVolumeToothRuns) {
  write_file_atomic(path("scene.json"),
                    volume_scene("\"source\": \"volume\", \"volume\": \"scan.nii.gz\", "
                                 "\"resolution\": 64"));
  const Scene scene = load_scene(path("scene.json"));
  EXPECT_EQ(scene.tooth.volume_path, path("scan.nii.gz"));  // relative to the scene file
  const auto r = run_dentsim("run " + path("scene.json") + " --duration 0.2 --out " + path("run"));
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(fs::exists(path("run/report.json")));
  EXPECT_GT(fs::file_size(path("run/tooth_before.png")), 1000u);

  auto error_of = [](const std::string& fields) {
    try {
      parse_scene(volume_scene(fields), "v.json");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  EXPECT_THAT(error_of("\"source\": \"volume\", \"volume\": \"a.nii\", \"material_thresholds\": "
                       "\"enamel=1:2\""),
              HasSubstr("tooth.material_thresholds"));
  EXPECT_THAT(error_of("\"source\": \"procedural\", \"volume\": \"a.nii\""),
              HasSubstr("tooth.volume"));
  EXPECT_THAT(error_of("\"source\": \"ct\""), HasSubstr("\"volume\""));
}

// The field model on a scan (issue #30): the loader takes "contact_model": "field" with a volume
// tooth, and `dentsim run` builds the scan's field (its iso-surface) and renders it.
TEST_F(VolumeCli, SceneWithAVolumeToothRunsTheFieldModel) {
  std::string text = volume_scene("\"source\": \"volume\", \"volume\": \"scan.nii.gz\", "
                                  "\"resolution\": 64");
  const std::string from = "\"contact_model\": \"sdf\"";
  text.replace(text.find(from), from.size(), "\"contact_model\": \"field\"");
  write_file_atomic(path("field.json"), text);
  EXPECT_EQ(load_scene(path("field.json")).tooth.contact_model, "field");
  const auto r =
      run_dentsim("run " + path("field.json") + " --duration 2.5 --out " + path("field_run"));
  ASSERT_EQ(r.status, 0) << r.output;
  const auto j = nlohmann::json::parse(read_file(path("field_run/report.json")));
  // The probe phase (1.5 s to the end) presses 0.5 N on the sphere: in contact throughout
  // (measured 1532 ticks), the contact force near the hand's 0.5 N (measured 0.516 N max), and
  // the penalty law F = K_tooth d on the field's surface renders K_tooth = 3000 N/m (measured
  // 3005).
  EXPECT_GE(j["contact_ticks"].get<int>(), 1000);
  EXPECT_NEAR(j["max_contact_force_n"].get<double>(), 0.5, 0.1);
  EXPECT_NEAR(j["rendered_stiffness_n_per_m"].get<double>(), 3000.0, 0.02 * 3000.0);
}

}  // namespace
}  // namespace dentsim
