// Checks of the view's pictures shared by tests/view/: reading a PNG back, the silhouette the
// tooth must cover (an oracle independent of the mesher and of GL: the solid voxels' boxes
// projected with the view's camera), and colour classes.
#pragma once

#include <png.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "reference/tooth/materials.h"
#include "tooth_io/render_png.h"
#include "view/camera.h"

namespace dentsim::view::testing {

// Reads an 8-bit RGB(A) PNG into an RgbImage (alpha dropped); width 0 on failure.
inline RgbImage read_png(const std::string& path) {
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  RgbImage out;
  if (!png_image_begin_read_from_file(&image, path.c_str())) return out;
  image.format = PNG_FORMAT_RGB;
  out.rgb.resize(PNG_IMAGE_SIZE(image));
  if (!png_image_finish_read(&image, nullptr, out.rgb.data(), 0, nullptr)) {
    png_image_free(&image);
    return {};
  }
  out.width = static_cast<int>(image.width);
  out.height = static_cast<int>(image.height);
  return out;
}

inline bool is_background(const RgbImage& img, int x, int y) {
  const std::uint8_t* p = &img.rgb[3 * (static_cast<std::size_t>(y) * img.width + x)];
  return p[0] == kBackgroundRgb[0] && p[1] == kBackgroundRgb[1] && p[2] == kBackgroundRgb[2];
}

// The pixels covered by the solid voxels of `grid` seen through `cam` in a width x height picture:
// each solid voxel with an empty face neighbour fills the bounding rectangle of its 8 projected
// corners (a slight over-cover at the edges: up to one pixel around the silhouette).
inline std::vector<std::uint8_t> voxel_silhouette(const VoxelGrid& grid, const OrbitCamera& cam,
                                                  int width, int height) {
  std::vector<std::uint8_t> mask(static_cast<std::size_t>(width) * height, 0);
  const Eigen::Matrix4f m =
      cam.projection(static_cast<float>(width) / static_cast<float>(height)) * cam.view();
  const float h = static_cast<float>(grid.voxel_size);
  for (int k = 0; k < grid.n; ++k) {
    for (int j = 0; j < grid.n; ++j) {
      for (int i = 0; i < grid.n; ++i) {
        if (!grid.solid(i, j, k)) continue;
        if (grid.solid(i - 1, j, k) && grid.solid(i + 1, j, k) && grid.solid(i, j - 1, k) &&
            grid.solid(i, j + 1, k) && grid.solid(i, j, k - 1) && grid.solid(i, j, k + 1)) {
          continue;
        }
        float x0 = 1e9f, x1 = -1e9f, y0 = 1e9f, y1 = -1e9f;
        for (int c = 0; c < 8; ++c) {
          const Eigen::Vector3f p =
              grid.origin.cast<float>() +
              h * Eigen::Vector3f(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
          const Eigen::Vector4f q = m * Eigen::Vector4f(p.x(), p.y(), p.z(), 1.0f);
          const float px = (q.x() / q.w() + 1.0f) * 0.5f * width;
          const float py = (1.0f - q.y() / q.w()) * 0.5f * height;
          x0 = std::min(x0, px);
          x1 = std::max(x1, px);
          y0 = std::min(y0, py);
          y1 = std::max(y1, py);
        }
        // Pixels whose centre lies inside the rectangle.
        for (int y = std::max(0, static_cast<int>(std::ceil(y0 - 0.5f)));
             y <= std::min(height - 1, static_cast<int>(std::floor(y1 - 0.5f))); ++y) {
          for (int x = std::max(0, static_cast<int>(std::ceil(x0 - 0.5f)));
               x <= std::min(width - 1, static_cast<int>(std::floor(x1 - 0.5f))); ++x) {
            mask[static_cast<std::size_t>(y) * width + x] = 1;
          }
        }
      }
    }
  }
  return mask;
}

// The material whose shaded colour pixel c is: c = a rgb_m + s (a > 0.25: lit; s: grey specular
// highlight), judged on the channel differences (c0 - c1, c1 - c2), which the grey part leaves
// unchanged; the material with the smallest residual within `tol` levels, else 0 (background,
// tool, overlay).
inline std::uint8_t classify(const std::uint8_t* c, double tol = 6.0) {
  const double d1 = double(c[0]) - c[1], d2 = double(c[1]) - c[2];
  std::uint8_t best = 0;
  double best_r = tol;
  for (std::uint8_t m = 1; m < kMaterialCount; ++m) {
    const std::uint8_t* base = material_properties(m).rgb;
    const double b1 = double(base[0]) - base[1], b2 = double(base[1]) - base[2];
    const double a = (d1 * b1 + d2 * b2) / (b1 * b1 + b2 * b2);
    if (a < 0.25) continue;
    const double r = std::max(std::abs(d1 - a * b1), std::abs(d2 - a * b2));
    if (r <= best_r) {
      best_r = r;
      best = m;
    }
  }
  return best;
}

}  // namespace dentsim::view::testing
