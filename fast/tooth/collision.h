// Fast collision of the tool-tip sphere with the voxel tooth: the twin of
// reference/tooth/collision.h (thesis §2.5.2, §2.3 (2.15)-(2.16)), which states the contact model.
// This file computes the same contact set -- same members, same order, same voxel indices, the
// doubles from the same arithmetic -- faster:
// - free-space early out: the sphere's voxel box (padded by one voxel, so rounding can only widen
//   it) against the solid's bounding box and the grid; a miss costs a few flops;
// - candidates: only SURFACE voxels (fast/tooth/brick_tooth.h), in the reference octree's order,
//   filtered per brick by the box with 64-bit masks and then by the reference's own exact
//   predicate sphere_intersects_voxel (so the candidate set is the reference's minus the voxels
//   with no exposed face, which emit nothing there);
// - patch bounds: q_u = clamp(c_u, lo_u, hi_u) needs only the bound on c's side of the face, and
//   only until the run passes c_u, so the walk along coplanar exposed faces goes one way and
//   stops early; the clamped value equals the reference's (the header of collision.cc proves it);
// - disk_rect_area: a face square well inside the contact disk skips the reference's sweep (its
//   result there is one product difference, decided with a margin); otherwise the reference's.
// Units and frames as the reference: world frame, metres.
#pragma once

#include <cstddef>
#include <limits>
#include <vector>

#include "fast/tooth/brick_tooth.h"
#include "reference/core/params.h"
#include "reference/core/types.h"
#include "reference/tooth/collision.h"

namespace dentsim::fast {

// Bitwise equal to dentsim::disk_rect_area (collision.cc: the inside-the-disk shortcut).
double disk_rect_area(double a, double x0, double x1, double y0, double y1);

// The twin of dentsim::collide_tool_tip over the fast tooth (same arguments, no scratch: nothing
// is stored between the candidate walk and the faces). Throws InputError if rho <= 0 (validate
// once outside the tick: validate_tool_tip); otherwise never throws and never allocates beyond
// the vectors' capacity; returns false when the set would exceed max_contacts.
bool collide_tool_tip(const BrickTooth& tooth, const Pose& proxy, const ToolTip& tip,
                      double k_tooth, double b_tooth, std::vector<Contact>* contacts,
                      std::vector<std::size_t>* contact_voxels = nullptr,
                      std::size_t max_contacts = std::numeric_limits<std::size_t>::max());

// Inclusive voxel box [lo, hi] that holds every voxel the sphere (c, rho) can intersect, clipped
// to the solid's bounding box; false (nothing to test) when it is empty or c is not finite.
bool sphere_voxel_box(const BrickTooth& tooth, const Vec3& c, double rho, int lo[3], int hi[3]);

// The candidate stage alone: appends to `out` the flat indices of the surface voxels that the
// sphere (c, rho) intersects (sphere_intersects_voxel), in the reference octree's order. Used by
// the benchmarks against other voxel structures (bench/tooth_vdb_bench.cc) and by tests.
void sphere_surface_voxels(const BrickTooth& tooth, const Vec3& c, double rho,
                           std::vector<std::size_t>* out);

}  // namespace dentsim::fast
