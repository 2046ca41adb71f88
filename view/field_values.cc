// The tooth's field over a block of voxel centres (view/field_values.h).
#include "view/field_values.h"

#include <algorithm>
#include <cstddef>

namespace dentsim::view {

void read_field_samples(const SampledField& field, const int lo[3], const int hi[3], float* out) {
  for (int z = lo[2]; z <= hi[2]; ++z) {
    for (int y = lo[1]; y <= hi[1]; ++y) {
      for (int x = lo[0]; x <= hi[0]; ++x) *out++ = field.at(x, y, z);
    }
  }
}

void field_values_at_voxel_centres(const SampledField& field, const VoxelGrid& grid,
                                   const int c0[3], const int c1[3], std::vector<float>* scratch,
                                   float* out) {
  int w[3];
  for (int a = 0; a < 3; ++a) w[a] = c1[a] - c0[a] + 1;
  if (w[0] <= 0 || w[1] <= 0 || w[2] <= 0) return;
  const int m = field.samples_per_axis();
  if (m < 2) {  // SampledField::sample's value without a lattice
    std::fill(out, out + static_cast<std::size_t>(w[0]) * w[1] * w[2], 0.0f);
    return;
  }
  // SampledField::sample's cell and local coordinates (its locate()): per axis a,
  // u = clamp((x_a - origin_a) / H, 0, m - 1), cell min(floor(u), m - 2), t = u - cell, with
  // origin = sample 0's position (origin + H * 0, the same number) and x = grid.center(...),
  // whose component a is the same for every centre with the same index along a.
  const Vec3 origin = field.sample_position(0, 0, 0);
  const double spacing = field.spacing();
  const int w_max = std::max({w[0], w[1], w[2]});
  std::vector<int> cell(3 * static_cast<std::size_t>(w_max));
  std::vector<double> local(3 * static_cast<std::size_t>(w_max));
  int lo[3] = {m, m, m}, hi[3] = {-1, -1, -1};
  for (int q = 0; q < w_max; ++q) {
    const Vec3 x = grid.center(c0[0] + std::min(q, w[0] - 1), c0[1] + std::min(q, w[1] - 1),
                               c0[2] + std::min(q, w[2] - 1));
    for (int a = 0; a < 3; ++a) {
      if (q >= w[a]) continue;
      const double u = std::clamp((x[a] - origin[a]) / spacing, 0.0, static_cast<double>(m - 1));
      const int s = std::min(static_cast<int>(u), m - 2);
      const std::size_t at = static_cast<std::size_t>(a) * w_max + q;
      cell[at] = s;
      local[at] = u - s;
      lo[a] = std::min(lo[a], s);
      hi[a] = std::max(hi[a], s + 1);
    }
  }
  const std::size_t step_y = static_cast<std::size_t>(hi[0] - lo[0] + 1);
  const std::size_t step_z = step_y * static_cast<std::size_t>(hi[1] - lo[1] + 1);
  scratch->resize(step_z * static_cast<std::size_t>(hi[2] - lo[2] + 1));
  read_field_samples(field, lo, hi, scratch->data());
  const float* box = scratch->data();
  for (int k = 0; k < w[2]; ++k) {
    const std::size_t zk = 2 * static_cast<std::size_t>(w_max) + k;
    const double tz = local[zk];
    const std::size_t oz = static_cast<std::size_t>(cell[zk] - lo[2]) * step_z;
    for (int j = 0; j < w[1]; ++j) {
      const std::size_t yj = static_cast<std::size_t>(w_max) + j;
      const double ty = local[yj];
      const std::size_t oyz = oz + static_cast<std::size_t>(cell[yj] - lo[1]) * step_y;
      for (int i = 0; i < w[0]; ++i) {
        const double tx = local[static_cast<std::size_t>(i)];
        const float* c = box + oyz + static_cast<std::size_t>(cell[static_cast<std::size_t>(i)] - lo[0]);
        // SampledField::sample's value: along x on the four x-edges (dy, dz), then y, then z.
        double ex[2][2];
        for (int dz = 0; dz < 2; ++dz) {
          for (int dy = 0; dy < 2; ++dy) {
            const double v0 = c[dy * step_y + dz * step_z];
            const double v1 = c[1 + dy * step_y + dz * step_z];
            ex[dy][dz] = v0 + tx * (v1 - v0);
          }
        }
        const double ey0 = ex[0][0] + ty * (ex[1][0] - ex[0][0]);
        const double ey1 = ex[0][1] + ty * (ex[1][1] - ex[0][1]);
        *out++ = static_cast<float>(ey0 + tz * (ey1 - ey0));
      }
    }
  }
}

}  // namespace dentsim::view
