// The load-time stability check (sim/scene_stability.h): the built-in scenes and every scene
// file the tests ship pass it; explicit Euler outside K T < b (the coupling, its rotation, the
// proxy in contact) is refused naming the field and the numbers; the bound itself is exact (a
// hair inside passes, a hair outside fails); PMI scenes are never refused.
#include "sim/scene_stability.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "reference/core/io.h"

namespace dentsim {
namespace {

namespace fs = std::filesystem;

TEST(SceneStability, BuiltinAndShippedScenesPass) {
  for (const std::string& name : builtin_scene_names()) {
    EXPECT_TRUE(scene_stability_problems(load_scene(name)).empty()) << name;
  }
  int files = 0;
  for (const char* dir : {"/tests/cli/data", "/tests/validation/data"}) {
    for (const auto& e : fs::directory_iterator(std::string(DENTSIM_SOURCE_DIR) + dir)) {
      const std::string path = e.path().string();
      if (e.path().extension() != ".json") continue;
      Scene s;
      try {
        s = load_scene(path);
      } catch (const InputError&) {
        continue;  // not a scene file (a stored report)
      }
      ++files;
      const bool meant_unstable = path.find("harsh32_explicit") != std::string::npos;
      EXPECT_EQ(scene_stability_problems(s).empty(), !meant_unstable) << path;
    }
  }
  EXPECT_GE(files, 8);
}

TEST(SceneStability, ExplicitOutsideKTOverBIsRefusedNamingTheField) {
  Scene s = load_scene("drill");
  s.method.method = Method::kExplicitVc;
  s.tick_hz = 1000.0;
  s.tooth.k_tooth = 0.0;
  s.tooth.b_tooth = 0.0;
  s.method.proxy.damping_lin = 0.0;
  // The coupling: k_vc T < b_vc exactly at the bound.
  s.method.coupling.b_lin = 4.0;
  s.method.coupling.k_lin = 3999.0;
  EXPECT_TRUE(scene_stability_problems(s).empty());
  s.method.coupling.k_lin = 4001.0;
  std::vector<std::string> p = scene_stability_problems(s);
  ASSERT_FALSE(p.empty());
  EXPECT_EQ(p.front().rfind("method.k_vc_n_per_m: ", 0), 0u) << p.front();
  EXPECT_NE(p.front().find("K T < b"), std::string::npos) << p.front();
  // The proxy in contact: k_vc + k_tooth.
  s.method.coupling.k_lin = 1000.0;
  s.tooth.k_tooth = 12000.0;
  s.tooth.b_tooth = 5.0;
  p = scene_stability_problems(s);
  ASSERT_EQ(p.size(), 1u);
  EXPECT_EQ(p.front().rfind("tooth.k_tooth_n_per_m: ", 0), 0u) << p.front();
  s.tooth.b_tooth = 9.1;  // 13000 N/m x 1 ms = 13 < 4 + 9.1
  EXPECT_TRUE(scene_stability_problems(s).empty());
  // The rotation.
  s.method.coupling.k_ang = 2.0;
  s.method.coupling.b_ang = 0.001;
  p = scene_stability_problems(s);
  ASSERT_EQ(p.size(), 1u);
  EXPECT_EQ(p.front().rfind("method.k_vc_ang_n_m_per_rad: ", 0), 0u) << p.front();
  // The message users get names the scene, the field and --force.
  try {
    check_scene_stability(s);
    ADD_FAILURE() << "not refused";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.rfind(s.origin + ": method.k_vc_ang_n_m_per_rad: ", 0), 0u) << m;
    EXPECT_NE(m.find("--force"), std::string::npos) << m;
  }
  // PMI integrates the same gains implicitly: nothing to refuse.
  s.method.method = Method::kPmiVc;
  EXPECT_TRUE(scene_stability_problems(s).empty());
}

}  // namespace
}  // namespace dentsim
