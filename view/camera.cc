#include "view/camera.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <numbers>

#include "view/view.h"

namespace dentsim::view {
namespace {
constexpr float kDeg = std::numbers::pi_v<float> / 180.0f;
}

Eigen::Vector3f OrbitCamera::eye() const {
  const float az = azimuth_deg * kDeg, el = elevation_deg * kDeg;
  return target + distance * Eigen::Vector3f(std::cos(el) * std::cos(az),
                                             std::cos(el) * std::sin(az), std::sin(el));
}

Eigen::Matrix4f OrbitCamera::view() const {
  const Eigen::Vector3f e = eye();
  const Eigen::Vector3f f = (target - e).normalized();
  Eigen::Vector3f up = Eigen::Vector3f::UnitZ();
  if (std::abs(f.dot(up)) > 0.999f) up = Eigen::Vector3f::UnitY();
  const Eigen::Vector3f s = f.cross(up).normalized();
  const Eigen::Vector3f u = s.cross(f);
  Eigen::Matrix4f m = Eigen::Matrix4f::Identity();
  m.block<1, 3>(0, 0) = s.transpose();
  m.block<1, 3>(1, 0) = u.transpose();
  m.block<1, 3>(2, 0) = -f.transpose();
  m(0, 3) = -s.dot(e);
  m(1, 3) = -u.dot(e);
  m(2, 3) = f.dot(e);
  return m;
}

Eigen::Matrix4f OrbitCamera::projection(float aspect) const {
  const float near = std::max(1e-4f, 0.05f * distance), far = 20.0f * distance;
  const float t = 1.0f / std::tan(0.5f * fov_y_deg * kDeg);
  Eigen::Matrix4f p = Eigen::Matrix4f::Zero();
  p(0, 0) = t / aspect;
  p(1, 1) = t;
  p(2, 2) = (far + near) / (near - far);
  p(2, 3) = 2.0f * far * near / (near - far);
  p(3, 2) = -1.0f;
  return p;
}

OrbitCamera camera_for(const VoxelGrid& grid) {
  // The bounds of the solid voxels' centres: a centre's coordinate d grows with its index d alone
  // (origin + h (i + 1/2), rounded, then cast: monotone), so the smallest and largest centres are
  // those of the extreme solid indices. One pass over the rows, each scanned from both ends.
  std::array<int, 3> lo_i = {grid.n, grid.n, grid.n}, hi_i = {-1, -1, -1};
  const std::size_t n = static_cast<std::size_t>(std::max(grid.n, 0));
  for (int k = 0; k < grid.n; ++k) {
    for (int j = 0; j < grid.n; ++j) {
      const std::uint8_t* row = grid.voxels.data() + grid.index(0, j, k);
      const std::uint8_t* first = std::find_if(row, row + n, [](std::uint8_t m) { return m != 0; });
      if (first == row + n) continue;
      const std::uint8_t* last =
          std::find_if(std::make_reverse_iterator(row + n), std::make_reverse_iterator(first),
                       [](std::uint8_t m) { return m != 0; })
              .base() -
          1;
      lo_i = {std::min(lo_i[0], static_cast<int>(first - row)), std::min(lo_i[1], j),
              std::min(lo_i[2], k)};
      hi_i = {std::max(hi_i[0], static_cast<int>(last - row)), std::max(hi_i[1], j),
              std::max(hi_i[2], k)};
    }
  }
  OrbitCamera cam;
  const float h = static_cast<float>(grid.voxel_size);
  if (hi_i[0] < 0) {
    cam.target = (grid.origin + 0.5 * grid.n * grid.voxel_size * Vec3::Ones()).cast<float>();
    cam.distance = std::max(1e-3f, 2.0f * h * grid.n);
    return cam;
  }
  const Eigen::Vector3f lo = grid.center(lo_i[0], lo_i[1], lo_i[2]).cast<float>();
  const Eigen::Vector3f hi = grid.center(hi_i[0], hi_i[1], hi_i[2]).cast<float>();
  cam.target = 0.5f * (lo + hi);
  const float radius = 0.5f * (hi - lo).norm() + h;
  cam.distance = radius / std::sin(0.5f * 0.8f * cam.fov_y_deg * kDeg);
  return cam;
}

OrbitCamera camera_for(const VoxelGrid& grid, const ViewOptions& options) {
  OrbitCamera cam = camera_for(grid);
  cam.azimuth_deg = options.azimuth_deg;
  cam.elevation_deg = options.elevation_deg;
  cam.distance /= std::max(0.05f, options.zoom);
  return cam;
}

}  // namespace dentsim::view
