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
//   double lipschitz() const;                 L: |phi(x) - phi(y)| <= L |x - y|.
// The swept test advances by (phi - (rho - s)) / L per step (conservative advancement under the
// L-Lipschitz bound), so the sweep never leaves {phi >= rho - s}; for the exact distance L = 1
// and the steps are the same doubles as before the refactor.
//
// Real-time: nothing allocates or throws (as long as the Solid's queries do not).
#pragma once

#include <algorithm>

#include "reference/core/types.h"
#include "reference/tooth/sdf.h"

namespace dentsim::proxy_detail {

// Step 1: moves x into A = {phi >= rho - push_tol} along the shortest way; returns phi(x) - rho at
// the end (0 when phi >= rho was found within the search of reach rho; >= -push_tol when it
// converged).
template <class Solid>
double push_out(const ProxyConstants& k, const Solid& solid, Vec3* x) {
  // Inside, the shortest way out may be long: search as far as the grid's extent. Outside, all
  // that matters is whether phi >= rho (then x stays where it is): a search within rho finds the
  // nearest point exactly when it is nearer than rho and stops early otherwise.
  const VoxelGrid& grid = solid.tooth().grid();
  const double far = grid.voxel_size * grid.n;
  for (int it = 0; it < kSurfaceProxyPushOuts; ++it) {
    int idx[3];
    const bool inside = sdf_detail::voxel_of(grid, *x, idx) &&
                        grid.voxels[grid.index(idx[0], idx[1], idx[2])] != kEmpty;
    const double reach = inside ? far : k.rho;
    const SignedDistance sd = solid.distance(*x, reach);
    if (!sd.found || sd.phi >= k.rho - k.push_tol) return (sd.found ? sd.phi : reach) - k.rho;
    const Vec3 u = solid.normal(*x, sd);
    *x = sd.nearest + k.rho * u;  // the nearest surface point, then rho out along the normal
  }
  const SignedDistance sd = solid.distance(*x, k.rho);
  return sd.phi - k.rho;
}

// Step 2: conservative advancement from `from` towards `to` within A_skin = {phi >= rho - s};
// true if `to` was reached, else *from is the last point reached.
template <class Solid>
bool sweep(const ProxyConstants& k, const Solid& solid, Vec3* from, const Vec3& to) {
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
    const double advance = clearance / lip;  // a step this long stays in A_skin (Lipschitz)
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
template <class Solid>
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
    Vec3 y = *g;
    const bool reached = sweep(k, solid, &y, target);
    *g = y;
    // Back from the skin to phi >= rho, along the local normal; where the push-out does not
    // converge, y itself (in A_skin: the sweep started there and stays there) is kept.
    if (push_out(k, solid, g) < -k.skin) *g = y;
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
