// The "field" contact model (reference/tooth/field_contact.h). Beyond the thesis.
#include "reference/tooth/field_contact.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdlib>

#include "reference/core/io.h"
#include "reference/tooth/field_edit_core.h"
#include "reference/tooth/surface_proxy_core.h"

namespace dentsim {

// The field takes the proxy core's field-only paths (surface_proxy_core.h) and answers them.
static_assert(proxy_detail::kFieldPaths<FieldSolid> && proxy_detail::FieldPathSolid<FieldSolid>);

SignedDistance FieldSolid::distance(const Vec3& x, double reach) const {
  if (field_.deep_inside(x)) return signed_distance(tooth_, x, reach);
  const FieldSample s = field_.sample(x);
  SignedDistance out;
  if (s.value >= reach) {
    out.phi = reach;
    out.found = false;
    return out;
  }
  out.phi = s.value;
  out.found = true;
  const double g = s.gradient.norm();
  out.nearest = g > 0.0 ? Vec3(x - (s.value / g) * s.gradient) : x;
  return out;
}

Vec3 FieldSolid::normal(const Vec3& x, const SignedDistance& sd) const {
  if (!field_.deep_inside(x)) {
    const Vec3 grad = field_.sample(x).gradient;
    const double g = grad.norm();
    if (g > 0.0) return grad / g;
  }
  // No gradient of the field here: the voxel distance's direction.
  const SignedDistance exact =
      field_.deep_inside(x) ? sd : signed_distance(tooth_, x, tooth_.grid().voxel_size * tooth_.grid().n);
  return distance_gradient(tooth_, x, exact);
}

double FieldSolid::slope(const Vec3& x) const {
  return field_.deep_inside(x) ? 0.0 : field_.sample(x).gradient.norm();
}

double FieldSolid::sweep_advance(const Vec3& y, const SignedDistance&, const Vec3& dir,
                                 double clearance, double slack, double left) const {
  // y's cell as SampledField::sample locates it; a clamped coordinate (y beyond the lattice)
  // gives no cell of y's own: no advance from it.
  const int m = field_.samples_per_axis();
  if (m < 2) return 0.0;
  const Vec3 origin = field_.sample_position(0, 0, 0);
  const double h = field_.spacing();
  int s[3];
  double t[3];
  for (int a = 0; a < 3; ++a) {
    const double u = (y[a] - origin[a]) / h;
    if (!(u >= 0.0 && u <= static_cast<double>(m - 1))) return 0.0;
    s[a] = std::min(static_cast<int>(u), m - 2);
    t[a] = u - s[a];
  }
  float c[8];
  for (int k = 0; k < 8; ++k) c[k] = field_.at(s[0] + (k & 1), s[1] + ((k >> 1) & 1), s[2] + (k >> 2));
  return field_cell_advance(c, t, h, dir, clearance, slack, left, field_.lipschitz());
}

namespace {

// The reference's reads and writes for the shared edit (reference/tooth/field_edit_core.h).
struct FieldAccess {
  SampledField* field;
  const VoxelTooth& tooth;
  SignedDistanceFn sd;
  float at(int sx, int sy, int sz) const { return field->at(sx, sy, sz); }
  double distance(int, int, int, const Vec3& p, double reach) const {
    return sd(tooth, p, reach).phi;
  }
  bool raise(int sx, int sy, int sz, double value) { return field->raise(sx, sy, sz, value); }
  void include_cells(const int lo[3], const int hi[3]) { field->include_cells(lo, hi); }
};

}  // namespace

bool edit_field_for_removed_voxels(SampledField* field, const VoxelTooth& tooth,
                                   std::span<const std::size_t> removed, SignedDistanceFn sd,
                                   FieldEditStats* stats, FieldEditCursor* cursor,
                                   long budget) {
  FieldAccess access{field, tooth, sd};
  return field_edit_detail::edit_field(*field, tooth, removed, access, stats, cursor, budget);
}

const Vec3& SurfaceProxy::update(const FieldSolid& solid, const Vec3& c) {
  proxy_detail::update(constants(), solid, &valid_, &g_, c);
  return g_;
}

}  // namespace dentsim
