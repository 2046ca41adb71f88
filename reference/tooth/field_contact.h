// The "field" contact model (issue #30; BEYOND THE THESIS; derivation in
// docs/derivations/field_contact.md): the surface proxy of the "sdf" model
// (reference/tooth/sdf.h, its algorithm in reference/tooth/surface_proxy_core.h) run on the
// sampled signed-distance field of the tooth's source surface (reference/tooth/sampled_field.h)
// instead of the exact distance to the voxel staircase. The tip's admissible set is
// A = {phi_field >= rho}; the sweep advances by (phi - (rho - s)) / L, L the field's Lipschitz
// constant, so g never enters {phi_field < rho - s} and so never crosses the field's solid
// {phi_field <= 0} (no tunnelling, docs/derivations/field_contact.md §3).
//
// Deep inside (all 8 corners of x's cell at the inside clamp, so no gradient), the query falls
// back to the exact voxel distance (reference/tooth/sdf.h) to find the way out: only a proxy that
// starts inside the tooth goes there.
//
// Materials stay per voxel: the contact's material is the solid voxel nearest to g (as "sdf").
// Drilling: the provider (tooth_contacts.h) removes voxels by the sdf model's rule (drilling.h),
// then edit_field_for_removed_voxels subtracts them from the field (below).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <span>
#include <utility>

#include "reference/tooth/sampled_field.h"
#include "reference/tooth/sdf.h"

namespace dentsim {

// The sweep's advance along the cell's own cubic (docs/derivations/field_contact.md §3, "The
// sweep's step along the cell's cubic"; both twins call this, so their steps are the same
// doubles). The point y lies in the lattice cell with corners c[dx + 2 dy + 4 dz] (stored values)
// at cell coordinates t (each in [0, 1]); h the lattice spacing; dir a unit direction;
// clearance = phi(y) - (rho - s) > 2 slack > 0; left the distance to the segment's end; lipschitz
// the field's L. Along dir, phi(y + tau dir) within the cell is the cubic
// p(tau) = phi(y) + a1 tau + a2 tau^2 + a3 tau^3 (the trilinear interpolant restricted to a line),
// so the first tau at which p meets rho - s + slack is found from the 8 corners, with no query:
// q = p - (rho - s + slack) is monotone between the roots of q' (at most two), so q >= 0 on
// [0, T] (T = min(cell exit, left)) iff q >= 0 at those roots and at T, and on the first monotone
// piece where q falls below 0 a bracketing iteration (regula falsi, Illinois) keeps a point lo
// with q(lo) >= 0 (so q >= 0 on [0, lo]) until q(lo) <= slack / 2. Returns lo there (the next
// query at y + lo dir then finds clearance in [slack, 1.5 slack], below the sweep's blocking
// threshold 2 slack); else T if T = left; else (the cell's exit) T + q(T) / (2 L), a little
// beyond the exit by the Lipschitz bound (phi >= rho - s + slack + q(T) / 2 there), so that the
// next query lies in the next cell. 0 when y is not strictly in the lattice's cell (clamped).
inline double field_cell_advance(const float c[8], const double t[3], double h, const Vec3& dir,
                                 double clearance, double slack, double left, double lipschitz) {
  const double v0 = c[0], v1 = c[1], v2 = c[2], v3 = c[3];
  const double v4 = c[4], v5 = c[5], v6 = c[6], v7 = c[7];
  // The interpolant in the cell's monomials 1, x, y, z, xy, xz, yz, xyz.
  const double c100 = v1 - v0, c010 = v2 - v0, c001 = v4 - v0;
  const double c110 = (v3 - v2) - c100, c101 = (v5 - v4) - c100, c011 = (v6 - v4) - c010;
  const double c111 = ((v7 - v6) - (v5 - v4)) - ((v3 - v2) - c100);
  const double tx = t[0], ty = t[1], tz = t[2];
  // Its partial derivatives at y (cell units) and the cross terms, then the cubic's coefficients
  // in tau (metres along dir: the cell coordinates move by dir / h a metre).
  const double ex = c100 + c110 * ty + c101 * tz + c111 * (ty * tz);
  const double ey = c010 + c110 * tx + c011 * tz + c111 * (tx * tz);
  const double ez = c001 + c101 * tx + c011 * ty + c111 * (tx * ty);
  const double ax = dir.x() / h, ay = dir.y() / h, az = dir.z() / h;
  const double a1 = ex * ax + ey * ay + ez * az;
  const double a2 = (c110 + c111 * tz) * (ax * ay) + (c101 + c111 * ty) * (ax * az) +
                    (c011 + c111 * tx) * (ay * az);
  const double a3 = c111 * (ax * ay * az);
  double exit = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (dir[a] > 0.0) exit = std::min(exit, (1.0 - t[a]) * h / dir[a]);
    if (dir[a] < 0.0) exit = std::min(exit, t[a] * h / -dir[a]);
  }
  const double end = std::min(exit, left);
  const double a0 = clearance - slack;
  const auto q = [&](double s) { return a0 + s * (a1 + s * (a2 + s * a3)); };
  // The roots of q' = a1 + 2 a2 s + 3 a3 s^2 inside (0, end), ascending, then end.
  double stops[3];
  int count = 0;
  {
    const double qa = 3.0 * a3, qb = 2.0 * a2;
    double r[2];
    int n = 0;
    if (qa != 0.0) {
      const double disc = qb * qb - 4.0 * qa * a1;
      if (disc > 0.0) {
        const double w = -0.5 * (qb + std::copysign(std::sqrt(disc), qb));
        r[n++] = w / qa;
        r[n++] = a1 / w;
      }
    } else if (qb != 0.0) {
      r[n++] = -a1 / qb;
    }
    if (n == 2 && r[1] < r[0]) std::swap(r[0], r[1]);
    for (int i = 0; i < n; ++i) {
      if (r[i] > 0.0 && r[i] < end) stops[count++] = r[i];
    }
    stops[count++] = end;
  }
  double lo = 0.0, qlo = a0;
  for (int i = 0; i < count; ++i) {
    const double hi0 = stops[i], qhi0 = q(hi0);
    if (qhi0 >= 0.0) {
      lo = hi0;
      qlo = qhi0;
      continue;
    }
    // q falls from qlo >= 0 at lo to qhi0 < 0 at hi0, monotone: its first root lies between.
    double hi = hi0, wlo = qlo, whi = qhi0;
    int side = 0;
    for (int it = 0; it < 64 && qlo > 0.5 * slack; ++it) {
      double m = (lo * whi - hi * wlo) / (whi - wlo);
      if (!(m > lo && m < hi)) m = 0.5 * (lo + hi);
      if (!(m > lo && m < hi)) break;  // no double between lo and hi
      const double qm = q(m);
      if (qm >= 0.0) {
        lo = m;
        qlo = wlo = qm;
        if (side > 0) whi *= 0.5;  // Illinois: the end kept twice has its weight halved
        side = 1;
      } else {
        hi = m;
        whi = qm;
        if (side < 0) wlo *= 0.5;
        side = -1;
      }
    }
    return lo;
  }
  if (end >= left) return end;
  return end + qlo / (2.0 * lipschitz);
}

// The sampled field as the surface proxy's Solid (surface_proxy_core.h). Both must outlive it.
class FieldSolid {
 public:
  FieldSolid(const VoxelTooth& tooth, const SampledField& field) : tooth_(tooth), field_(field) {}
  // The proxy core's field-only paths (surface_proxy_core.h: the Newton push-out step, the
  // cell-certified sweep, the stalled-slide stop; docs/derivations/field_contact.md §3).
  static constexpr bool kFieldPaths = true;

  const VoxelTooth& tooth() const { return tooth_; }
  const SampledField& field() const { return field_; }
  // phi_field(x) (found = false and phi = reach when phi >= reach), nearest = x - phi n; deep
  // inside, the exact voxel distance (header comment).
  SignedDistance distance(const Vec3& x, double reach) const;
  // grad phi / |grad phi| (deep inside or where the gradient vanishes: the voxel distance's).
  Vec3 normal(const Vec3& x, const SignedDistance& sd) const;
  double lipschitz() const { return field_.lipschitz(); }
  // |grad phi| at x (0 deep inside, where the query is the voxel distance's): the push-out's
  // Newton step (surface_proxy_core.h plain_step).
  double slope(const Vec3& x) const;
  // The sweep's certified advance from y (sd = distance(y, ..), found) along the unit direction
  // dir with the given clearance and slack, `left` from the segment's end: field_cell_advance on
  // y's cell (0 where y lies outside the lattice, so that the caller's Lipschitz step is kept).
  double sweep_advance(const Vec3& y, const SignedDistance& sd, const Vec3& dir, double clearance,
                       double slack, double left) const;

 private:
  const VoxelTooth& tooth_;
  const SampledField& field_;
};

// What edit_field_for_removed_voxels did (summed over calls).
struct FieldEditStats {
  long voxels = 0;            // removed voxels subtracted (counted when a voxel's box is done)
  long samples_scanned = 0;   // samples read (of the ball, those the row bounds let pass)
  long samples_queried = 0;   // samples the removal may change (the rule's candidates)
  long samples_bounded = 0;   // of those, answered without a voxel-distance query: inside ones
                              // by the closed form, outside ones by a listed solid voxel
                              // (reference/tooth/field_edit_core.h)
  long samples_raised = 0;    // samples whose value rose
  long samples_lost = 0;      // raises refused for want of a spare brick (field then conservative)
  long rows_read = 0;         // rows of a voxel's box whose row bounds were read
  long cells_measured = 0;    // cells whose Lipschitz bound was re-measured (with repeats)
  long work = 0;              // the budget's units spent (weights below, field_edit_core.h)
};

// The budgeted edit's work, in units of one sample read (field_edit_core.h): a removed voxel's
// set-up (its 26 neighbours listed), a row of its box that reaches the row bounds, a sample read,
// a voxel-distance query (an outside candidate no listed voxel answers: the octree, or in the fast
// twin its kept distance; the same charge in both twins, so both pause at the same rows), and the
// cells whose Lipschitz bound is re-measured (kFieldEditCellsPerUnit a unit, rounded up per row).
// Measured with callgrind over the fast edit of tests/fast/field_test.cc's path (docs/benchmarks.md
// "The field edit's budget of work per tick"): a sample read with its share of the rows, voxels
// and candidates 597 instructions, a distance call 1 513 on the mean (2.5 units; an octree query
// 6 032, 10.1 units; a kept answer far less), a cell 188 (1/3 unit). The query's weight lies
// between the mean and an octree query; the cell's, set before that measurement, is below its
// cost (1 per 3 cells would match).
inline constexpr long kFieldEditVoxelWeight = 4;
inline constexpr long kFieldEditRowWeight = 1;
inline constexpr long kFieldEditQueryWeight = 4;
inline constexpr long kFieldEditCellsPerUnit = 8;
// The batch at stride k > 1 (field_edit_core.h): at most kFieldEditGroup consecutive removed
// voxels with the same box centre floor(c / k) are subtracted in one visit of the box; each
// sample read then also costs the least over the group's voxels (~12 instructions a voxel),
// charged group / kFieldEditGroupPerUnit units (a unit ~600 instructions: field_contact.h above).
inline constexpr int kFieldEditGroup = 64;
inline constexpr long kFieldEditGroupPerUnit = 16;
// The units charged for `cells` re-measured cells.
inline constexpr long field_edit_cell_work(long cells) {
  return (cells + kFieldEditCellsPerUnit - 1) / kFieldEditCellsPerUnit;
}
// The most work one step of the edit adds between two of its budget checks (before a voxel's
// set-up and before each row of its box): a voxel's set-up, or a row of 2R + 1 samples each read
// and queried, and its raises' cells (x in [x_lo - 1, x_hi], two rows of cells in y and z).
// At stride k > 1 a sample read also carries its group's charge (kFieldEditGroupPerUnit).
inline constexpr long field_edit_step_work(int reach, int stride = 1) {
  const long width = 2L * reach + 1;
  const long group = stride > 1 ? kFieldEditGroup / kFieldEditGroupPerUnit : 0;
  const long row = kFieldEditRowWeight + width * (1 + kFieldEditQueryWeight + group) +
                   field_edit_cell_work(4 * (width + 1));
  return row > kFieldEditVoxelWeight ? row : kFieldEditVoxelWeight;
}

// Where a budgeted edit stopped (edit_field_for_removed_voxels with a cursor): the voxel of
// `removed` being subtracted and the next row (dz, dy) of its box, row = (dz + R) (2R + 1) + dy +
// R. The edit of `removed` is whole when next == removed.size(). Plain data: preallocated by its
// owner (the provider, tooth_contacts.h), nothing in the tick.
struct FieldEditCursor {
  std::size_t next = 0;
  int row = 0;
  // At stride k > 1: the length of the group (batch) of `removed` from `next` being subtracted
  // when row > 0 (field_edit_core.h), so that a resumed group is the one begun.
  std::size_t group = 0;
};

// Drilling edits the field (docs/derivations/field_contact.md §5): `removed` are the flat indices
// of voxels of `tooth` that drilling just removed (drill_tick; the octree already without them).
// For each, every sample s with |s - p_v|_inf <= R = SampledField::edit_radius() = ceil(c_out / h
// + 1) samples (p_v the voxel's centre; at stride k > 1, within R = ceil(R_v / k) samples of
// floor(c / k) + P, the voxels edited in batches: field_edit_core.h) whose value v(s) < c_out and whose distance to the voxel's cube grown by h / 2
// is <= |v(s)| (the cube, or the source's sub-voxel sliver next to it, held s's nearest surface,
// so the removal may change v(s)) is set to
//     v(s) <- max(v(s), -dist(p(s), C_v))                 if s's voxel is still solid,
//     v(s) <- max(v(s), clamp(d_vox(s), -c_in, c_out))    otherwise,
// C_v the removed voxel's cube (the exact inside distance to the complement stays exact: no
// query), d_vox the exact signed distance to the remaining solid voxels (`sd`: signed_distance or
// its fast twin, reach c_out, or a shorter reach that gives the same double). The field's
// Lipschitz constant is then raised to the cell bound of the cells with a changed corner (at the
// call's end), so it bounds the edited field (§2, §5). Values only rise, so
// the proxy's admissible set only grows. Bounded: at most (2R + 1)^3 sample reads (only those
// within the clamps' reach of the cube: the ball) and at most as many queries per removed voxel.
// The loop is written once for this and the fast twin (reference/tooth/field_edit_core.h, which
// also says why its savings change no value). Never allocates (new bricks come from the field's spare room,
// SampledField::reserve_spare_bricks) or throws; returns false if a raise found no spare brick
// (that sample keeps its value: the field then lags the voxels there, on the safe side).
// With `cursor`: resumes there and spends about `budget` units of work (the weights below; at
// most max(budget - 1, kFieldEditVoxelWeight) + field_edit_step_work(R), budget >= 1), leaving
// the cursor where the next call resumes (field_edit_core.h edit_field: a budgeted edit is safe
// after every call and ends where the whole edit ends).
bool edit_field_for_removed_voxels(SampledField* field, const VoxelTooth& tooth,
                                   std::span<const std::size_t> removed, SignedDistanceFn sd,
                                   FieldEditStats* stats, FieldEditCursor* cursor = nullptr,
                                   long budget = 0);

}  // namespace dentsim
