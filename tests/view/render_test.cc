// Tests of the headless renderer (view/view.h render_offscreen, EGL surfaceless): the tooth's
// silhouette covers the pixels its voxels project to, its materials show in their colours (the
// pulp only in the cut-away), drilling changes the picture where the voxels were removed and
// nowhere else, and the tool is drawn where the snapshot puts it.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "tests/view/picture_check.h"
#include "tooth_io/procedural_molar.h"
#include "view/view.h"

namespace dentsim::view {
namespace {

using testing::classify;
using testing::is_background;
using testing::voxel_silhouette;

class Render : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    if (!headless_available(&why)) GTEST_SKIP() << why;
  }
  static const VoxelGrid& tooth() {
    static const VoxelGrid g = voxelize_procedural_molar(MolarParams{}, 64);
    return g;
  }
  static ViewOptions options() {
    ViewOptions o;
    o.width = 320;
    o.height = 240;
    o.overlay = false;
    o.tool = false;
    return o;
  }
};

// camera_for's definition written plainly: the component-wise bounds of every solid voxel's
// centre (as floats), the camera aimed at their middle.
OrbitCamera plain_camera_for(const VoxelGrid& grid) {
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(1e30f), hi = Eigen::Vector3f::Constant(-1e30f);
  for (int k = 0; k < grid.n; ++k) {
    for (int j = 0; j < grid.n; ++j) {
      for (int i = 0; i < grid.n; ++i) {
        if (!grid.solid(i, j, k)) continue;
        const Eigen::Vector3f c = grid.center(i, j, k).cast<float>();
        lo = lo.cwiseMin(c);
        hi = hi.cwiseMax(c);
      }
    }
  }
  OrbitCamera cam;
  const float h = static_cast<float>(grid.voxel_size);
  if (lo.x() > hi.x()) {
    cam.target = (grid.origin + 0.5 * grid.n * grid.voxel_size * Vec3::Ones()).cast<float>();
    cam.distance = std::max(1e-3f, 2.0f * h * grid.n);
    return cam;
  }
  cam.target = 0.5f * (lo + hi);
  const float radius = 0.5f * (hi - lo).norm() + h;
  constexpr float kDeg = std::numbers::pi_v<float> / 180.0f;
  cam.distance = radius / std::sin(0.5f * 0.8f * cam.fov_y_deg * kDeg);
  return cam;
}

// camera_for scans each row from its ends for the extreme solid indices (issue #30: four
// pictures of a 512^3 tooth): the same camera, bit for bit, as the plain bounds of every solid
// centre, on the molar, on scattered voxels (one of them alone in its row, at a grid corner) and
// on an empty grid.
TEST(CameraFor, IsThePlainBoundsOfTheSolidCentres) {
  std::vector<VoxelGrid> grids = {voxelize_procedural_molar(MolarParams{}, 64)};
  VoxelGrid scattered(32, Vec3(-1.3e-3, 0.7e-3, 2.1e-3), 0.37e-3);
  scattered.set(5, 9, 30, kDentin);
  scattered.set(17, 0, 12, kEnamel);
  scattered.set(31, 31, 31, kPulp);
  scattered.set(3, 20, 4, kCaries);
  grids.push_back(scattered);
  grids.push_back(VoxelGrid(16, Vec3(1e-3, 2e-3, 3e-3), 1e-4));
  for (const VoxelGrid& g : grids) {
    const OrbitCamera a = camera_for(g), b = plain_camera_for(g);
    EXPECT_EQ(a.target, b.target);
    EXPECT_EQ(a.distance, b.distance);
  }
}

TEST_F(Render, SilhouetteCoversTheProjectedVoxels) {
  const ViewOptions o = options();
  const RgbImage img = render_offscreen(tooth(), nullptr, o);
  ASSERT_EQ(img.width, o.width);
  ASSERT_EQ(img.height, o.height);
  const std::vector<std::uint8_t> expected =
      voxel_silhouette(tooth(), camera_for(tooth(), o), o.width, o.height);
  long both = 0, only_expected = 0, only_drawn = 0;
  for (int y = 0; y < o.height; ++y) {
    for (int x = 0; x < o.width; ++x) {
      const bool drawn = !is_background(img, x, y);
      const bool want = expected[static_cast<std::size_t>(y) * o.width + x] != 0;
      both += drawn && want;
      only_expected += want && !drawn;
      only_drawn += drawn && !want;
    }
  }
  const double iou = static_cast<double>(both) / (both + only_expected + only_drawn);
  std::printf("silhouette: %ld pixels in both, %ld only expected, %ld only drawn, IoU %.3f\n", both,
              only_expected, only_drawn, iou);
  // The tooth spans ~190 px (64 voxels, ~3 px each); the smooth surface lies within half a voxel
  // inside the voxel boxes and the boxes' rectangles over-cover by up to a pixel: the
  // disagreement is a rim of ~1.5 px around a ~500 px outline, < 10 % of the ~9 000 px area.
  // Measured: IoU 0.916, nothing drawn outside the voxels.
  ASSERT_GT(both, 6000);
  EXPECT_GT(iou, 0.90);
  EXPECT_LT(only_drawn, only_expected) << "the surface is inside the voxel hull";
}

TEST_F(Render, MaterialsShowInTheirColoursAndThePulpOnlyInTheCutAway) {
  ViewOptions o = options();
  auto count = [](const RgbImage& img) {
    std::array<long, kMaterialCount> c{};
    for (std::size_t p = 0; p < img.rgb.size(); p += 3) ++c[classify(&img.rgb[p])];
    return c;
  };
  const auto whole = count(render_offscreen(tooth(), nullptr, o));
  o.cutaway = true;
  const auto cut = count(render_offscreen(tooth(), nullptr, o));
  std::printf("whole: enamel %ld dentin %ld pulp %ld; cut: enamel %ld dentin %ld pulp %ld\n",
              whole[1], whole[2], whole[3], cut[1], cut[2], cut[3]);
  EXPECT_GT(whole[kEnamel], 2000);
  EXPECT_GT(whole[kDentin], 1000);
  EXPECT_LT(whole[kPulp], 10) << "the pulp is enclosed";
  EXPECT_GT(cut[kPulp], 200);
  EXPECT_GT(cut[kDentin], whole[kDentin]);
}

TEST_F(Render, DrillingChangesThePictureOnlyWhereVoxelsWereRemoved) {
  ViewOptions o = options();
  o.elevation_deg = 70.0f;  // look down on the occlusal surface
  VoxelGrid drilled = tooth();
  int top = -1;
  for (int k = 0; k < drilled.n; ++k) {
    if (drilled.solid(32, 32, k)) top = k;
  }
  ASSERT_GT(top, 4);
  VoxelGrid removed(drilled.n, drilled.origin, drilled.voxel_size);
  for (int k = top - 4; k <= top; ++k) {
    for (int j = 28; j <= 36; ++j) {
      for (int i = 28; i <= 36; ++i) {
        if (std::hypot(i - 32, j - 32, k - top) <= 4.0 && drilled.solid(i, j, k)) {
          removed.set(i, j, k, drilled.at(i, j, k));
          drilled.set(i, j, k, kEmpty);
        }
      }
    }
  }
  const RgbImage a = render_offscreen(tooth(), nullptr, o);
  const RgbImage b = render_offscreen(drilled, nullptr, o);
  // The camera (aimed at the solid's bounding box) is the same for both: the cavity is below the
  // cusp tips.
  ASSERT_EQ(camera_for(tooth(), o).target, camera_for(drilled, o).target);
  // A removed voxel moves the surface within 3 voxels of it (quads of inside centres within 2,
  // their vertices within 1 more: view/surface_mesh.h): the pixels of every voxel box within 3
  // voxels of a removed one, solid or not.
  VoxelGrid reach(drilled.n, drilled.origin, drilled.voxel_size);
  for (int k = 0; k < drilled.n; ++k) {
    for (int j = 0; j < drilled.n; ++j) {
      for (int i = 0; i < drilled.n; ++i) {
        if (!removed.solid(i, j, k)) continue;
        for (int dz = -3; dz <= 3; ++dz) {
          for (int dy = -3; dy <= 3; ++dy) {
            for (int dx = -3; dx <= 3; ++dx) {
              if (reach.inside(i + dx, j + dy, k + dz)) reach.set(i + dx, j + dy, k + dz, 1);
            }
          }
        }
      }
    }
  }
  const std::vector<std::uint8_t> near =
      voxel_silhouette(reach, camera_for(tooth(), o), o.width, o.height);
  long changed_inside = 0, changed_outside = 0;
  for (int y = 0; y < o.height; ++y) {
    for (int x = 0; x < o.width; ++x) {
      const std::size_t p = static_cast<std::size_t>(y) * o.width + x;
      bool differs = false;
      for (int c = 0; c < 3; ++c) differs = differs || a.rgb[3 * p + c] != b.rgb[3 * p + c];
      (near[p] ? changed_inside : changed_outside) += differs;
    }
  }
  std::printf("drilling changed %ld pixels near the cavity, %ld elsewhere\n", changed_inside,
              changed_outside);
  EXPECT_GT(changed_inside, 20);
  EXPECT_EQ(changed_outside, 0);
}

TEST_F(Render, ToolIsDrawnAtTheSnapshotsPose) {
  ViewOptions o = options();
  o.tool = true;
  TickSnapshot tick;
  tick.tick = 10;
  tick.tool_radius_m = 0.5e-3;
  const OrbitCamera cam = camera_for(tooth(), o);
  // The tool beside the tooth, on the camera's right, at the target's height.
  const Eigen::Vector3f eye = cam.eye();
  const Eigen::Vector3f right = (cam.target - eye).cross(Eigen::Vector3f::UnitZ()).normalized();
  tick.device.x =
      (cam.target + 0.35f * cam.distance * std::tan(0.5f * cam.fov_y_deg * 3.14159f / 180) * right)
          .cast<double>();
  tick.proxy = tick.device;
  const RgbImage without = render_offscreen(tooth(), nullptr, o);
  const RgbImage with = render_offscreen(tooth(), &tick, o);
  // Where the tip centre projects.
  const Eigen::Matrix4f m = cam.projection(static_cast<float>(o.width) / o.height) * cam.view();
  const Eigen::Vector4f q =
      m * Eigen::Vector4f(tick.device.x.x(), tick.device.x.y(), tick.device.x.z(), 1.0f);
  const int px = static_cast<int>((q.x() / q.w() + 1.0f) * 0.5f * o.width);
  const int py = static_cast<int>((1.0f - q.y() / q.w()) * 0.5f * o.height);
  ASSERT_TRUE(px > 0 && px < o.width && py > 0 && py < o.height);
  EXPECT_TRUE(is_background(without, px, py));
  EXPECT_FALSE(is_background(with, px, py));
  EXPECT_EQ(classify(&with.rgb[3 * (static_cast<std::size_t>(py) * o.width + px)]), 0)
      << "steel grey, not a tooth colour";
}

}  // namespace
}  // namespace dentsim::view
