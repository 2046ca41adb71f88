// Contact that never tunnels: the exact signed distance to the voxel tooth and a surface proxy
// (god-object) kept outside it (BEYOND THE THESIS: the thesis's model is the face model of
// reference/tooth/collision.h; derivation in docs/derivations/sdf_contact.md).
//
// Frames and units: world frame {O}, metres. The solid S is the union of the closed boxes of the
// solid voxels of the grid (reference/tooth/voxel_grid.h); the tip is a sphere of radius rho.
//
// Signed distance (exact, no stored field): phi(x) = dist(x, S) >= 0 for x outside S, and
// phi(x) = -dist(x, complement of S) < 0 for x inside a solid voxel. |grad phi| = 1 almost
// everywhere and phi is 1-Lipschitz: |phi(x) - phi(y)| <= |x - y| (SD1). Outside S it is found by
// a nearest-box search in the octree (prune every node whose box is farther than the best so
// far), so it is up to date under drilling with no update step: drilling edits the octree.
//
// Surface proxy g (the tip centre as rendered): the set of admissible tip centres is
//   A = { x : phi(x) >= rho }   (the tip sphere does not overlap the solid).
// Each tick, given the tool's tip centre c (the PMI proxy x_2 + R_2 o):
//   1. push-out (shortest way): x = P(c), the point reached from c by x <- q + rho u, q the
//      nearest point of S (outside: u = (x - q)/|x - q|) or of its complement (inside:
//      u = (q - x)/|q - x|), repeated until phi(x) >= rho (a concave corner takes a few steps);
//   2. swept test: g moves to x only if the segment g -> x stays in A_skin = {phi >= rho - s}
//      (conservative advancement: from y, a step of phi(y) - (rho - s) along the segment stays in
//      A_skin by (SD1)). Crossing a wall needs phi <= 0 on the way, and s < rho, so g never
//      crosses material, whatever the tool's speed or the wall's thickness (one voxel included);
//   3. if the segment is blocked (the shortest way came out on another side, or c jumped through
//      a wall), g advances to where the sweep stopped, is pushed back into A, and slides: the next
//      target is c projected onto the tangent plane at g (normal n = grad phi(g)); up to
//      kSurfaceProxySlides slides per tick.
// The contact is the spring between c and g: n = (g - c) / |g - c|, depth delta = |g - c|,
// x_o = g - rho n (on the surface), x_c = c - rho n (the point of the tool's sphere deepest along
// -n), so delta = n^T (x_o - x_c) as in (2.15); there is a contact iff g != c.
//
// Real-time: every query walks a fixed-size stack; nothing allocates or throws.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>

#include "reference/core/types.h"
#include "reference/tooth/collision.h"

namespace dentsim {

// The nearest point of the solid (outside) or of its complement (inside) to a query point.
struct SignedDistance {
  double phi = std::numeric_limits<double>::infinity();  // signed distance [m]
  Vec3 nearest = Vec3::Zero();  // nearest point of S (phi >= 0) or of the complement (phi < 0)
  std::size_t voxel = 0;        // the solid voxel holding `nearest` (phi >= 0) or x (phi < 0)
  bool found = false;           // false: phi >= `reach` (no solid within reach; phi = reach)
};

// phi(x) with the search limited to `reach` [m] (> 0): if no solid lies within reach of x,
// returns found = false and phi = reach; inside, the depth is capped at -reach likewise
// (found = true, nearest = x + reach * (direction of the grid's nearest outside)). Exact
// otherwise.
SignedDistance signed_distance(const VoxelTooth& tooth, const Vec3& x, double reach);

// A signed-distance query with signed_distance's contract: the surface proxy and its contact take
// one, so that the fast pipeline can give its twin (fast/tooth/sdf.h) to the same algorithm.
using SignedDistanceFn = SignedDistance (*)(const VoxelTooth& tooth, const Vec3& x, double reach);

// The parts of signed_distance its twins share (same arithmetic, so the same doubles).
namespace sdf_detail {
// Squared distance from x to the box of cells [lo, hi) (voxel indices), and its nearest point.
double box_distance2(const VoxelGrid& grid, const int lo_idx[3], const int hi_idx[3], const Vec3& x,
                     Vec3* nearest);
// The voxel holding x (floor of the grid coordinates); false outside the grid.
bool voxel_of(const VoxelGrid& grid, const Vec3& x, int idx[3]);
// The outside search's order-free rule: a box at squared distance d2 holding solid voxel v beats
// the best so far if it is nearer, or as near with a smaller flat index (boxes exactly as near are
// common where the surface proxy sits between walls: the rule makes the answer the same whatever
// order a search visits them in). A node's box at d2 may hold such a box iff prunable() is false.
inline bool sdf_nearer(double d2, std::size_t v, double best2, const SignedDistance& best) {
  return d2 < best2 || (best.found && d2 == best2 && v < best.voxel);
}
inline bool sdf_prunable(double d2, double best2, const SignedDistance& best) {
  return !(d2 < best2 || (best.found && d2 == best2));
}
// Inside solid voxel idx: the nearest point of the complement within reach (shell search).
SignedDistance inside_distance(const VoxelGrid& grid, const Vec3& x, const int idx[3],
                               double reach);
// signed_distance with the outside descent's child order chosen: fixed (0..7, the reference's)
// or nearest first (fast::signed_distance). Same answer either way (sdf_nearer).
SignedDistance signed_distance_ordered(const VoxelTooth& tooth, const Vec3& x, double reach,
                                       bool nearest_first);
}  // namespace sdf_detail

// The outward unit normal at x from its nearest point (phi != 0); for phi == 0 (x on S) the
// direction from the centre of `voxel` to x.
Vec3 distance_gradient(const VoxelTooth& tooth, const Vec3& x, const SignedDistance& sd);

// The sampled field's solid (reference/tooth/field_contact.h), for SurfaceProxy::update below.
class FieldSolid;

namespace proxy_detail {
// The surface proxy's constants (its algorithm: reference/tooth/surface_proxy_core.h).
struct ProxyConstants {
  double rho;   // tip radius [m]
  double skin;  // s = min(rho / 4, h / 2) [m]
  double tol;   // distance below which two points are the same [m]
  // The push-out (step 1) stops once phi >= rho - push_tol: push_tol = s / 100, inside the skin
  // set A_s by 0.99 s, so the no-tunnelling proof (which needs only A_s) is unchanged. Without it
  // a push-out in a concave corner zig-zags between two walls, closing the gap to phi = rho only
  // geometrically, and on a face q + rho u can round to phi = rho minus a few ulps: either way it
  // ran to its cap (docs/derivations/sdf_contact.md §2 step 1, §5).
  double push_tol;
};
}  // namespace proxy_detail

inline constexpr int kSurfaceProxySlides = 4;       // slides per tick (step 3)
inline constexpr int kSurfaceProxyPushOuts = 16;    // push-out iterations (step 1)
inline constexpr int kSurfaceProxySweepSteps = 64;  // conservative-advancement steps per segment

// The surface proxy of one tip sphere on one tooth (state: g).
class SurfaceProxy {
 public:
  // rho [m] > 0 (checked by the owner). Skin s = min(0.25 rho, 0.5 h). `sd`: the signed-distance
  // query every step uses (the reference's, or the fast pipeline's twin).
  SurfaceProxy(double rho, double voxel_size, SignedDistanceFn sd = &signed_distance);

  // Steps 1-3 for the tool's tip centre c; returns g. The first call starts from g = c.
  const Vec3& update(const VoxelTooth& tooth, const Vec3& c);
  // The same steps on the sampled field of the tooth's source surface (the "field" model,
  // reference/tooth/field_contact.h); the skin is this proxy's (min(rho/4, h/2)).
  const Vec3& update(const FieldSolid& solid, const Vec3& c);
  // The same steps on any Solid of reference/tooth/surface_proxy_core.h (defined there): a twin
  // of FieldSolid with the same answers (the fast pipeline's, fast/tooth/field.h).
  template <class Solid>
  const Vec3& update_on(const Solid& solid, const Vec3& c);
  // Forgets g (the next update starts from c again).
  void reset() { valid_ = false; }
  const Vec3& g() const { return g_; }
  bool valid() const { return valid_; }
  double skin() const { return skin_; }
  proxy_detail::ProxyConstants constants() const { return {rho_, skin_, tol_, 0.01 * skin_}; }

  // Moves x into A along the shortest way (step 1); returns the final phi(x) - rho (>= 0 unless
  // the iteration cap was hit, which the crosscheck counts as penetration; 0 when x is outside
  // with phi >= rho: only the sign matters there, and the search stops at rho).
  double push_out(const VoxelTooth& tooth, Vec3* x) const;
  // Conservative advancement from `from` towards `to` within A_skin; returns true if `to` was
  // reached, else leaves *from at the last point reached.
  bool sweep(const VoxelTooth& tooth, Vec3* from, const Vec3& to) const;

 private:
  double rho_;
  double skin_;
  double tol_;  // distance below which two points are the same [m]
  SignedDistanceFn sd_;
  bool valid_ = false;
  Vec3 g_ = Vec3::Zero();
};

// The contact of the tool's sphere at tip centre c with surface proxy g (header comment); false
// (and *out untouched) when g == c. k_tooth [N/m], b_tooth [N s/m] are scaled by the material of
// the solid voxel nearest to g (found by `sd`).
bool surface_proxy_contact(const VoxelTooth& tooth, const Pose& proxy, const ToolTip& tip,
                           const Vec3& g, double k_tooth, double b_tooth, Contact* out,
                           SignedDistanceFn sd = &signed_distance);

// surface_proxy_contact in its parts, for a provider that finds the material its own way (the
// fast pipeline's, fast/tooth/cut_set.h): the geometry (n, x_o, r, depth and weight 1; false and
// *out untouched when g == c); the reach of the material's search (2 rho); the material of the
// solid voxel nearest to g within that reach by `sd` (kEmpty when none); and the contact's
// material, stiffness and damping for a material (kEmpty: enamel).
bool surface_proxy_geometry(const Pose& proxy, const ToolTip& tip, const Vec3& g, Contact* out);
inline double proxy_material_reach(double rho) { return 2.0 * rho; }
std::uint8_t proxy_material(const VoxelTooth& tooth, const Vec3& g, double rho,
                            SignedDistanceFn sd = &signed_distance);
void set_contact_material(std::uint8_t material, double k_tooth, double b_tooth, Contact* out);

}  // namespace dentsim
