// The tooth's field over a block of voxel centres, for the view's mesher (view/surface_mesh.h;
// issue #30: the pictures of a 512^3 tooth mesh phi at every voxel centre of ~10^5 blocks).
// SampledField::value() locates each point's cell and reads its 8 samples through the brick
// index, and computes the gradient too; over a box of voxel centres the cells are located once
// per axis (a centre's coordinate along an axis depends on its index along that axis only) and
// the samples they need read once, and only the value is interpolated. The values are value()'s
// bit for bit: the same operations in the same order (tests/view/surface_mesh_test.cc).
#pragma once

#include <vector>

#include "reference/tooth/sampled_field.h"
#include "reference/tooth/voxel_grid.h"

namespace dentsim::view {

// The stored samples of the box [lo, hi] (inclusive lattice coordinates in
// [0, samples_per_axis())), x fastest: out[(x - lo_x) + w_x ((y - lo_y) + w_y (z - lo_z))] =
// field.at(x, y, z), w = hi - lo + 1.
void read_field_samples(const SampledField& field, const int lo[3], const int hi[3], float* out);

// phi at the voxel centres (i, j, k) of `grid` (the field's tooth grid, placed as the field is)
// of the box [c0, c1] (voxel indices, inclusive; beyond the grid too), x fastest:
// out[(i - c0_x) + w_x ((j - c0_y) + w_y (k - c0_z))] = float(field.value(grid.center(i, j, k)))
// bit for bit, w = c1 - c0 + 1. `scratch` holds the samples read (resized).
void field_values_at_voxel_centres(const SampledField& field, const VoxelGrid& grid,
                                   const int c0[3], const int c1[3], std::vector<float>* scratch,
                                   float* out);

}  // namespace dentsim::view
