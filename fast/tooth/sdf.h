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
// Its own descent (fast/tooth/sdf.cc, issue #30's "fast path that is fast"): the reference
// computes box_distance2 for each of a node's up to 8 children, 3 clamps and 6 coordinate
// products each; a child box's extent on each axis is one of the node's two halves, so the
// clamp and the squared gap of each half are computed once per node (6 of each) and a child's
// d2 is (t_x + t_y) + t_z: box_distance2's own terms summed in its own order, the same doubles.
// The node's occupancy byte is read by its morton code carried down the descent (8 m + child),
// not recomputed from (level, x, y, z).
//
// Real-time: a fixed-size stack; nothing allocates or throws.
#pragma once

#include <array>

#include "reference/tooth/sdf.h"

namespace dentsim::fast {

// The twin of dentsim::signed_distance (same arguments and result).
SignedDistance signed_distance(const VoxelTooth& tooth, const Vec3& x, double reach);
// The same, and *outside_best2: for x outside the solid the search's squared distance of the
// answer (+inf when nothing lies within reach), -1 for x inside (or a single-voxel grid).
SignedDistance signed_distance(const VoxelTooth& tooth, const Vec3& x, double reach,
                               double* outside_best2);

// The surface proxy's Solid (reference/tooth/surface_proxy_core.h) on fast::signed_distance for
// one update of the proxy (the tooth must not change while it lives): it remembers its last
// kEntries outside answers and answers a query at the same point (bitwise) from them where the
// contract decides it (an answer found within reach R is the answer within every reach whose
// square exceeds its d2; "nothing within R" is the answer within every shorter reach), so its
// answers are the query's own. The proxy asks the same point again and again within a tick: the
// swept test starts where the push-out ended, a slide asks at the g the push-out left.
class RecallingVoxelSolid {
 public:
  explicit RecallingVoxelSolid(const VoxelTooth& tooth) : tooth_(tooth) {}
  const VoxelTooth& tooth() const { return tooth_; }
  SignedDistance distance(const Vec3& x, double reach) const;
  Vec3 normal(const Vec3& x, const SignedDistance& sd) const {
    return distance_gradient(tooth_, x, sd);
  }
  double lipschitz() const { return 1.0; }

 private:
  struct Entry {
    Vec3 x;
    double reach;
    double best2;  // the answer's d2, +inf: nothing within reach
    SignedDistance sd;
  };
  static constexpr int kEntries = 16;
  const VoxelTooth& tooth_;
  mutable std::array<Entry, kEntries> memo_{};
  mutable int count_ = 0;
  mutable int next_ = 0;
};

}  // namespace dentsim::fast
