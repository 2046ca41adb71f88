#include "tooth_io/render_png.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "reference/core/io.h"
#include "reference/tooth/materials.h"

namespace dentsim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kAmbient = 0.35;

struct Scene {
  const VoxelGrid* grid;
  std::array<int, 3> lo, hi;  // solid bounding box (voxel indices, inclusive)
  Vec3 center;                // its world centre
  bool cut = false;
  Vec3 cut_a, cut_b;  // remove voxels with (p - center) . cut_a > 0 and . cut_b > 0
};

bool visible(const Scene& s, int i, int j, int k) {
  if (!s.grid->solid(i, j, k)) return false;
  if (!s.cut) return true;
  const Vec3 d = s.grid->center(i, j, k) - s.center;
  return !(d.dot(s.cut_a) > 0 && d.dot(s.cut_b) > 0);
}

// First visible voxel along o + t dir (dir unit); returns its material and the entry normal.
std::uint8_t cast(const Scene& s, const Vec3& o, const Vec3& dir, Vec3* normal) {
  const VoxelGrid& g = *s.grid;
  const double h = g.voxel_size;
  // Clip the ray to the solid's box [lo, hi + 1] in voxel units.
  const Vec3 q = (o - g.origin) / h;
  double t0 = 0, t1 = std::numeric_limits<double>::infinity();
  int entry_axis = 0;
  for (int a = 0; a < 3; ++a) {
    const double lo = s.lo[a], hi = s.hi[a] + 1.0;
    if (dir[a] == 0) {
      if (q[a] < lo || q[a] > hi) return kEmpty;
      continue;
    }
    double ta = (lo - q[a]) / dir[a], tb = (hi - q[a]) / dir[a];
    if (ta > tb) std::swap(ta, tb);
    if (ta > t0) {
      t0 = ta;
      entry_axis = a;
    }
    t1 = std::min(t1, tb);
  }
  if (t0 > t1) return kEmpty;
  const Vec3 p = q + dir * (t0 + 1e-9);
  std::array<int, 3> v, step;
  std::array<double, 3> t_max, t_delta;
  for (int a = 0; a < 3; ++a) {
    v[a] = std::clamp(static_cast<int>(std::floor(p[a])), s.lo[a], s.hi[a]);
    step[a] = dir[a] > 0 ? 1 : -1;
    t_delta[a] = dir[a] != 0 ? std::abs(1.0 / dir[a]) : std::numeric_limits<double>::infinity();
    const double next = dir[a] > 0 ? v[a] + 1.0 : double(v[a]);
    t_max[a] =
        dir[a] != 0 ? (t0 + (next - p[a]) / dir[a]) : std::numeric_limits<double>::infinity();
  }
  int axis = entry_axis;
  while (true) {
    if (visible(s, v[0], v[1], v[2])) {
      *normal = Vec3::Zero();
      (*normal)[axis] = -step[axis];
      return g.at(v[0], v[1], v[2]);
    }
    axis = t_max[0] < t_max[1] ? (t_max[0] < t_max[2] ? 0 : 2) : (t_max[1] < t_max[2] ? 1 : 2);
    v[axis] += step[axis];
    if (v[axis] < s.lo[axis] || v[axis] > s.hi[axis]) return kEmpty;
    t_max[axis] += t_delta[axis];
  }
}

}  // namespace

RgbImage render_voxels(const VoxelGrid& grid, const RenderOptions& options) {
  if (options.panel_size < 8) throw InputError("picture size: expected at least 8 pixels");
  Scene s;
  s.grid = &grid;
  s.lo = {grid.n, grid.n, grid.n};
  s.hi = {-1, -1, -1};
  for (int k = 0; k < grid.n; ++k) {
    for (int j = 0; j < grid.n; ++j) {
      for (int i = 0; i < grid.n; ++i) {
        if (!grid.solid(i, j, k)) continue;
        const std::array<int, 3> p = {i, j, k};
        for (int a = 0; a < 3; ++a) {
          s.lo[a] = std::min(s.lo[a], p[a]);
          s.hi[a] = std::max(s.hi[a], p[a]);
        }
      }
    }
  }
  if (s.hi[0] < 0) throw InputError("picture: the voxel tooth is empty; nothing to draw");
  const double h = grid.voxel_size;
  const Vec3 box_min = grid.origin + h * Vec3(s.lo[0], s.lo[1], s.lo[2]);
  const Vec3 box_max = grid.origin + h * Vec3(s.hi[0] + 1, s.hi[1] + 1, s.hi[2] + 1);
  s.center = 0.5 * (box_min + box_max);
  const double radius = 0.5 * (box_max - box_min).norm();

  // Camera: up axis u, horizontal grid axes e1, e2 (the grid axes other than the one closest to u).
  const Vec3 u = options.up.normalized();
  int up_axis = 0;
  u.cwiseAbs().maxCoeff(&up_axis);
  const Vec3 e1 = Vec3::Unit((up_axis + 1) % 3), e2 = Vec3::Unit((up_axis + 2) % 3);
  const double az = options.azimuth_deg * kPi / 180, el = options.elevation_deg * kPi / 180;
  const Vec3 horizontal = std::cos(az) * e1 + std::sin(az) * e2;
  const Vec3 to_camera = (std::cos(el) * horizontal + std::sin(el) * u).normalized();
  const Vec3 forward = -to_camera;
  const Vec3 right = forward.cross(u).normalized();
  const Vec3 cam_up = right.cross(forward);
  const Vec3 light = (to_camera + 0.6 * u + 0.4 * right).normalized();
  // The cut-away removes the quarter whose two horizontal axes point towards the camera.
  s.cut_a = (horizontal.dot(e1) >= 0 ? 1.0 : -1.0) * e1;
  s.cut_b = (horizontal.dot(e2) >= 0 ? 1.0 : -1.0) * e2;

  const int w = options.panel_size;
  RgbImage img;
  img.width = 2 * w;
  img.height = w;
  img.rgb.resize(static_cast<std::size_t>(img.width) * img.height * 3);
  img.material.assign(static_cast<std::size_t>(img.width) * img.height, kEmpty);
  for (int panel = 0; panel < 2; ++panel) {
    s.cut = panel == 1;
    for (int py = 0; py < w; ++py) {
      for (int px = 0; px < w; ++px) {
        const double sx = ((px + 0.5) / w - 0.5) * 2 * radius;
        const double sy = (0.5 - (py + 0.5) / w) * 2 * radius;
        const Vec3 o = s.center + sx * right + sy * cam_up - 2 * radius * forward;
        Vec3 n;
        const std::uint8_t m = cast(s, o, forward, &n);
        const std::size_t pix = static_cast<std::size_t>(py) * img.width + panel * w + px;
        img.material[pix] = m;
        for (int c = 0; c < 3; ++c) {
          if (m == kEmpty) {
            img.rgb[3 * pix + c] = kBackgroundRgb[c];
          } else {
            const double shade = kAmbient + (1 - kAmbient) * std::max(0.0, n.dot(light));
            img.rgb[3 * pix + c] =
                static_cast<std::uint8_t>(std::lround(material_properties(m).rgb[c] * shade));
          }
        }
      }
    }
  }
  return img;
}

}  // namespace dentsim
