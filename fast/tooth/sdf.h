// The fast twin of the exact signed distance to the voxel tooth (reference/tooth/sdf.h, beyond
// the thesis; derivation docs/derivations/sdf_contact.md), which the surface-proxy contact model
// ("sdf", the scenes' default) queries 10-60 times a tick: push-out, swept test, slides.
//
// Same contract, same tooth (the reference's VoxelTooth: its octree is what drilling keeps up to
// date), same code: sdf_detail::signed_distance_ordered, the reference's shell search inside and
// its pruned octree descent outside, with one change of order: at every node the occupied children
// are visited nearest first (their box distances sorted), so the first leaves reached are the
// nearest and the bound best^2 tightens at once; the reference visits children in a fixed order
// (7..0) and may scan a far subtree within reach before the near one. Every box distance is
// computed by the reference's own sdf_detail::box_distance2, so phi is the same double (the minimum
// of the same numbers), and boxes exactly as near are decided by the same order-free rule
// (sdf_detail::sdf_nearer: the smaller voxel index), so `nearest` and `voxel` are the same too
// (tests/fast/sdf_test.cc: bitwise, on random, grid-aligned and surface-proxy queries).
//
// Real-time: a fixed-size stack; nothing allocates or throws.
#pragma once

#include "reference/tooth/sdf.h"

namespace dentsim::fast {

// The twin of dentsim::signed_distance (same arguments and result).
SignedDistance signed_distance(const VoxelTooth& tooth, const Vec3& x, double reach);

}  // namespace dentsim::fast
