// Why the one-way patch walk gives the reference's q (reference/tooth/collision.cc patch_bound):
// the reference clamps c_u to [lo, hi], lo = the run's end on the minus side (<= u0, the face's own
// edge: the end coordinate origin + h * cell is monotone in cell, also in floating point) and hi
// the end on the plus side (>= u1), or +-infinity once the run is longer than `reach` voxels.
// - u0 <= c_u <= u1: the clamp returns c_u whatever lo and hi are;
// - c_u > u1: std::clamp never returns lo (c_u >= lo), so only hi matters, and it returns c_u as
//   soon as hi >= c_u. Walking the run cell by cell, once a cell's end reaches c_u every later end
//   (and infinity) does too, so the walk can stop there with c_u; if the run ends before, its end
//   coordinate (< c_u) is the reference's hi and the clamp returns it; c_u < u0 mirrors this.
// Every double is computed by the same expression as in the reference, so q is bitwise equal.
#include "fast/tooth/collision.h"

#include <algorithm>
#include <cmath>

namespace dentsim::fast {
namespace {

// The in-plane coordinate of the face region's point nearest to c along one axis, for c_u
// outside the face's own span on side s (+1: c_u > u1, -1: c_u < u0): the end of the run of
// coplanar exposed faces (bit `face_bit`) from voxel v at coordinate `cell`, or c_u once the run
// passes c_u or is longer than `reach` voxels (file comment).
double clamp_along_run(const std::uint8_t* codes, std::size_t v, int cell, int n,
                       std::ptrdiff_t stride, unsigned face_bit, int s, double c_u, double origin,
                       double h, int reach) {
  for (int step = 0; step < reach; ++step) {
    const double end = origin + h * (cell + (s > 0 ? 1 : 0));
    if (s > 0 ? end >= c_u : end <= c_u) return c_u;
    const int next = cell + s;
    if (next < 0 || next >= n) return end;
    v = static_cast<std::size_t>(static_cast<std::ptrdiff_t>(v) + s * stride);
    if ((codes[v] & face_bit) == 0) return end;
    cell = next;
  }
  return c_u;
}

}  // namespace

double disk_rect_area(double a, double x0, double x1, double y0, double y1) {
  // Rectangle inside the disk (the common case: a face well inside the contact disk): the
  // reference's sweep then has no breakpoint strictly inside (x0, x1) -- t = sqrt(a^2 - y^2) >=
  // max(x1, -x0) for y = y0, y1 -- and its single piece has s_mid >= max(y1, -y0), so no chord:
  // area = y1 (x1 - x0) - y0 (x1 - x0). The conditions are decided on the squares with a relative
  // margin of 1e-12 (far above the rounding of sqrt and of the squares), so whenever this branch
  // is taken the reference's own decisions are the same, and the result is bitwise equal; cases
  // within the margin take the reference's sweep. (a <= 0 or NaN never enters: x0 < x1 fails.)
  if (x0 >= -a && x1 <= a && x0 < x1 && y0 < y1) {
    constexpr double kMargin = 1.0 + 1e-12;
    const double a2 = a * a;
    const double m = std::max(x1, -x0);
    const double ym = std::max(y1, -y0);
    const double mid = 0.5 * (x0 + x1);
    if (a2 - y0 * y0 >= m * m * kMargin && a2 - y1 * y1 >= m * m * kMargin &&
        a2 - mid * mid >= ym * ym * kMargin) {
      const double width = x1 - x0;
      return std::max(0.0, y1 * width - y0 * width);
    }
  }
  return dentsim::disk_rect_area(a, x0, x1, y0, y1);
}

bool sphere_voxel_box(const BrickTooth& tooth, const Vec3& c, double rho, int lo[3], int hi[3]) {
  // Free space first: the sphere's box against the solid's world box padded by a voxel (a few
  // compares; false for NaN too, whose comparisons fail).
  const Vec3& bmin = tooth.solid_box_min();
  const Vec3& bmax = tooth.solid_box_max();
  if (tooth.free_space_early_out() &&
      !(c.x() + rho > bmin.x() && c.x() - rho < bmax.x() && c.y() + rho > bmin.y() &&
        c.y() - rho < bmax.y() && c.z() + rho > bmin.z() && c.z() - rho < bmax.z())) {
    return false;
  }
  if (!c.allFinite()) return false;  // the reference's predicate rejects every voxel then
  const VoxelGrid& g = tooth.grid();
  // One voxel of padding each way: the exact predicate decides, the box only has to contain it.
  const double limit_hi = static_cast<double>(g.n) + 1.0;
  for (int a = 0; a < 3; ++a) {
    const double t0 = std::floor((c[a] - rho - g.origin[a]) * tooth.inv_voxel_size()) - 1.0;
    const double t1 = std::floor((c[a] + rho - g.origin[a]) * tooth.inv_voxel_size()) + 1.0;
    lo[a] = std::max(tooth.solid_lo()[a], static_cast<int>(std::clamp(t0, -2.0, limit_hi)));
    hi[a] = std::min(tooth.solid_hi()[a], static_cast<int>(std::clamp(t1, -2.0, limit_hi)));
    if (lo[a] > hi[a]) return false;
  }
  return true;
}

void sphere_surface_voxels(const BrickTooth& tooth, const Vec3& c, double rho,
                           std::vector<std::size_t>* out) {
  int lo[3], hi[3];
  if (!sphere_voxel_box(tooth, c, rho, lo, hi)) return;
  tooth.for_each_surface_voxel(lo, hi, [&](int i, int j, int k, std::size_t v) {
    if (sphere_intersects_voxel(tooth.grid(), i, j, k, c, rho)) out->push_back(v);
  });
}

namespace {

// What one query shares across its faces.
struct Query {
  const VoxelGrid& grid;
  const std::uint8_t* codes;
  const Pose& proxy;
  Vec3 c;
  double rho, h, k_tooth, b_tooth;
  int n, reach;
  std::ptrdiff_t stride[3];
  std::vector<Contact>* contacts;
  std::vector<std::size_t>* contact_voxels;
  std::size_t max_contacts;
};

// Face F (compile-time: its axis and side, so every coordinate index below is a constant and the
// points stay in registers) of surface voxel idx / v: the reference's steps 2 (collision.h) on
// the same expressions. Returns false when the contact buffer is full.
template <int F>
bool face_contact(const Query& qr, const int idx[3], std::size_t v, std::uint8_t material,
                  const MaterialProperties& props) {
  constexpr int a = F / 2;
  constexpr int sign = F % 2 == 0 ? -1 : 1;
  constexpr int u = (a + 1) % 3, w = (a + 2) % 3;
  const Vec3& c = qr.c;
  const double h = qr.h;
  const Vec3& origin = qr.grid.origin;
  const double plane = origin[a] + h * (idx[a] + (sign > 0 ? 1 : 0));
  const double d = sign * (c[a] - plane);
  if (!(std::abs(d) < qr.rho)) return true;
  const double u0 = origin[u] + h * idx[u], u1 = origin[u] + h * (idx[u] + 1);
  const double w0 = origin[w] + h * idx[w], w1 = origin[w] + h * (idx[w] + 1);
  const auto clamp_axis = [&](int axis, double lo_e, double hi_e) {
    const int s = c[axis] > hi_e ? 1 : (c[axis] < lo_e ? -1 : 0);
    return s == 0 ? c[axis]
                  : clamp_along_run(qr.codes, v, idx[axis], qr.n, qr.stride[axis], 1u << F, s,
                                    c[axis], origin[axis], h, qr.reach);
  };
  Vec3 q;  // nearest point of the face region to c, on the face plane
  q[a] = plane;
  q[u] = clamp_axis(u, u0, u1);
  q[w] = clamp_axis(w, w0, w1);
  Vec3 normal;
  double factor;
  if (q[u] == c[u] && q[w] == c[w]) {
    // c projects onto the face region: for d > 0 the reference's c - q is (c_a - plane) e_a with
    // +0 elsewhere, |c - q| = sqrt(fl(x^2)) = |x| = d exactly (radix 2, round to nearest), so
    // n = sign e_a = n_f and the taper d / |c - q| = 1 exactly; for d <= 0 the reference sets the
    // same. No square root, no division.
    normal = face_normal(F);
    factor = 1.0;
  } else if (d > 0.0) {
    const Vec3 gap = c - q;
    const double dist = gap.norm();
    if (!(dist < qr.rho)) return true;
    normal = gap / dist;
    factor = d / dist;
  } else {
    return true;  // centre behind the face plane and not over the face region
  }
  const double disk = std::sqrt(qr.rho * qr.rho - d * d);
  const double weight = factor * disk_rect_area(disk, u0 - c[u], u1 - c[u], w0 - c[w], w1 - c[w]);
  if (!(weight > 0.0)) return true;
  if (qr.contacts->size() >= qr.max_contacts) return false;
  Contact& contact = qr.contacts->emplace_back();
  contact.n = normal;
  contact.x_o = q;
  const Vec3 x_c = c - qr.rho * normal;
  contact.r = qr.proxy.R.transpose() * (x_c - qr.proxy.x);
  contact.depth = normal.dot(contact.x_o - x_c);
  contact.stiffness = qr.k_tooth * props.stiffness_scale;
  contact.damping = qr.b_tooth * props.damping_scale;
  contact.weight = weight;
  contact.material = material;
  if (qr.contact_voxels != nullptr) qr.contact_voxels->push_back(v);
  return true;
}

}  // namespace

bool collide_tool_tip(const BrickTooth& tooth, const Pose& proxy, const ToolTip& tip,
                      double k_tooth, double b_tooth, std::vector<Contact>* contacts,
                      std::vector<std::size_t>* contact_voxels, std::size_t max_contacts) {
  validate_tool_tip(tip);
  const double rho = tip.radius;
  const Vec3 c = proxy.x + proxy.R * tip.offset_body;
  int lo[3], hi[3];
  if (!sphere_voxel_box(tooth, c, rho, lo, hi)) return true;
  const VoxelGrid& grid = tooth.grid();
  const int n = grid.n;
  const Query qr{grid,
                 tooth.codes().code.data(),
                 proxy,
                 c,
                 rho,
                 grid.voxel_size,
                 k_tooth,
                 b_tooth,
                 n,
                 static_cast<int>(std::ceil(rho / grid.voxel_size)) + 2,  // reach, as the reference
                 {1, n, static_cast<std::ptrdiff_t>(n) * n},
                 contacts,
                 contact_voxels,
                 max_contacts};
  bool fits = true;
  tooth.for_each_surface_voxel(lo, hi, [&](int i, int j, int k, std::size_t v) {
    if (!fits || !sphere_intersects_voxel(grid, i, j, k, c, rho)) return;
    const std::uint8_t code = qr.codes[v];
    const int idx[3] = {i, j, k};
    const std::uint8_t material = grid.voxels[v];
    const MaterialProperties& props = material_properties(material);
    fits = ((code & 1u) == 0 || face_contact<0>(qr, idx, v, material, props)) &&
           ((code & 2u) == 0 || face_contact<1>(qr, idx, v, material, props)) &&
           ((code & 4u) == 0 || face_contact<2>(qr, idx, v, material, props)) &&
           ((code & 8u) == 0 || face_contact<3>(qr, idx, v, material, props)) &&
           ((code & 16u) == 0 || face_contact<4>(qr, idx, v, material, props)) &&
           ((code & 32u) == 0 || face_contact<5>(qr, idx, v, material, props));
  });
  return fits;
}

}  // namespace dentsim::fast
