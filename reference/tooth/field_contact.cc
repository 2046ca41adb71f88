// The "field" contact model (reference/tooth/field_contact.h). Beyond the thesis.
#include "reference/tooth/field_contact.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdlib>

#include "reference/core/io.h"
#include "reference/tooth/surface_proxy_core.h"

namespace dentsim {

SignedDistance FieldSolid::distance(const Vec3& x, double reach) const {
  if (field_.deep_inside(x)) return signed_distance(tooth_, x, reach);
  const FieldSample s = field_.sample(x);
  SignedDistance out;
  if (s.value >= reach) {
    out.phi = reach;
    out.found = false;
    return out;
  }
  out.phi = s.value;
  out.found = true;
  const double g = s.gradient.norm();
  out.nearest = g > 0.0 ? Vec3(x - (s.value / g) * s.gradient) : x;
  return out;
}

Vec3 FieldSolid::normal(const Vec3& x, const SignedDistance& sd) const {
  if (!field_.deep_inside(x)) {
    const Vec3 grad = field_.sample(x).gradient;
    const double g = grad.norm();
    if (g > 0.0) return grad / g;
  }
  // No gradient of the field here: the voxel distance's direction.
  const SignedDistance exact =
      field_.deep_inside(x) ? sd : signed_distance(tooth_, x, tooth_.grid().voxel_size * tooth_.grid().n);
  return distance_gradient(tooth_, x, exact);
}

bool edit_field_for_removed_voxels(SampledField* field, const VoxelTooth& tooth,
                                   std::span<const std::size_t> removed, SignedDistanceFn sd,
                                   FieldEditStats* stats) {
  const VoxelGrid& grid = tooth.grid();
  const std::size_t n = static_cast<std::size_t>(grid.n);
  const double h = grid.voxel_size;
  const double c_out = field->outside_clamp();
  const float out_f = static_cast<float>(c_out);
  const int m = field->samples_per_axis(), pad = field->padding();
  const int reach = static_cast<int>(std::ceil(c_out / h + 1.0));
  const double slack = 1e-6 * h;  // float rounding of the stored values
  bool complete = true;
  // The box of the changed samples: the cell bound is measured once all of the tick's removed
  // voxels are subtracted (a cell between two of them is whole only then).
  int lo[3] = {INT_MAX, INT_MAX, INT_MAX}, hi[3] = {-1, -1, -1};
  for (const std::size_t v : removed) {
    const int s0[3] = {static_cast<int>(v % n) + pad, static_cast<int>((v / n) % n) + pad,
                       static_cast<int>(v / (n * n)) + pad};
    ++stats->voxels;
    for (int dz = -reach; dz <= reach; ++dz) {
      const int sz = s0[2] + dz;
      if (sz < 0 || sz >= m) continue;
      const double ez = std::max(std::abs(dz) - 1.0, 0.0);
      for (int dy = -reach; dy <= reach; ++dy) {
        const int sy = s0[1] + dy;
        if (sy < 0 || sy >= m) continue;
        const double ey = std::max(std::abs(dy) - 1.0, 0.0);
        for (int dx = -reach; dx <= reach; ++dx) {
          const int sx = s0[0] + dx;
          if (sx < 0 || sx >= m) continue;
          ++stats->samples_scanned;
          const float old = field->at(sx, sy, sz);
          if (old >= out_f) continue;  // at the outside clamp: a max cannot raise it
          const double ex = std::max(std::abs(dx) - 1.0, 0.0);
          // Distance from s to the removed voxel's cube grown by h / 2 (the source's sub-voxel
          // slivers in the empty cubes next to it went with it): beyond |v(s)| that did not
          // hold s's nearest surface point.
          const double to_cube = h * std::sqrt(ex * ex + ey * ey + ez * ez);
          if (to_cube > std::abs(static_cast<double>(old)) + slack) continue;
          ++stats->samples_queried;
          const double d = sd(tooth, field->sample_position(sx, sy, sz), c_out).phi;
          if (!(d > old)) continue;
          if (!field->raise(sx, sy, sz, d)) {
            ++stats->samples_lost;
            complete = false;
            continue;
          }
          ++stats->samples_raised;
          const int s[3] = {sx, sy, sz};
          for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], s[a]);
            hi[a] = std::max(hi[a], s[a]);
          }
        }
      }
    }
  }
  if (hi[0] >= 0) field->include_cells(lo, hi);
  return complete;
}

const Vec3& SurfaceProxy::update(const FieldSolid& solid, const Vec3& c) {
  proxy_detail::update(constants(), solid, &valid_, &g_, c);
  return g_;
}

}  // namespace dentsim
