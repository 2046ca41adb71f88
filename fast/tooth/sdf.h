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

class SurfaceVoxels;  // fast/tooth/cut_set.h

// The sdf model's local distance query (issue #30, stop 46): the outside answer of
// signed_distance (phi, nearest, voxel: the octree descent's, bitwise) from the tooth's exposed
// voxels (SurfaceVoxels, the bits the cut set keeps current under drilling), searched about the
// query point instead of from the octree's root.
//
// The search. The reference's answer outside is the solid voxel v* minimising (D(v), v) over the
// solid voxels with D < reach^2 (D: box_distance2's double; the descent prunes only nodes whose
// box, which holds their voxels' boxes, is no nearer, and a node box's terms are no larger than
// its voxels' by monotone rounding). The twin minimises the same key over the exposed voxels: the
// bricks of 8^3 voxels about x (one brick of margin beyond the bound on each side, far above the
// rounding of the floors), skipping a brick, a 4^3 word, a 2^3 byte whose box is already no
// nearer than the best (sdf_prunable; a block's term on an axis is the least of its voxels',
// so the box test never loses a voxel the voxel test would take), and the voxels by the same
// terms box_distance2 sums, in its order ((t_x + t_y) + t_z): the same D. Temporal coherence:
// the voxel of the last answer, while it is still exposed, is the first candidate, and its D the
// search's first bound (the proxy's queries in a tick, and from tick to tick, lie within a few
// voxels of each other, so the bound is nearly the answer's and few blocks are opened).
//
// Claim: if x is at least eps = 2^-23 reach from every grid plane origin_a + h i on every axis,
// h >= eps and eps >= 2^-44 (|origin|_inf + N h + reach), the exposed minimum is v* (and when no
// exposed voxel has D < reach^2, no solid voxel has). Proof: SurfaceCutSet's (fast/tooth/
// cut_set.h, "The material"), with reach for its R': a non-exposed v* has six solid face
// neighbours; D(v*) = 0 would put x in v*'s cell by voxel_of (an outside query is not in a solid
// voxel's cell); the face neighbour towards x on an axis where x is below v*'s slab is as near and
// has a smaller index; above it, it is nearer by more than the roundings (terms differing by
// >= eps^2 = 2^-46 reach^2 against errors <= 2^-51 reach^2). For "none found": from any solid v
// with D(v) < reach^2 the same steps (each to a face neighbour no farther, towards x) reach an
// exposed voxel, or a voxel with D = 0, excluded as above. Otherwise (x near a plane, the bits
// not current, a reach beyond the bounds below) outside() returns false and the caller asks the
// octree (counted: fallbacks()).
//
// Nearest first (stop 47; the walk shared with the field model's material since stop 48, fast/
// tooth/nearest_voxel_walk.h). The bricks within the bound are searched by increasing box distance,
// in a brick its 4^3 words likewise, and a 2^3 byte's box is shrunk to its set bits per axis
// (kByteLayers, a table of 256: a byte's term on an axis is the least of its set voxels'), so
// bytes in the cap about the tangent point are pruned. The first bound is the least (D, index)
// of the last answer's voxel and the balls' voxels (below), each taken only while solid: any
// solid voxel's key bounds the answer's, and the exposed minimum is the solid one (the claim).
//
// The balls (stop 47): no search where an earlier answer is certified. A search that found v at
// x0 also bounds every other solid voxel's squared distance from x0 below by L: the least of
// (a) the bounds of the blocks it pruned and the D of the voxels (and first candidates) it did
// not keep, (b) (r + 4 h)^2 for the bricks beyond its span (more than r + 7 h away), and (c) D
// of v's solid face neighbours. Claim: every solid voxel u != v of the tooth at that time has
// D(u) >= L. An exposed u was pruned or tested (a), or lies beyond the span (b). An interior u:
// x0 is in no solid voxel's cell and at least eps from the grid planes, so some term of u is
// > 0 and u's face neighbour towards x0 on that axis is solid and no farther (the claim's step);
// repeating, the chain reaches an exposed voxel w with D(w) <= D(u): w != v gives D(u) >= L by
// (a)/(b), and w = v means the voxel before it is a solid face neighbour of v (c). Drilling only
// removes voxels, so the bound holds while v stays solid. Then at a later x with d = |x - x0|,
// if sqrt(L) - d >= phi_v(x) + m (phi_v(x) = sqrt(D_v(x)), D_v by box_distance2's terms in its
// order, m = 1e-9 h + 1e-12 sqrt(L)), v is the answer at x: every other solid voxel is at least
// sqrt(L) - d away (1-Lipschitz) and m covers the roundings (each D within 5 u = 5 2^-53 of its
// exact square, the norm and the differences within a few u, far below 1e-12); the answer is
// (phi_v, the clamp of x to v's box, v) when D_v(x) < reach^2, and nothing within reach
// otherwise: the search's own doubles. The last kBalls balls are kept across ticks. A point on a
// grid plane may be answered from a ball (the ball's argument does not need the plane guard).
//
// Real-time: fixed-size arrays on the stack; nothing allocates or throws.
class LocalVoxelDistance {
 public:
  // `tooth` and `surface` (its exposed voxels, kept current by their owner) outlive this.
  LocalVoxelDistance(const VoxelTooth& tooth, const SurfaceVoxels& surface);
  // For x not in a solid voxel's cell and reach > 0: signed_distance(tooth, x, reach)'s answer into
  // *out and its squared distance into *best2 (+inf: nothing within reach), true; false (nothing
  // written) when the claim above does not certify it.
  bool outside(const Vec3& x, double reach, SignedDistance* out, double* best2) const;
  // Counters (tests and benchmarks): outside() calls, those that returned false, the voxels whose
  // distance they computed, and the calls answered from a ball (no search).
  long queries() const { return queries_; }
  long fallbacks() const { return fallbacks_; }
  long voxels_tested() const { return voxels_tested_; }
  long reused() const { return reused_; }
  // Forgets the last answer's voxel (the next search starts without a bound).
  void forget() const {
    have_hint_ = false;
    ball_count_ = 0;
  }

  // The largest brick span on an axis the search's arrays hold (a wider reach falls back).
  static constexpr int kMaxSpan = 24;

 private:
  const VoxelTooth& tooth_;
  const SurfaceVoxels& surface_;
  double max_reach_;  // 2^23 h: h >= eps
  double extent_;     // |origin|_inf + N h
  mutable std::size_t hint_ = 0;
  mutable bool have_hint_ = false;
  // The balls about earlier answers' points in which their voxel stays the answer (the last
  // kBalls, the oldest making room).
  struct Ball {
    Vec3 x;
    double lower;   // no other solid voxel is nearer to x than this
    double margin;  // the rounding allowance of the test
    std::size_t voxel;
  };
  static constexpr int kBalls = 8;
  mutable std::array<Ball, kBalls> balls_{};
  mutable int ball_count_ = 0, ball_next_ = 0;
  mutable long queries_ = 0, fallbacks_ = 0, voxels_tested_ = 0, reused_ = 0;
};

// The sdf model's free-space certificate (issue #30; the field model's is in fast/tooth/field.h):
// a lower bound on the distance from the tip to the solid kept across ticks, so that while the
// tip is farther from the tooth than its travel since the last exact query, no query reads the
// octree. It lives as long as the provider that owns it; the tooth it is used with may only lose
// voxels (drilling) while it lives.
// Claim: let D_t(x) be the Euclidean distance from x to the union of the solid voxels' boxes at
// time t, each box with the corners box_distance2 computes (origin + h i, rounded). If an outside
// query at x0 found its answer at squared distance best2 (lower = sqrt(best2)), or found nothing
// within reach R' (lower = R'), and later
//     lower - |x - x0| >= reach + margin,   margin = 1e-9 h + 1e-12 lower,
// then signed_distance(tooth, x, reach) returns {phi = reach, found = false} (bitwise: every other
// field its default). Proof: (1) D_then(x0) >= lower (1 - 10 u) (u = 2^-53): each leaf's computed
// d2 is its exact square within 5 u relative (a rounded difference, square and two sums of
// non-negative terms), the search's pruning by node boxes that contain their children loses no
// leaf by more than that, and sqrt rounds within u. (2) Drilling only removes boxes, so D_now >=
// D_then, and D is 1-Lipschitz: D_now(x) >= lower (1 - 10 u) - |x - x0| (the computed norm within
// 3 u of the exact); with the test's own two roundings, D_now(x) >= reach + margin - 16 u
// (lower + |x - x0|) > reach (1 + 3 u) (|x - x0| <= lower when the test passes; margin >= 32 u
// lower). (3) Then every leaf's computed d2 at x is >= fl(reach^2) (5 u and u again), so the outside
// search accepts none and returns reach, not found; and x is not in a solid voxel by voxel_of's
// floor((x - origin) / h) either, which differs from the boxes by a few ulps of the coordinates,
// far below 1e-9 h > 0 of clearance. So the certified answer is the query's own.
class FreeSpaceCertificate {
 public:
  // True when (x, reach > 0) is answered {phi = reach, found = false} by the claim above.
  bool certifies(const Vec3& x, double reach) const {
    if (!have_ || !(reach > 0.0)) return false;
    return lower_ - (x - x0_).norm() >= reach + margin_;
  }
  // An exact outside query at x0 found nothing nearer than `lower` (claim above); h the voxel size.
  void record(const Vec3& x0, double lower, double h) {
    have_ = true;
    x0_ = x0;
    lower_ = lower;
    margin_ = 1e-9 * h + 1e-12 * lower;
  }
  // The reach of the exact query a certificate is taken from: the query's, widened by
  // kWidenVoxels voxels, so that "nothing within reach" still certifies the next ticks' queries
  // while the tip travels less than that.
  static double widened(double reach, double h) { return reach + kWidenVoxels * h; }
  static constexpr double kWidenVoxels = 8.0;
  // Counters for tests and benchmarks: queries answered by the certificate, and exact ones.
  long certified() const { return certified_; }
  long evaluated() const { return evaluated_; }
  void count(bool certified) const { ++(certified ? certified_ : evaluated_); }

 private:
  bool have_ = false;
  Vec3 x0_ = Vec3::Zero();
  double lower_ = 0.0;
  double margin_ = 0.0;
  mutable long certified_ = 0, evaluated_ = 0;
};

// The outside answers a RecallingVoxelSolid remembers (the last kEntries, the oldest making room).
// A provider may keep them across updates (SdfContactProvider: the proxy's first queries of a
// tick are at the g the last tick left): the tooth may only lose voxels meanwhile (drilling), and
// an answer whose voxel is no longer solid is not used. Removals keep every other answer: a found
// voxel still solid is still the least (D, index) of a subset holding it, and "nothing within R"
// stays true.
struct RecalledAnswers {
  struct Entry {
    Vec3 x;
    double reach;
    double best2;  // the answer's d2, +inf: nothing within reach
    SignedDistance sd;
  };
  static constexpr int kEntries = 16;
  std::array<Entry, kEntries> entries{};
  int count = 0;
  int next = 0;
};

// The surface proxy's Solid (reference/tooth/surface_proxy_core.h) on fast::signed_distance for
// one update of the proxy (the tooth must not change while it lives): it remembers its last
// outside answers (RecalledAnswers; its own, or the provider's kept across updates) and answers a
// query at the same point (bitwise) from them where the contract decides it (an answer found
// within reach R is the answer within every reach whose square exceeds its d2; "nothing within
// R" is the answer within every shorter reach), so its answers are the query's own. The proxy
// asks the same point again and again within a tick: the swept test starts where the push-out
// ended, a slide asks at the g the push-out left.
// With a certificate (the provider's, kept across ticks): a query it certifies reads nothing; an
// outside query it does not is searched within FreeSpaceCertificate::widened(reach), answered
// at `reach` by the same rule as a remembered answer, and renews the certificate.
// With a local query (LocalVoxelDistance, the provider's: its last answer's voxel kept across
// ticks) every outside search asks it first, the octree where it cannot certify its answer.
class RecallingVoxelSolid {
 public:
  explicit RecallingVoxelSolid(const VoxelTooth& tooth, FreeSpaceCertificate* certificate = nullptr,
                               const LocalVoxelDistance* local = nullptr,
                               RecalledAnswers* kept = nullptr)
      : tooth_(tooth), certificate_(certificate), local_(local), kept_(kept) {}
  const VoxelTooth& tooth() const { return tooth_; }
  SignedDistance distance(const Vec3& x, double reach) const;
  Vec3 normal(const Vec3& x, const SignedDistance& sd) const {
    return distance_gradient(tooth_, x, sd);
  }
  double lipschitz() const { return 1.0; }

 private:
  // The search at x (not in a solid voxel) within the certificate's widened reach, renewing it.
  SignedDistance certified_search(const Vec3& x, double reach) const;
  // The outside search at x (not in a solid voxel; the octree's levels > 0): the local query's,
  // else the octree's; *best2 as outside_distance's.
  SignedDistance search_outside(const Vec3& x, double reach, double* best2) const;
  void remember(const Vec3& x, double reach, double best2, const SignedDistance& sd) const;
  RecalledAnswers& answers() const { return kept_ != nullptr ? *kept_ : own_; }

  const VoxelTooth& tooth_;
  FreeSpaceCertificate* certificate_;
  const LocalVoxelDistance* local_;
  RecalledAnswers* kept_;
  mutable RecalledAnswers own_;
};

}  // namespace dentsim::fast
