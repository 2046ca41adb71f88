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
// The rule (field_contact.h, docs/derivations/field_contact.md §5), per removed voxel v (cube C_v)
// and sample s within the clamps' reach of C_v grown by h / 2 with v(s) < c_out and that distance
// <= |v(s)|:
// - s inside (its voxel solid now): v(s) <- max(v(s), -dist(p(s), C_v)), the exact distance to
//   the cube in closed form (samples sit at voxel centres: h |(max(|d_a| - 1/2, 0))_a| for the
//   offset d in samples). No query: -dist(., complement of (S minus C_v)) = max(-dist(., comp S),
//   -dist(., C_v)), so an exact inside value stays exact (the proof in §5).
// - s outside (its voxel empty, or beyond the grid): v(s) <- max(v(s), clamp(d_vox(s))), d_vox
//   the exact distance to the remaining solid voxels (`Access::distance`, reach c_out).
//
// Two savings against the rule as written, neither changing a stored value, the Lipschitz
// constant, or which samples are raised (so both twins and the field stay what the rule makes):
// - Only the ball is read (and of it, the next point). A sample whose distance to the removed cube (grown by h/2) exceeds
//   v_max + slack, v_max the largest |v| a stored value below c_out can have (the float clamps),
//   fails the rule's test to_cube > |v(s)| + slack whatever v(s) is (floating-point addition is
//   monotone), so it is not read; whole planes and rows are skipped the same way (to_cube only
//   grows with |dx|, |dy|, |dz|: a sum of exact squares of small integers, then sqrt and * h,
//   both monotone). FieldEditStats::samples_scanned counts the samples read.
// - Only the samples a removal can change are read. The field keeps, for each x row of 8 samples
//   of one of its bricks (sample x in [8 b, 8 b + 7], fixed y and z), a bound B >= |v(s)| over
//   the row's samples with v(s) < c_out (as float), or B < 0 when it has none
//   (SampledField::row_bound). Invariant: the build measures it; raise() is the only writer
//   afterwards and, when the value it stores is below c_out, raises B to that |v| (the other
//   samples of the row keep their values, so B still covers them; a brick taken from the spare
//   room holds -c_in everywhere and starts at B = c_in); the fast twin raises through the same
//   SampledField and its bricks mirror the same floats, so the bound is one for both twins. A
//   sample of the row that the rule examines has old < c_out, so |old| <= B, and to_cube <=
//   |old| + slack <= B + slack (floating-point addition is monotone). to_cube = h sqrt(q_s),
//   q_s = ex^2 + ey^2 + ez^2 exact in small integers; h sqrt(q_s) <= B + slack gives q_s <=
//   ((B + slack) / h)^2 (1 + 4 eps), so with t = (1 + 1e-9) (B + slack) / h (the margin far
//   above the few roundings of t) ex^2 <= t^2 - ey^2 - ez^2 and ex <= floor(sqrt(that)) = ex_max
//   (sqrt is correctly rounded and monotone and sqrt(ex^2) = ex). So the samples of the segment
//   with |dx| - 1 > ex_max, and every sample of a segment with B < 0 or t^2 < ey^2 + ez^2, fail
//   the rule's test: they are not read. A raise during the scan changes only the sample just
//   read (each sample is read once per removed voxel), so a segment's bound read before its
//   samples covers all of them that are still to be read. The scan then reads, within the ball,
//   the samples whose own row allows it: near a flat floor the outside rows at height z read
//   about ex^2 + ey^2 <= 2 z (a paraboloid over the cube, not the ball), inside rows the ball of
//   c_in (tests/tooth/field_drilling_test.cc prints the samples read per removed voxel).
// - Outside samples ask with a shorter reach, or not at all. Outside, the query returns
//   phi = sqrt(best2), best2 the least box_distance2 from p(s) over the solid voxels with
//   box_distance2 < reach^2, and the voxel of the least index among those at best2
//   (reference/tooth/sdf.cc outside_distance, sdf_nearer; its fast twin the same doubles). Let U
//   be the solid voxels among the 27 around s's voxel and the 26 around the removed one (after
//   the removal), and D = (1 + 1e-9) min over U of the distance from p(s) to the voxel's cube in
//   closed form (samples sit at voxel centres: h |(max(|u_a - c_a| - 1/2, 0))_a|, exact in
//   integers up to the one square root; the computed box_distance2 of the same cube differs from
//   its square by far less than the 1e-9, which holds while the coordinates are below 10^5 h).
//   If D <= v(s) (< c_out), some solid voxel has box_distance2 < D^2 < c_out^2, so phi <= D <=
//   v(s) and the rule raises nothing: no query. Otherwise the query is asked with reach
//   min(D, c_out) instead of c_out: the voxels with box_distance2 < D^2 hold every voxel at the
//   least distance (below D^2), so the search returns the same best2, voxel and nearest point,
//   the same phi, and prunes every octree node beyond D (U empty: D = c_out, the rule's query).
//   The 26 listed around the removed voxel are taken first (no grid reads): if their least
//   distance already gives D' <= v(s), then D <= D' (a minimum over more voxels; the map from
//   lattice_distance4 to D is monotone) and the 27 around s are not read: the same decision.
// FieldEditStats::samples_queried counts the samples the rule examines (inside and outside),
// samples_bounded those of them answered without a voxel-distance query (inside samples by the
// closed form, outside ones by a solid neighbour): the queries are the difference.
//
// Stride k > 1 (sampled_field.h; docs/derivations/field_contact.md §7): sample s sits at voxel
// k (s - P), so its offset from a removed voxel c is D = k (s - P) - c voxels (integers) and every
// closed form above holds with D for the sample offset; the box is the R = ceil(R_v / k) samples
// around floor(c / k) + P. The batch: consecutive removed voxels with the same box centre (the
// provider sorts each tick's voxels by it) are subtracted in one visit of the box, at most
// kFieldEditGroup of them: a sample's test takes the least distance over the group (a voxel
// whose -dist would raise an inside sample passes its own test, and an outside sample's query is
// the same on the same grid), the inside value -h sqrt(min over the group), which is the max of
// the voxels' one-by-one raises, bit for bit; the ball's and the row bounds' skips use the
// distance to the group's bounding box (a lower bound of each voxel's), so they skip only
// samples every voxel skips. A group lists no neighbours (U is then the 27 around the sample: a
// subset, which the proof of the shorter reach allows). At k = 1 a group is one voxel: the
// code above, bit for bit.
// The group's minimum, factored per row (edit51): a voxel's squared distances are sums of one
// term per axis, e_x^2 + e_y^2 + e_z^2 (the grown cube) and a_x^2 + a_y^2 + a_z^2 (the cube),
// each term an integer or a quarter-integer far below 2^53, so every sum is exact whatever its
// order. On a row (fixed sy, sz) the y and z terms of a voxel are fixed: the row (at its first
// sample read) takes, for each x column of the group (c_x in [cl_x, ch_x], at most
// kFieldEditGroup of them), the least (y + z) sum over the column's voxels (+inf: none), and a
// sample then the least over the columns of its x term plus the column's least: min_g (x_g +
// yz_g) = min_j (x_j + min_{g in j} yz_g), exactly, the same doubles as the voxel-by-voxel
// minimum (so every value, count and unit of work is unchanged). The columns are visited outward
// from the sample's own: the x term grows along each direction and the (y + z) least is >= 0,
// so a direction stops once both x terms reach the minima found (a farther column cannot lower
// a minimum: the same double). O(group) a row read, a few columns a sample, instead of O(group)
// a sample. At k > kFieldEditGroup (a stride field_stride_for never gives) a group is one voxel.
// The batch's union box (edit51). A whole edit (no cursor: the worker's batch, the reference's
// fixed-latency publish) groups the consecutive voxels (at most kFieldEditGroup) whose span stays
// below kFieldEditGroup voxels on every axis, whatever their box centres, and visits once the
// union box [floor(cl / k) + P - R, floor(ch / k) + P + R] of their boxes ([cl, ch] the group's
// voxel bounds): every sample within R_v voxels of a group voxel c lies within R of floor(c / k)
// + P, inside it. Nothing above used the common centre: the least distances over the group, the
// skips by the distance to [cl, ch] (a lower bound of each voxel's) and the closed forms are the
// same for any voxels, so every stored value and the Lipschitz constant are the voxel-by-voxel
// edit's; the counts are per visit (a sample the group's voxels would each have read is read
// once, each row of the union once, where the centre groups of one tick's drilling each read
// their whole box of (2R + 1)^2 rows, mostly rows whose row bounds skip every sample). A
// budgeted edit keeps the common centre (its cursor's rows are rows of one box).
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

// (2 dist / h)^2 from the centre of voxel a to the cube of voxel b, exact in integers: the
// per-axis gap is max(|b - a| - 1/2, 0) voxels.
inline int lattice_distance4(const int a[3], const int b[3]) {
  int sum = 0;
  for (int k = 0; k < 3; ++k) {
    const int g = std::max(2 * std::abs(b[k] - a[k]) - 1, 0);
    sum += g * g;
  }
  return sum;
}

// The least lattice_distance4 from voxel position c (a sample's voxel, possibly beyond the grid)
// to a solid voxel among the 27 around c and the `near_count` voxels `near` (INT_MAX: none).
inline int nearest_listed4(const VoxelGrid& grid, const int c[3], const int (*near)[3],
                           int near_count) {
  int best = INT_MAX;
  for (int k = c[2] - 1; k <= c[2] + 1; ++k) {
    for (int j = c[1] - 1; j <= c[1] + 1; ++j) {
      for (int i = c[0] - 1; i <= c[0] + 1; ++i) {
        if (!grid.inside(i, j, k) || grid.voxels[grid.index(i, j, k)] == kEmpty) continue;
        const int u[3] = {i, j, k};
        best = std::min(best, lattice_distance4(c, u));
      }
    }
  }
  for (int u = 0; u < near_count; ++u) best = std::min(best, lattice_distance4(c, near[u]));
  return best;
}

// Where a budgeted edit stopped (reference/tooth/field_contact.h).
using dentsim::FieldEditCursor;

// floor(a / b) for b > 0 (C++ division truncates towards zero).
inline int floor_div(int a, int b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

// The edit (header comment). With a cursor, it resumes there and stops before the first row (or
// the first voxel) at which it has spent `budget` units of work in this call, leaving the cursor
// there (budget >= 1: every call then takes at least one row); without one it subtracts all of
// `removed`. The work (FieldEditStats::work, weights in field_contact.h) charges what costs
// instructions: a voxel's set-up, each row that reaches the row bounds, each sample read, each
// voxel-distance query and each cell whose Lipschitz bound is re-measured. A step (a voxel's
// set-up, or one row with its queries and its cells) is begun only while less than `budget` is
// spent, except that a call's first row is always begun (after its voxel's set-up: so a call
// takes at least one row, and a budget below a set-up's weight cannot stall the edit), so a call
// spends at most max(budget - 1, kFieldEditVoxelWeight) + field_edit_step_work(R) and reads at
// most budget + 2R samples. Rows the ball skips are not charged: at most (2R + 1)^2 a voxel, a few
// instructions each. A budgeted edit is safe after every call and ends where the whole one does:
// - Values only rise (every write is SampledField::raise, a max), so {phi >= rho - s} only grows:
//   a proxy admissible before the call stays admissible, and no call puts it inside material.
//   The samples not yet reached hold at most their edited value: the admissible set is smaller,
//   never larger, than after the whole edit (material the voxels lost, never a tunnel).
// - lipschitz() bounds the field after every call, whole or stopped inside a voxel's box. Claim:
//   if L >= L_cell(c) for every cell c before the call (docs/derivations/field_contact.md §2), the
//   same holds after it. Proof: L_cell(c) is a function of c's 8 corner values only. A cell none
//   of whose corners the call changed keeps its L_cell <= L, and L never falls. A sample changes
//   only through a raise that returned true (a refused one, samples_lost, writes nothing), and each
//   such sample s widens [lo, hi] to hold it; a cell with s as a corner has its lower corner in
//   [s_a - 1, s_a] on each axis a (and in [0, m - 2]). The raises of one row (fixed sy, sz) lie in
//   [x_lo, x_hi] of that row, so their cells have lower corners in [max(0, x_lo - 1),
//   min(m - 2, x_hi)] x [sy - 1, sy] x [sz - 1, sz] (clamped to [0, m - 2]): exactly the cells
//   Access::include_cells({x_lo, sy, sz}, {x_hi, sy, sz}) measures (SampledField::include_cells;
//   the fast twin measures the same cells from its bricks) and raises L over, for every row with
//   a raise, at the call's end (or earlier, when the call's list of such rows is full: a cell
//   with a corner changed after that is measured again at the end). So every cell is covered,
//   whichever samples the call reached: the proof uses only which samples changed, not that a
//   voxel's box, or `removed`, was finished. (A cell between a sample edited and one not yet
//   edited may exceed the whole edit's 1.5 sqrt(3) of §5; L then keeps that transient, which only
//   shortens the proxy's sweep steps.) Measured per row at the call's end, not once over the
//   bounding box of the call's raises: the same maximum (a cell of the box with no changed corner
//   had L_cell <= L already), but at most 4 (2R + 2) cells a row, charged to the budget, and a
//   call spanning two voxels' boxes no longer measures the space between them. (Measured after
//   each row instead, the transients of half-edited boxes ratcheted L to 3.0 in
//   FieldDrilling.TheEditsSavingsChangeNoValue and 7.1 in LipschitzBoundHoldsAfterTheEdits.)
// - The same end: each sample's update depends only on its value, the removed voxel and the grid
//   (the solid voxels listed around the removed voxel are listed again when a call resumes); the
//   calls take the voxels, rows and samples in the order of one whole call, so while the grid does
//   not change in between, every value and count (voxels, samples read, asked, raised, rows read,
//   cells measured) ends the same, and so does the Lipschitz constant (the calls measure the same
//   cells after the same rows as the whole edit; only the work differs: a voxel resumed at a row
//   is charged its set-up again). When the grid changes in between (drilling
//   goes on while the provider's queue drains), a sample reached later is evaluated on the later
//   grid, as when the queue lags by whole voxels: the rule and the proofs above hold per call.
// `FieldDrilling.ABudgetedEditEndsWhereTheWholeEditEnds` and
// `FieldDrilling.TheProvidersBudgetedEditEndsWhereTheWholeEditEnds` check this.
template <class Access>
bool edit_field(const SampledField& field, const VoxelTooth& tooth,
                std::span<const std::size_t> removed, Access& access, FieldEditStats* stats,
                FieldEditCursor* cursor = nullptr, long budget = 0) {
  const VoxelGrid& grid = tooth.grid();
  const std::size_t n = static_cast<std::size_t>(grid.n);
  const double h = grid.voxel_size;
  const double c_out = field.outside_clamp();
  const float out_f = static_cast<float>(c_out);
  const float in_f = static_cast<float>(-field.inside_clamp());
  const int m = field.samples_per_axis(), pad = field.padding();
  // Stride k (sampled_field.h): sample s sits at the centre of voxel k (s - P); the offsets below
  // (the distances to the removed cube, the closed forms, the listed voxels) are in voxels, the
  // box's rows in samples (reach = R, field samples). At k = 1 every expression is the one of
  // one sample per voxel centre (D = s - P - c = d).
  const int stride = field.stride();
  const int reach = field.edit_radius();
  const double slack = 1e-6 * h;  // float rounding of the stored values
  constexpr double kWide = 1.0 + 1e-9;  // a closed-form lattice distance over the computed one
  // Any stored value below c_out has |v| <= v_max; beyond `ball` no sample can pass the test.
  const double v_max = std::max(static_cast<double>(out_f), -static_cast<double>(in_f));
  const double ball = v_max + slack;
  bool complete = true;
  const int width = 2 * reach + 1;  // rows of a box along y (and planes along z)
  const long work_before = stats->work;
  // Whether this call has spent its budget of work (never without a cursor, nor before the call
  // has begun a row: every call makes progress, even when a voxel's set-up alone exceeds it).
  bool began_row = false;
  const auto spent = [&] {
    return cursor != nullptr && began_row && stats->work - work_before >= budget;
  };
  // The rows with raises, (x_lo, x_hi, sy, sz): their cells are measured at the call's end (the
  // comment above says why that keeps lipschitz() a bound), or earlier when the list is full.
  constexpr int kChangedRows = 1024;  // 16 KB of stack
  int changed[kChangedRows][4];
  int changed_rows = 0;
  const auto measure = [&] {
    for (int r = 0; r < changed_rows; ++r) {
      const int lo[3] = {changed[r][0], changed[r][2], changed[r][3]};
      const int hi[3] = {changed[r][1], changed[r][2], changed[r][3]};
      access.include_cells(lo, hi);
    }
    changed_rows = 0;
  };
  bool paused = false;
  std::size_t group = 1;  // the voxels edited together (the batch, header comment)
  const auto voxel_of = [&](std::size_t v, int c[3]) {
    c[0] = static_cast<int>(v % n);
    c[1] = static_cast<int>((v / n) % n);
    c[2] = static_cast<int>(v / (n * n));
  };
  for (std::size_t at = cursor != nullptr ? cursor->next : 0; at < removed.size() && !paused;
       at += group) {
    int cv[3];
    voxel_of(removed[at], cv);
    // The box's centre sample floor(c / k) + P: the samples within R_v voxels of c lie within R
    // of it (SampledField::edit_radius).
    const int s0[3] = {cv[0] / stride + pad, cv[1] / stride + pad, cv[2] / stride + pad};
    // The first row of this group's box this call takes (a resumed group's next row).
    const bool resumed = cursor != nullptr && at == cursor->next;
    const int first_row = resumed ? cursor->row : 0;
    // The batch (stride k > 1): the consecutive voxels with the same box centre, at most
    // kFieldEditGroup; a group resumed inside its box keeps the length it was begun with.
    group = 1;
    if (resumed && first_row > 0 && cursor->group > 0) {
      group = std::min(cursor->group, removed.size() - at);
    } else if (stride > 1 && stride <= kFieldEditGroup) {  // a group's x columns fit its rows'
      // A whole edit (no cursor) groups the consecutive voxels whose span stays below
      // kFieldEditGroup voxels on every axis, whatever their box centres (header comment, "The
      // batch's union box"); a budgeted one those with the same centre.
      int span_lo[3] = {cv[0], cv[1], cv[2]}, span_hi[3] = {cv[0], cv[1], cv[2]};
      while (at + group < removed.size() && group < static_cast<std::size_t>(kFieldEditGroup)) {
        int c[3];
        voxel_of(removed[at + group], c);
        if (cursor == nullptr) {
          bool fits = true;
          for (int a = 0; a < 3; ++a) {
            fits = fits && std::max(span_hi[a], c[a]) - std::min(span_lo[a], c[a]) <
                               kFieldEditGroup;
          }
          if (!fits) break;
          for (int a = 0; a < 3; ++a) {
            span_lo[a] = std::min(span_lo[a], c[a]);
            span_hi[a] = std::max(span_hi[a], c[a]);
          }
        } else if (c[0] / stride + pad != s0[0] || c[1] / stride + pad != s0[1] ||
                   c[2] / stride + pad != s0[2]) {
          break;
        }
        ++group;
      }
    }
    // The group's voxels' bounds per axis (one voxel: cv itself).
    int cl[3] = {cv[0], cv[1], cv[2]}, ch[3] = {cv[0], cv[1], cv[2]};
    int gv[kFieldEditGroup][3];
    for (std::size_t g = 0; g < group; ++g) {
      voxel_of(removed[at + g], gv[g]);
      for (int a = 0; a < 3; ++a) {
        cl[a] = std::min(cl[a], gv[g][a]);
        ch[a] = std::max(ch[a], gv[g][a]);
      }
    }
    // The voxel offset of sample coordinate s_a from the group's voxels: |D_a| = |k (s_a - P) -
    // c_a| for one voxel, the distance to [cl_a, ch_a] for a group (a lower bound of each
    // voxel's, so the ball's and the row bounds' skips stay skips of every voxel's test).
    const auto offset = [&](int a, int sa) {
      const int q = stride * (sa - pad);
      return q < cl[a] ? cl[a] - q : (q > ch[a] ? q - ch[a] : 0);
    };
    // The box: the samples within R of the group's box centres, [lo_a - R, lo_a + ext_a + R]
    // (one centre, ext = 0: the box of R about s0).
    const int box_lo[3] = {cl[0] / stride + pad, cl[1] / stride + pad, cl[2] / stride + pad};
    const int ext[3] = {ch[0] / stride + pad - box_lo[0], ch[1] / stride + pad - box_lo[1],
                        ch[2] / stride + pad - box_lo[2]};
    const int row_width = width + ext[1];
    if (spent()) {  // the budget is spent before this group's next row: the next call's first
      cursor->next = at;
      cursor->row = first_row;
      cursor->group = group;
      paused = true;
      break;
    }
    // The removed voxel's solid neighbours U (header comment): at most 26 boxes.
    stats->work += kFieldEditVoxelWeight;
    int near_lo[26][3] = {};
    int near_count = 0;
    if (group == 1) {  // a group lists none (only the 27 around each sample: a subset of U)
      const int* c = cv;
      for (int k = c[2] - 1; k <= c[2] + 1; ++k) {
        for (int j = c[1] - 1; j <= c[1] + 1; ++j) {
          for (int i = c[0] - 1; i <= c[0] + 1; ++i) {
            if (!grid.inside(i, j, k) || grid.voxels[grid.index(i, j, k)] == kEmpty) continue;
            near_lo[near_count][0] = i;
            near_lo[near_count][1] = j;
            near_lo[near_count][2] = k;
            ++near_count;
          }
        }
      }
    }
    for (int dz = -reach + first_row / row_width; dz <= reach + ext[2] && !paused; ++dz) {
      const int sz = box_lo[2] + dz;
      if (sz < 0 || sz >= m) continue;
      const int oz = offset(2, sz);
      const double ez = std::max(std::abs(oz) - 1.0, 0.0);
      if (h * std::sqrt(ez * ez) > ball) continue;  // the plane misses the ball
      for (int dy = -reach; dy <= reach + ext[1] && !paused; ++dy) {
        const int row = (dz + reach) * row_width + dy + reach;
        if (row < first_row) continue;  // taken by an earlier call
        if (spent()) {
          cursor->next = at;  // the budget is spent: this row is the next call's first
          cursor->row = row;
          cursor->group = group;
          paused = true;
          break;
        }
        began_row = true;
        const int sy = box_lo[1] + dy;
        if (sy < 0 || sy >= m) continue;
        const int oy = offset(1, sy);
        const double ey = std::max(std::abs(oy) - 1.0, 0.0);
        if (h * std::sqrt(ey * ey + ez * ez) > ball) continue;  // the row misses the ball
        ++stats->rows_read;
        stats->work += kFieldEditRowWeight;
        // A group's least distances, factored per row (header comment, "The group's minimum"):
        // for each x column j = c_x - cl_x of its voxels, the least y and z terms over the voxels
        // of that column, (e_y^2 + e_z^2) for the grown cube and (a_y^2 + a_z^2) for the cube.
        // Taken at the row's first sample read (most rows read none).
        bool columns_taken = false;
        double row_e2[kFieldEditGroup], row_a2[kFieldEditGroup];
        const auto take_columns = [&] {
          columns_taken = true;
          const int qy = stride * (sy - pad), qz = stride * (sz - pad);
          for (int j = 0; j <= ch[0] - cl[0]; ++j) {
            row_e2[j] = INFINITY;
            row_a2[j] = INFINITY;
          }
          for (std::size_t g = 0; g < group; ++g) {
            const int j = gv[g][0] - cl[0];
            const int o[2] = {std::abs(qy - gv[g][1]), std::abs(qz - gv[g][2])};
            double e2 = 0.0, a2 = 0.0;
            for (int a = 0; a < 2; ++a) {
              const double e = std::max(o[a] - 1.0, 0.0), c = std::max(o[a] - 0.5, 0.0);
              e2 += e * e;
              a2 += c * c;
            }
            row_e2[j] = std::min(row_e2[j], e2);
            row_a2[j] = std::min(row_a2[j], a2);
          }
        };
        // The x extent of this row's raises: the cells with one of them as a corner are
        // re-measured once the row is done (header comment).
        int raised_lo = INT_MAX, raised_hi = -1;
        // The row in segments of the field's bricks, each read only where its row bound lets a
        // sample pass the rule's test (header comment, "Only the samples a removal can change").
        const int x_first = std::max(0, box_lo[0] - reach),
                  x_last = std::min(m - 1, box_lo[0] + ext[0] + reach);
        for (int xb = x_first / kFieldBrick; xb * kFieldBrick <= x_last; ++xb) {
          const float bound = field.row_bound(xb, sy, sz);
          if (bound < 0.0f) continue;  // every sample of the segment at c_out
          const double t = (static_cast<double>(bound) + slack) / h * kWide;
          const double q = t * t - (ey * ey + ez * ez);
          if (q < 0.0) continue;  // the segment's row misses the bound's ball
          const int ex_max = static_cast<int>(std::sqrt(q));  // |D_x| - 1 <= ex_max
          // |k (sx - P) - c_x| <= ex_max + 1 (at k = 1: |sx - s0| <= ex_max + 1).
          const int x_lo = std::max({x_first, xb * kFieldBrick,
                                     pad - floor_div(ex_max + 1 - cl[0], stride)});
          const int x_hi = std::min({x_last, xb * kFieldBrick + kFieldBrick - 1,
                                     pad + floor_div(ch[0] + ex_max + 1, stride)});
          for (int sx = x_lo; sx <= x_hi; ++sx) {
            const int dx = offset(0, sx);
            const double ex = std::max(std::abs(dx) - 1.0, 0.0);
            // Distance from s to the removed voxel's cube grown by h / 2 (the source's sub-voxel
            // slivers in the empty cubes next to it went with it): beyond |v(s)| that did not
            // hold s's nearest surface point. A group: the least over its voxels, and the least
            // distance to their cubes for the closed form (h sqrt(.) is monotone, so the least
            // of the sums gives the least distance, the same double).
            double grown2 = ex * ex + ey * ey + ez * ez, cube2 = 0.0;
            if (group > 1) {
              if (!columns_taken) take_columns();
              const int qx = stride * (sx - pad);
              grown2 = INFINITY;
              cube2 = INFINITY;
              // The columns outward from the nearest one: the x term only grows along each
              // direction and the (y + z) least is >= 0, so once both x terms reach the minima
              // found, no farther column can lower them (the same doubles).
              const int span = ch[0] - cl[0];
              const int j0 = std::clamp(qx - cl[0], 0, span);
              const auto visit = [&](int j) {
                const int o = std::abs(qx - (cl[0] + j));
                const double e = std::max(o - 1.0, 0.0), c = std::max(o - 0.5, 0.0);
                if (e * e >= grown2 && c * c >= cube2) return false;
                grown2 = std::min(grown2, e * e + row_e2[j]);
                cube2 = std::min(cube2, c * c + row_a2[j]);
                return true;
              };
              for (int j = j0; j >= 0 && visit(j); --j) {
              }
              for (int j = j0 + 1; j <= span && visit(j); ++j) {
              }
              stats->work += static_cast<long>(group) / kFieldEditGroupPerUnit;
            }
            const double to_cube = h * std::sqrt(grown2);
            if (to_cube > ball) continue;
            ++stats->samples_scanned;
            ++stats->work;
            const float old = access.at(sx, sy, sz);
            if (old >= out_f) continue;  // at the outside clamp: a max cannot raise it
            if (to_cube > std::abs(static_cast<double>(old)) + slack) continue;
            ++stats->samples_queried;
            const Vec3 p = field.sample_position(sx, sy, sz);
            int idx[3] = {0, 0, 0};
            const bool in_grid = sdf_detail::voxel_of(grid, p, idx);
            const bool inside =
                in_grid && grid.voxels[grid.index(idx[0], idx[1], idx[2])] != kEmpty;
            double d = 0.0;
            if (inside) {  // the closed form: minus the distance to the removed cube
              ++stats->samples_bounded;
              if (group > 1) {
                d = -h * std::sqrt(cube2);
              } else {
                const double ax = std::max(std::abs(dx) - 0.5, 0.0);
                const double ay = std::max(std::abs(oy) - 0.5, 0.0);
                const double az = std::max(std::abs(oz) - 0.5, 0.0);
                d = -h * std::sqrt(ax * ax + ay * ay + az * az);
              }
            } else {
              // The nearest listed solid voxel (header comment): no query if it is within v(s),
              // else the query's reach cut down to it.
              const int c[3] = {field.voxel_of_sample(sx), field.voxel_of_sample(sy),
                                field.voxel_of_sample(sz)};
              const auto to_listed = [&](int best4) {
                return best4 == INT_MAX ? c_out
                                        : 0.5 * h * std::sqrt(static_cast<double>(best4)) * kWide;
              };
              // The removed voxel's 26 first (no grid reads): when they already bound v(s), so
              // does the least over all of U (to_listed is monotone), and the 27 are not read.
              int best4 = INT_MAX;
              for (int u = 0; u < near_count; ++u) {
                best4 = std::min(best4, lattice_distance4(c, near_lo[u]));
              }
              if (to_listed(best4) > static_cast<double>(old)) {
                best4 = std::min(best4, nearest_listed4(grid, c, near_lo, 0));
              }
              const double listed = to_listed(best4);
              if (listed <= static_cast<double>(old)) {
                ++stats->samples_bounded;  // the query's phi <= v(s): no raise (header comment)
                continue;
              }
              stats->work += kFieldEditQueryWeight;
              d = access.distance(sx, sy, sz, p, std::min(listed, c_out));
            }
            if (!(d > old)) continue;
            if (!access.raise(sx, sy, sz, d)) {
              ++stats->samples_lost;
              complete = false;
              continue;
            }
            ++stats->samples_raised;
            raised_lo = std::min(raised_lo, sx);
            raised_hi = sx;
          }
        }
        if (raised_hi >= 0) {  // the cells with a corner among this row's raises: charged now,
                               // measured at the call's end (or when the list is full)
          const long cells = static_cast<long>(std::min(m - 2, raised_hi) -
                                               std::max(0, raised_lo - 1) + 1) *
                             (std::min(m - 2, sy) - std::max(0, sy - 1) + 1) *
                             (std::min(m - 2, sz) - std::max(0, sz - 1) + 1);
          stats->cells_measured += cells;
          stats->work += field_edit_cell_work(cells);
          if (changed_rows == kChangedRows) measure();
          changed[changed_rows][0] = raised_lo;
          changed[changed_rows][1] = raised_hi;
          changed[changed_rows][2] = sy;
          changed[changed_rows][3] = sz;
          ++changed_rows;
        }
      }
    }
    if (!paused) stats->voxels += static_cast<long>(group);  // this group's box is done
  }
  if (cursor != nullptr && !paused) {  // every voxel whole
    cursor->next = removed.size();
    cursor->row = 0;
    cursor->group = 0;
  }
  measure();
  return complete;
}

}  // namespace dentsim::field_edit_detail
