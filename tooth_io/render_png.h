// A picture of the voxel tooth (issue #4, `dentsim voxelize --png`): software ray casting of the
// voxel grid into an RGB buffer. The PNG encoding itself is in cli/png_writer.h (the dentsim
// binary links libpng; the reference library does not).
//
// Two panels side by side, the same orthographic camera:
//  - left: the whole tooth, so the shape (cusps, fissures, roots) shows;
//  - right: a cut-away: the quarter of the tooth facing the camera is removed along two grid
//    planes through the centre of the solid's bounding box, so enamel cap, dentin and pulp show as
//    layers.
// Each pixel's ray walks the grid voxel by voxel (Amanatides & Woo, "A Fast Voxel Traversal
// Algorithm for Ray Tracing", Eurographics 1987) to the first solid voxel; the face it enters
// through gives the normal; colour = material colour (materials.h) x (ambient + diffuse), with a
// key light from over the camera's shoulder.
#pragma once

#include <cstdint>
#include <vector>

#include "reference/core/types.h"
#include "reference/tooth/voxel_grid.h"

namespace dentsim {

struct RgbImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;       // width * height * 3, row-major from the top-left
  std::vector<std::uint8_t> material;  // width * height material id per pixel (0: background)
};

struct RenderOptions {
  int panel_size = 512;         // each panel is panel_size x panel_size pixels
  double azimuth_deg = -60.0;   // camera direction around the up axis, from the first other axis
  double elevation_deg = 25.0;  // camera height above the horizontal plane
  Vec3 up = Vec3::UnitZ();      // world direction shown upwards (the crown axis)
};

// Background colour of the pictures.
inline constexpr std::uint8_t kBackgroundRgb[3] = {236, 239, 243};

// Renders both panels; throws InputError if the grid has no solid voxel or panel_size < 8.
RgbImage render_voxels(const VoxelGrid& grid, const RenderOptions& options = {});

}  // namespace dentsim
