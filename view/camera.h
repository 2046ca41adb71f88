// The view's camera (issue #19): an orbit camera around a target point, perspective projection.
// Frames: world {O} with +z up (the crown axis, as the voxel pictures); azimuth is measured in
// the x-y plane from +x towards +y, elevation above that plane. Matrices are column-major
// (OpenGL's), mapping world [m] -> eye -> clip.
#pragma once

#include <Eigen/Core>

#include "reference/tooth/voxel_grid.h"

namespace dentsim::view {

struct OrbitCamera {
  Eigen::Vector3f target = Eigen::Vector3f::Zero();  // orbit centre [m]
  float distance = 0.05f;                            // eye to target [m]
  float azimuth_deg = 45.0f;
  float elevation_deg = 55.0f;
  float fov_y_deg = 30.0f;

  Eigen::Vector3f eye() const;
  Eigen::Matrix4f view() const;
  Eigen::Matrix4f projection(float aspect) const;
};

// The default camera for a tooth: aimed at the centre of its solid voxels' bounding box, far enough
// that the box's bounding sphere fills ~80 % of the picture's height. An empty grid: the grid's
// centre.
OrbitCamera camera_for(const VoxelGrid& grid);
// The same, turned to the options' azimuth/elevation and moved closer by their zoom.
struct ViewOptions;
OrbitCamera camera_for(const VoxelGrid& grid, const ViewOptions& options);

}  // namespace dentsim::view
