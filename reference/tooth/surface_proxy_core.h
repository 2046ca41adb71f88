// The surface proxy's algorithm (reference/tooth/sdf.h, docs/derivations/sdf_contact.md §2), once,
// for any solid that answers a signed-distance query: the exact distance to the voxel solid
// ("sdf", reference/tooth/sdf.h) or the sampled field of the source surface ("field",
// reference/tooth/field_contact.h). Beyond the thesis.
//
// A Solid provides
//   const VoxelTooth& tooth() const;          the voxel tooth (its grid says inside / outside)
//   SignedDistance distance(const Vec3& x, double reach) const;
//       phi(x) (found = false and phi = reach when phi >= reach), and the nearest point
//       `nearest` of the surface along the normal: x - phi n;
//   Vec3 normal(const Vec3& x, const SignedDistance& sd) const;   unit grad phi at x;
//   double lipschitz() const;                 L: |phi(x) - phi(y)| <= L |x - y|;
// and, to take the field-only paths (below), the compile-time claim
//   static constexpr bool kFieldPaths = true;
// with, then required (a static_assert), sweep_advance (the sweep's step from the cell's slope)
// and slope(x) = |grad phi(x)| (the push-out's Newton step, plain_step below).
//
// The field-only paths (proxy_detail::kFieldPaths<Solid>): the push-out's Newton step
// (plain_step), the cell-certified sweep step (sweep) and the stalled-slide stop (update). Each
// rests on the sampled field's interpolant (docs/derivations/field_contact.md §3) and moves the
// proxy to a different admissible point than the steps it replaces, so a Solid takes them only by
// saying so: a Solid that does not declare kFieldPaths (the `sdf` model's, reference/tooth/sdf.cc
// VoxelSolid and fast/tooth/sdf.h RecallingVoxelSolid, which static_assert that they do not)
// takes the thesis's steps, the same doubles as before the refactor, whatever methods it has.
// The swept test advances by (phi - (rho - s)) / L per step (conservative advancement under the
// L-Lipschitz bound), so the sweep never leaves {phi >= rho - s}; for the exact distance L = 1
// and the steps are the same doubles as before the refactor.
//
// Real-time: nothing allocates or throws (as long as the Solid's queries do not).
#pragma once

#include <algorithm>
#include <concepts>

#include <Eigen/LU>

#include "reference/core/types.h"
#include "reference/tooth/sdf.h"

namespace dentsim::proxy_detail {

// Whether Solid claims the field-only paths (header comment): Solid::kFieldPaths, false when it
// declares none.
template <class Solid>
inline constexpr bool kFieldPaths = requires { requires Solid::kFieldPaths; };

// What a Solid that claims the field-only paths must answer (header comment).
template <class Solid>
concept FieldPathSolid = requires(const Solid& solid, const Vec3& v, const SignedDistance& sd) {
  { solid.slope(v) } -> std::convertible_to<double>;
  { solid.sweep_advance(v, sd, v, 0.0, 0.0, 0.0) } -> std::convertible_to<double>;
};

// The claim checked where the core is instantiated: a Solid that claims the paths has them.
template <class Solid>
inline constexpr bool kSolidChecked = !kFieldPaths<Solid> || FieldPathSolid<Solid>;

// A wall the push-out has met: its offset plane {y : n . (y - q) = rho} (n the unit normal at
// the query, q the nearest point; docs/derivations/sdf_contact.md §2 step 1).
struct PushWall {
  Vec3 n;
  Vec3 q;
};

// The corner step of the push-out (docs/derivations/sdf_contact.md §2 step 1): the displacement d
// of least norm with n_i . d >= r_i for the current wall (i = 0: r_0 = rho - phi(x)) and the
// walls met before (r_i = rho - n_i . (x - q_i)), i.e. the nearest point of the intersection of
// their offset half-spaces. Enumerates the active sets that hold the current wall (a strictly
// convex QP: the one KKT point, multipliers >= 0, is its minimum); an active set whose normals are
// near-parallel (Gram determinant below kCornerMinGram) is skipped. False when the plain step
// d = r_0 n_0 already keeps every earlier wall within push_tol, or no active set qualifies.
inline constexpr double kCornerMinGram = 1e-2;  // sin^2 of the least angle between two normals
inline bool corner_step(const ProxyConstants& k, const PushWall* walls, const double* r, int count,
                        Vec3* d) {
  const Vec3 plain = r[0] * walls[0].n;
  bool violated = false;
  for (int i = 1; i < count; ++i) violated |= walls[i].n.dot(plain) < r[i] - k.push_tol;
  if (!violated) return false;
  bool found = false;
  double best = 0.0;
  // Active sets {0} + subsets of {1, .., count - 1} (bit i - 1 of `mask`), at most 3 walls.
  for (int mask = 1; mask < (1 << (count - 1)); ++mask) {
    int act[3] = {0, 0, 0};
    int m = 1;
    for (int i = 1; i < count; ++i) {
      if (mask & (1 << (i - 1))) act[m++] = i;
    }
    Eigen::Matrix3d gram = Eigen::Matrix3d::Identity();
    Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
    for (int a = 0; a < m; ++a) {
      rhs(a) = r[act[a]];
      for (int b = 0; b < m; ++b) gram(a, b) = walls[act[a]].n.dot(walls[act[b]].n);
    }
    if (!(gram.determinant() >= kCornerMinGram)) continue;
    const Eigen::Vector3d lambda = gram.inverse() * rhs;  // fixed size: closed form, no allocation
    Vec3 step = Vec3::Zero();
    bool ok = true;
    for (int a = 0; a < m; ++a) {
      ok &= lambda(a) >= 0.0;
      step += lambda(a) * walls[act[a]].n;
    }
    for (int i = 1; i < count; ++i) ok &= walls[i].n.dot(step) >= r[i] - k.push_tol;
    if (ok && (!found || step.squaredNorm() < best)) {
      found = true;
      best = step.squaredNorm();
      *d = step;
    }
  }
  return found;
}

// The push-out's step off one wall: to the nearest surface point, then rho out along the normal u
// (for the exact distance, |grad phi| = 1: phi = rho there). A Solid whose |grad phi| is not 1
// (the sampled field, field_contact.h FieldSolid::slope) takes the Newton step along u instead,
// x + (rho - phi) / |grad phi| u, where phi's linearisation along u reaches rho (one or two
// queries near a smooth surface where the unit step closes rho - phi only by the factor
// |grad phi|), if that step is no longer than phi(x) / L, the corner step's rule (the ball it
// stays in holds no solid); else the unit step (docs/derivations/field_contact.md §3).
template <class Solid>
Vec3 plain_step(const ProxyConstants& k, const Solid& solid, const Vec3& x,
                const SignedDistance& sd, const Vec3& u) {
  static_assert(kSolidChecked<Solid>, "kFieldPaths claimed without slope() and sweep_advance()");
  if constexpr (kFieldPaths<Solid>) {
    const double slope = solid.slope(x);
    if (slope > 0.0 && sd.phi > 0.0) {
      const double t = (k.rho - sd.phi) / slope;
      if (t * solid.lipschitz() <= sd.phi) return x + t * u;
    }
  }
  return sd.nearest + k.rho * u;
}

// Step 1: moves x into A = {phi >= rho - push_tol} along the shortest way; returns phi(x) - rho at
// the end (0 when phi >= rho was found within the search of reach rho; >= -push_tol when it
// converged). Each step moves x to rho outside the nearest surface point along the normal (the
// plain step), except in a concave corner: where that step would undo an earlier wall's (by more
// than push_tol), x moves onto the nearest point of the walls' offset half-spaces (corner_step),
// if that step is no longer than phi(x) / L (the ball it stays in holds no solid); the step off
// one wall is plain_step's.
template <class Solid>
double push_out(const ProxyConstants& k, const Solid& solid, Vec3* x) {
  // Inside, the shortest way out may be long: search as far as the grid's extent. Outside, all
  // that matters is whether phi >= rho (then x stays where it is): a search within rho finds the
  // nearest point exactly when it is nearer than rho and stops early otherwise.
  const VoxelGrid& grid = solid.tooth().grid();
  const double far = grid.voxel_size * grid.n;
  // walls[0]: the current one; walls[1..]: the last kPushWallsKept met before, newest first.
  constexpr int kPushWallsKept = 2;
  PushWall walls[kPushWallsKept + 1];
  double r[kPushWallsKept + 1];
  int kept = 0;
  for (int it = 0; it < kSurfaceProxyPushOuts; ++it) {
    int idx[3];
    const bool inside = sdf_detail::voxel_of(grid, *x, idx) &&
                        grid.voxels[grid.index(idx[0], idx[1], idx[2])] != kEmpty;
    const double reach = inside ? far : k.rho;
    const SignedDistance sd = solid.distance(*x, reach);
    if (!sd.found || sd.phi >= k.rho - k.push_tol) return (sd.found ? sd.phi : reach) - k.rho;
    const Vec3 u = solid.normal(*x, sd);
    walls[0] = {u, sd.nearest};
    r[0] = k.rho - sd.phi;
    for (int i = 1; i <= kept; ++i) r[i] = k.rho - walls[i].n.dot(*x - walls[i].q);
    Vec3 d = Vec3::Zero();
    if (kept > 0 && corner_step(k, walls, r, kept + 1, &d) &&
        d.norm() * solid.lipschitz() <= sd.phi) {
      *x += d;
    } else {
      *x = plain_step(k, solid, *x, sd, u);
    }
    // Remember the current wall (a near-parallel earlier one gives way to it, else the oldest).
    int slot = std::min(kept + 1, kPushWallsKept);
    for (int i = 1; i <= kept; ++i) {
      const double c = u.dot(walls[i].n);
      if (1.0 - c * c < kCornerMinGram && c > 0.0) slot = i;
    }
    for (int i = slot; i > 1; --i) walls[i] = walls[i - 1];
    walls[1] = walls[0];
    kept = std::max(kept, slot);
  }
  const SignedDistance sd = solid.distance(*x, k.rho);
  return sd.phi - k.rho;
}

// The sweep's slack for a step certified by the cell's slope (sweep below): half its blocking
// threshold (1e-3 s), so the step ends where the next query blocks, and far above the rounding
// of phi and of the slope bound (~1e-16 of a millimetre).
inline constexpr double kSweepSlack = 0.5e-3;

// Step 2: conservative advancement from `from` towards `to` within A_skin = {phi >= rho - s};
// true if `to` was reached, else *from is the last point reached.
template <class Solid>
bool sweep(const ProxyConstants& k, const Solid& solid, Vec3* from, const Vec3& to) {
  static_assert(kSolidChecked<Solid>, "kFieldPaths claimed without slope() and sweep_advance()");
  const double h = solid.tooth().grid().voxel_size;
  const double lip = solid.lipschitz();
  const double floor_phi = k.rho - k.skin;
  for (int step = 0; step < kSurfaceProxySweepSteps; ++step) {
    const Vec3 gap = to - *from;
    const double left = gap.norm();
    if (left <= k.tol) {
      *from = to;
      return true;
    }
    const double reach = floor_phi + lip * std::min(left, 4.0 * h) + k.skin;
    const SignedDistance sd = solid.distance(*from, reach);
    const double clearance = sd.phi - floor_phi;
    double advance = clearance / lip;  // a step this long stays in A_skin (Lipschitz)
    // The field (field_contact.h field_cell_advance) follows phi along the segment within the
    // cell about y exactly (a cubic from the cell's corners) and certifies a longer step: to the
    // cell's exit (a little beyond, by the Lipschitz bound) or to where phi first comes within
    // [slack, 1.5 slack] of rho - s, slack = half the blocking threshold below, so a blocked sweep
    // ends in A_skin with clearance in (0, 1e-3 s] after one more query instead of the Lipschitz
    // step's geometric approach (docs/derivations/field_contact.md §3).
    if constexpr (kFieldPaths<Solid>) {
      const double slack = kSweepSlack * k.skin;
      if (sd.found && clearance > 2.0 * slack && advance < left) {
        advance =
            std::max(advance, solid.sweep_advance(*from, sd, gap / left, clearance, slack, left));
      }
    }
    if (advance >= left) {
      *from = to;
      return true;
    }
    if (clearance <= 1e-3 * k.skin) return false;  // touching: blocked
    *from += (advance / left) * gap;
  }
  return false;
}

// Steps 1-3 for the tool's tip centre c: updates g (valid: g holds a previous tick's proxy).
// kStallStop: the field's stalled-slide stop below (false: the slides up to the cap, as the `sdf`
// model; for tests that compare the two rules).
template <class Solid, bool kStallStop = true>
void update(const ProxyConstants& k, const Solid& solid, bool* valid, Vec3* g, const Vec3& c) {
  if (!*valid) {
    *g = c;
    *valid = true;
  }
  // A proxy inside the tooth (the first call, or a caller that moved the tooth) leaves along the
  // shortest way (step 1). The push-out alternates between the walls of a concave groove narrower
  // than 2 rho and may not reach phi >= rho - s within its iterations: then a g that was
  // admissible stays where it was.
  {
    const Vec3 before = *g;
    if (push_out(k, solid, g) < -k.skin && solid.distance(before, k.rho).phi >= k.rho - k.skin) {
      *g = before;
    }
  }
  Vec3 target = c;
  for (int slide = 0; slide <= kSurfaceProxySlides; ++slide) {
    const Vec3 start = *g;
    Vec3 y = *g;
    const bool reached = sweep(k, solid, &y, target);
    *g = y;
    // Back from the skin to phi >= rho, along the local normal; where the push-out does not
    // converge, y itself (in A_skin: the sweep started there and stays there) is kept.
    if (push_out(k, solid, g) < -k.skin) *g = y;
    // The field: a slide the sweep blocked that moved g by no more than push_tol (the push-out's
    // own tolerance on where g ends) has stalled against a second wall (a concave corner, the
    // cavity the bur cut): g stays, instead of the tangent-plane slides that follow, each blocked
    // at once by the same wall, up to the cap. Only where the next slide would be taken; g is
    // admissible either way (Claim 1 rests on the sweep and the push-out, not on the target;
    // docs/derivations/field_contact.md §3, "The slide cap").
    if constexpr (kStallStop && kFieldPaths<Solid>) {
      if (slide > 0 && !reached && (*g - start).norm() <= k.push_tol) break;
    }
    if (reached && (target - c).norm() <= k.tol) break;  // the tool itself is admissible
    // Blocked (or a slide target reached): slide towards c on the tangent plane at g.
    const SignedDistance sd = solid.distance(*g, k.rho + k.skin);
    if (!sd.found) {
      target = c;
      continue;
    }
    const Vec3 n = solid.normal(*g, sd);
    const double behind = (c - *g).dot(n);
    const Vec3 next = behind < 0.0 ? Vec3(c - behind * n) : c;
    if ((next - *g).norm() <= k.tol) break;  // g is the constrained nearest point
    target = next;
  }
}

}  // namespace dentsim::proxy_detail

namespace dentsim {

template <class Solid>
const Vec3& SurfaceProxy::update_on(const Solid& solid, const Vec3& c) {
  proxy_detail::update(constants(), solid, &valid_, &g_, c);
  return g_;
}

}  // namespace dentsim
