// End-to-end `dentsim voxelize` (cli/cmd_voxelize.cc): runs the binary at DENTSIM_BINARY and
// checks the JSON contract (keys, counts equal to the library's, volume = count x h^3, the octree
// size formula), the PNG header, the echoed scale, and that bad input exits 2 with a message naming
// what was wrong and leaves the output file untouched.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "reference/core/io.h"
#include "reference/tooth/materials.h"
#include "tooth_io/mesh.h"
#include "tooth_io/procedural_molar.h"
#include "tooth_io/voxelize.h"

namespace dentsim {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

struct CliResult {
  int status;
  std::string err;
};

class VoxelizeCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("dentsim_voxelize_cli_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  CliResult run(const std::string& args) const {
    const std::string err = path("stderr.txt");
    const std::string cmd = std::string(DENTSIM_BINARY) + " voxelize " + args + " 2> " + err;
    const int rc = std::system(cmd.c_str());
    return {WIFEXITED(rc) ? WEXITSTATUS(rc) : -1, read_file(err)};
  }

  nlohmann::json json(const std::string& name) const {
    return nlohmann::json::parse(read_file(path(name)));
  }

  fs::path dir_;
};

long solid_of(const nlohmann::json& j) {
  long s = 0;
  for (const auto& [name, count] : j.at("voxels_by_material").items()) s += count.get<long>();
  return s;
}

TEST_F(VoxelizeCli, ProceduralJsonMatchesTheLibraryAndPngIsWritten) {
  const CliResult r = run("--procedural --resolution 64 --json " + path("p.json") + " --png " +
                          path("p.png") + " --png-size 96");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json j = json("p.json");
  for (const char* key : {"voxels_by_material", "volume_mm3", "resolution", "voxel_size_mm",
                          "octree_bytes", "timing_ms"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_FALSE(j.contains("mesh_volume_mm3"));  // only for meshes
  EXPECT_EQ(j["resolution"], 64);
  // The same tooth in-process: counts equal exactly.
  const VoxelGrid g = voxelize_procedural_molar(MolarParams{}, 64);
  const auto counts = count_materials(g);
  EXPECT_EQ(j["voxels_by_material"]["enamel"].get<long>(), counts[kEnamel]);
  EXPECT_EQ(j["voxels_by_material"]["dentin"].get<long>(), counts[kDentin]);
  EXPECT_EQ(j["voxels_by_material"]["pulp"].get<long>(), counts[kPulp]);
  const double h_mm = j["voxel_size_mm"].get<double>();
  EXPECT_DOUBLE_EQ(h_mm, g.voxel_size * 1e3);
  EXPECT_NEAR(j["volume_mm3"].get<double>(), solid_of(j) * h_mm * h_mm * h_mm, 1e-9);
  // Full octree over 64^3: (8^6 - 1) / 7 internal bytes + 64^3 leaves.
  EXPECT_EQ(j["octree_bytes"].get<long>(), (262144L - 1) / 7 + 262144L);
  EXPECT_GT(j["timing_ms"].get<double>(), 0.0);
  // PNG: signature and IHDR (two panels of 96 x 96).
  const std::string png = read_file(path("p.png"));
  ASSERT_GT(png.size(), 33u);
  EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  EXPECT_EQ(png.substr(12, 4), "IHDR");
  auto be32 = [&](std::size_t at) {
    return (static_cast<unsigned char>(png[at]) << 24) |
           (static_cast<unsigned char>(png[at + 1]) << 16) |
           (static_cast<unsigned char>(png[at + 2]) << 8) | static_cast<unsigned char>(png[at + 3]);
  };
  EXPECT_EQ(be32(16), 192);
  EXPECT_EQ(be32(20), 96);
}

TEST_F(VoxelizeCli, ProceduralSizeRescalesTheTooth) {
  ASSERT_EQ(run("--procedural --resolution 32 --size-mm 43 --json " + path("s.json")).status, 0);
  const nlohmann::json j = json("s.json");
  EXPECT_NEAR(j["scale"].get<double>(), 2.0, 1e-12);  // the default molar is 21.5 mm long
  EXPECT_NEAR(j["size_mm"][2].get<double>(), 43.0, 1e-9);
}

TEST_F(VoxelizeCli, MeshReportsItsVolumeAndEchoesTheScale) {
  const std::string mesh = std::string(DENTSIM_SOURCE_DIR) + "/../shared/data/chai3d-tooth.obj";
  if (!fs::exists(mesh)) GTEST_SKIP() << "../shared/data absent: " << mesh;
  const CliResult r = run(mesh + " --resolution 64 --size-mm 21 --json " + path("c.json"));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.err, HasSubstr("scaled by"));
  const nlohmann::json j = json("c.json");
  LoadedMesh m = load_mesh(mesh);
  const double k = scale_for_size(m.mesh, 21e-3);
  scale_mesh(m.mesh, k);
  EXPECT_DOUBLE_EQ(j["scale_m_per_unit"].get<double>(), k);
  EXPECT_NEAR(j["mesh_volume_mm3"].get<double>(), solid_volume(m.mesh) * 1e9, 1e-9);
  const double v = j["volume_mm3"].get<double>(), v_mesh = j["mesh_volume_mm3"].get<double>();
  EXPECT_LE(std::abs(v - v_mesh), j["volume_bound_mm3"].get<double>());
  EXPECT_GT(j["voxels_by_material"]["pulp"].get<long>(), 0);  // the Nerve group
  EXPECT_EQ(j["pulp_groups"], nlohmann::json::array({"Nerve"}));
  std::printf("chai3d at 64^3: %.2f mm^3 voxels vs %.2f mm^3 mesh\n", v, v_mesh);
}

TEST_F(VoxelizeCli, BadInputExitsTwoAndLeavesTheOutputAlone) {
  const std::string out = path("keep.json");
  write_file_atomic(out, "sentinel");
  const std::string stl = path("open.stl");
  write_file_atomic(stl,
                    "solid open\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n"
                    "   vertex 1 0 0\n   vertex 0 1 0\n  endloop\n endfacet\nendsolid open\n");
  struct Case {
    std::string args, message;
  };
  const Case cases[] = {
      {stl + " --resolution 32 --json " + out, "has no unit: give --scale K"},
      {stl + " --resolution 32 --scale 0.001 --json " + out, "3 boundary edges (holes)"},
      {stl + " --procedural --resolution 32 --json " + out, "either a MESH file or --procedural"},
      {"--procedural --resolution 100 --json " + out, "resolution 100: expected a power of two"},
      {"--procedural --resolution 32 --size-mm -3 --json " + out, "--size-mm"},
      {path("missing.obj") + " --resolution 32 --scale 1e-3 --json " + out, "cannot read"},
      {path("tooth.off") + " --resolution 32 --scale 1e-3 --json " + out, "unknown extension"},
      {"--procedural --resolution 32 --size-mm 10 --scale 2 --json " + out, "excludes"},
  };
  for (const Case& c : cases) {
    const CliResult r = run(c.args);
    EXPECT_EQ(r.status, 2) << c.args << "\n" << r.err;
    EXPECT_THAT(r.err, HasSubstr(c.message)) << c.args;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "one line: " << r.err;
    EXPECT_EQ(read_file(out), "sentinel") << c.args;
  }
}

}  // namespace
}  // namespace dentsim
