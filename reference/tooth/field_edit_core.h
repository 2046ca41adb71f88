// The drilling edit of the sampled field, written once for both twins (BEYOND THE THESIS; issue
// #30; the rule in reference/tooth/field_contact.h edit_field_for_removed_voxels, derivation in
// docs/derivations/field_contact.md §5). The reference runs it on the SampledField and the voxel
// distance it is given; the fast pipeline (fast/tooth/field.h) on its 9^3 bricks and its kept
// voxel distances. What may differ between them is only how a sample is read, how the voxel
// distance is found (the same double) and where a raise is written: `Access` provides
//   float at(int sx, int sy, int sz)                     the stored value of sample s
//   double distance(int sx, int sy, int sz, const Vec3& p, double reach)
//                                                        sd(tooth, p, reach).phi, p = p(s)
//   bool raise(int sx, int sy, int sz, double value)     SampledField::raise (false: no brick)
//   void include_cells(const int lo[3], const int hi[3]) the Lipschitz update of the sample box
//
// Two savings against the rule as written, neither changing a stored value, the Lipschitz
// constant, or which samples are raised (so both twins and the field stay what the rule makes):
// - Only the ball is read. A sample whose distance to the removed cube (grown by h/2) exceeds
//   v_max + slack, v_max the largest |v| a stored value below c_out can have (the float clamps),
//   fails the rule's test to_cube > |v(s)| + slack whatever v(s) is (floating-point addition is
//   monotone), so it is not read; whole planes and rows are skipped the same way (to_cube only
//   grows with |dx|, |dy|, |dz|: a sum of exact squares of small integers, then sqrt and * h,
//   both monotone). FieldEditStats::samples_scanned counts the samples read.
// - Inside samples ask with a shorter reach. For a sample in a solid voxel the query is the
//   shell search (reference/tooth/sdf.h inside_distance), and the rule raises v(s) only if
//   phi > v(s) >= float(-c_in). With reach r_in = max(c_in, -double(float(-c_in))) instead of
//   c_out: if the complement lies nearer than r_in, both searches return the same double (the
//   minimum over the same boxes: a search stops only once its shells are farther than its best,
//   and the two bests agree once a box nearer than r_in is seen); otherwise the short search
//   returns -r_in and the long one -d with d >= r_in, and both are <= float(-c_in) <= v(s): no
//   raise either way. The shell search then visits at most ceil(r_in / h) + 1 shells instead of
//   ceil(c_out / h) + 1 (at 128^3 with the drill scene's bur: 3 against 6, 343 voxels against
//   2197).
// - Outside samples next to a solid voxel within |v(s)| ask nothing. Outside, the query returns
//   phi = sqrt(best2), best2 the least box_distance2 from p(s) over the solid voxels with
//   box_distance2 < reach^2 (reference/tooth/sdf.cc outside_distance; its fast twin the same
//   double). If one of the 27 voxels around s's own, u, is solid with box_distance2(u) = d2u <
//   reach^2 and sqrt(d2u) <= v(s), then best2 <= d2u, so phi <= sqrt(d2u) <= v(s) (sqrt is
//   monotone) and the rule raises nothing: the query is skipped (FieldEditStats::samples_bounded;
//   samples_queried counts these too, so it keeps the rule's count).
//
// Real-time: no allocation, no throw (the Access must not either).
#pragma once

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <span>

#include "reference/tooth/field_contact.h"

namespace dentsim::field_edit_detail {

// Whether a solid voxel u among the 27 around voxel idx (which holds p) has
// sqrt(box_distance2(u, p)) <= v and box_distance2(u, p) < reach^2 (header comment).
inline bool solid_neighbour_within(const VoxelGrid& grid, const Vec3& p, const int idx[3],
                                   float v, double reach) {
  const double limit = static_cast<double>(v);
  if (!(limit >= 0.0)) return false;
  for (int k = idx[2] - 1; k <= idx[2] + 1; ++k) {
    for (int j = idx[1] - 1; j <= idx[1] + 1; ++j) {
      for (int i = idx[0] - 1; i <= idx[0] + 1; ++i) {
        if (!grid.inside(i, j, k) || grid.voxels[grid.index(i, j, k)] == kEmpty) continue;
        const int lo[3] = {i, j, k}, hi[3] = {i + 1, j + 1, k + 1};
        const double d2 = sdf_detail::box_distance2(grid, lo, hi, p, nullptr);
        if (d2 < reach * reach && std::sqrt(d2) <= limit) return true;
      }
    }
  }
  return false;
}

template <class Access>
bool edit_field(const SampledField& field, const VoxelTooth& tooth,
                std::span<const std::size_t> removed, Access& access, FieldEditStats* stats) {
  const VoxelGrid& grid = tooth.grid();
  const std::size_t n = static_cast<std::size_t>(grid.n);
  const double h = grid.voxel_size;
  const double c_out = field.outside_clamp();
  const float out_f = static_cast<float>(c_out);
  const float in_f = static_cast<float>(-field.inside_clamp());
  const int m = field.samples_per_axis(), pad = field.padding();
  const int reach = field.edit_radius();
  const double slack = 1e-6 * h;  // float rounding of the stored values
  // Any stored value below c_out has |v| <= v_max; beyond `ball` no sample can pass the test.
  const double v_max = std::max(static_cast<double>(out_f), -static_cast<double>(in_f));
  const double ball = v_max + slack;
  const double reach_in = std::max(field.inside_clamp(), -static_cast<double>(in_f));
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
      if (h * std::sqrt(ez * ez) > ball) continue;  // the plane misses the ball
      for (int dy = -reach; dy <= reach; ++dy) {
        const int sy = s0[1] + dy;
        if (sy < 0 || sy >= m) continue;
        const double ey = std::max(std::abs(dy) - 1.0, 0.0);
        if (h * std::sqrt(ey * ey + ez * ez) > ball) continue;  // the row misses the ball
        for (int dx = -reach; dx <= reach; ++dx) {
          const int sx = s0[0] + dx;
          if (sx < 0 || sx >= m) continue;
          const double ex = std::max(std::abs(dx) - 1.0, 0.0);
          // Distance from s to the removed voxel's cube grown by h / 2 (the source's sub-voxel
          // slivers in the empty cubes next to it went with it): beyond |v(s)| that did not
          // hold s's nearest surface point.
          const double to_cube = h * std::sqrt(ex * ex + ey * ey + ez * ez);
          if (to_cube > ball) continue;
          ++stats->samples_scanned;
          const float old = access.at(sx, sy, sz);
          if (old >= out_f) continue;  // at the outside clamp: a max cannot raise it
          if (to_cube > std::abs(static_cast<double>(old)) + slack) continue;
          ++stats->samples_queried;
          const Vec3 p = field.sample_position(sx, sy, sz);
          int idx[3] = {0, 0, 0};
          const bool in_grid = sdf_detail::voxel_of(grid, p, idx);
          const bool inside =
              in_grid && grid.voxels[grid.index(idx[0], idx[1], idx[2])] != kEmpty;
          if (!inside && in_grid && solid_neighbour_within(grid, p, idx, old, c_out)) {
            ++stats->samples_bounded;  // the query's phi <= v(s): no raise (header comment)
            continue;
          }
          const double d = access.distance(sx, sy, sz, p, inside ? reach_in : c_out);
          if (!(d > old)) continue;
          if (!access.raise(sx, sy, sz, d)) {
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
  if (hi[0] >= 0) access.include_cells(lo, hi);
  return complete;
}

}  // namespace dentsim::field_edit_detail
