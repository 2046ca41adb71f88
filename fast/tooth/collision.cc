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
#include <array>
#include <cmath>

namespace dentsim::fast {
namespace {

// Antiderivative of sqrt(a^2 - x^2) on [-a, a] (as reference/tooth/collision.cc).
double half_chord_integral(double a, double x) {
  const double t = std::clamp(x / a, -1.0, 1.0);
  const double xc = a * t;
  return 0.5 * (xc * std::sqrt(std::max(0.0, a * a - xc * xc)) + a * a * std::asin(t));
}

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
  if (!(a > 0.0)) return 0.0;
  const double lo = std::max(x0, -a);
  const double hi = std::min(x1, a);
  if (!(lo < hi) || !(y0 < y1)) return 0.0;
  std::array<double, 6> xs;
  int count = 0;
  xs[count++] = lo;
  xs[count++] = hi;
  for (const double y : {y0, y1}) {
    if (std::abs(y) < a) {
      const double t = std::sqrt(a * a - y * y);
      if (-t > lo && -t < hi) xs[count++] = -t;
      if (t > lo && t < hi) xs[count++] = t;
    }
  }
  for (int m = 1; m < count; ++m) {
    for (int q = m; q > 0 && xs[q - 1] > xs[q]; --q) std::swap(xs[q - 1], xs[q]);
  }
  double area = 0.0;
  for (int m = 0; m + 1 < count; ++m) {
    const double p = xs[m], q = xs[m + 1];
    if (!(p < q)) continue;
    const double mid = 0.5 * (p + q);
    const double s_mid = std::sqrt(std::max(0.0, a * a - mid * mid));
    const bool top_is_chord = s_mid < y1;
    const bool bottom_is_chord = -s_mid > y0;
    const double top = top_is_chord ? s_mid : y1;
    const double bottom = bottom_is_chord ? -s_mid : y0;
    if (!(top > bottom)) continue;
    // The circular-segment integral only where a chord bounds the piece.
    const double chord = (top_is_chord || bottom_is_chord)
                             ? half_chord_integral(a, q) - half_chord_integral(a, p)
                             : 0.0;
    const double int_top = top_is_chord ? chord : y1 * (q - p);
    const double int_bottom = bottom_is_chord ? -chord : y0 * (q - p);
    area += int_top - int_bottom;
  }
  return std::max(0.0, area);
}

bool sphere_voxel_box(const BrickTooth& tooth, const Vec3& c, double rho, int lo[3], int hi[3]) {
  if (!c.allFinite()) return false;  // the reference's predicate rejects every voxel then
  const VoxelGrid& g = tooth.grid();
  // One voxel of padding each way: the exact predicate decides, the box only has to contain it.
  const double limit_hi = static_cast<double>(g.n) + 1.0;
  for (int a = 0; a < 3; ++a) {
    const double t0 = std::floor((c[a] - rho - g.origin[a]) / g.voxel_size) - 1.0;
    const double t1 = std::floor((c[a] + rho - g.origin[a]) / g.voxel_size) + 1.0;
    lo[a] = std::max(tooth.solid_lo()[a], static_cast<int>(std::clamp(t0, -2.0, limit_hi)));
    hi[a] = std::min(tooth.solid_hi()[a], static_cast<int>(std::clamp(t1, -2.0, limit_hi)));
    if (lo[a] > hi[a]) return false;
  }
  return true;
}

bool collide_tool_tip(const BrickTooth& tooth, const Pose& proxy, const ToolTip& tip,
                      double k_tooth, double b_tooth, std::vector<Contact>* contacts,
                      std::vector<std::size_t>* contact_voxels, std::size_t max_contacts) {
  validate_tool_tip(tip);
  const double rho = tip.radius;
  const Vec3 c = proxy.x + proxy.R * tip.offset_body;
  int lo[3], hi[3];
  if (!sphere_voxel_box(tooth, c, rho, lo, hi)) return true;

  const VoxelGrid& grid = tooth.grid();
  const std::uint8_t* codes = tooth.codes().code.data();
  const double h = grid.voxel_size;
  const int n = grid.n;
  const std::ptrdiff_t stride[3] = {1, n, static_cast<std::ptrdiff_t>(n) * n};
  const int reach = static_cast<int>(std::ceil(rho / h)) + 2;  // as the reference
  bool fits = true;
  tooth.for_each_surface_voxel(lo, hi, [&](int i, int j, int k, std::size_t v) {
    if (!fits || !sphere_intersects_voxel(grid, i, j, k, c, rho)) return;
    const std::uint8_t code = codes[v];
    const int idx[3] = {i, j, k};
    const std::uint8_t material = grid.voxels[v];
    const MaterialProperties& props = material_properties(material);
    for (int f = 0; f < 6; ++f) {
      if ((code & (1u << f)) == 0) continue;
      const int a = face_axis(f);
      const int sign = face_sign(f);
      const int u = (a + 1) % 3, w = (a + 2) % 3;
      const double plane = grid.origin[a] + h * (idx[a] + (sign > 0 ? 1 : 0));
      const double d = sign * (c[a] - plane);
      if (!(std::abs(d) < rho)) continue;
      const double u0 = grid.origin[u] + h * idx[u], u1 = grid.origin[u] + h * (idx[u] + 1);
      const double w0 = grid.origin[w] + h * idx[w], w1 = grid.origin[w] + h * (idx[w] + 1);
      Vec3 q;
      q[a] = plane;
      for (const int axis : {u, w}) {
        const double lo_e = axis == u ? u0 : w0, hi_e = axis == u ? u1 : w1;
        const int s = c[axis] > hi_e ? 1 : (c[axis] < lo_e ? -1 : 0);
        q[axis] = s == 0 ? c[axis]
                         : clamp_along_run(codes, v, idx[axis], n, stride[axis], 1u << f, s,
                                           c[axis], grid.origin[axis], h, reach);
      }
      const Vec3 face_n = face_normal(f);
      Vec3 normal;
      double factor;
      if (d > 0.0) {
        const Vec3 gap = c - q;
        const double dist = gap.norm();
        if (!(dist < rho)) continue;
        normal = gap / dist;
        factor = d / dist;
      } else {
        if (q[u] != c[u] || q[w] != c[w]) continue;
        normal = face_n;
        factor = 1.0;
      }
      const double disk = std::sqrt(rho * rho - d * d);
      const double weight =
          factor * disk_rect_area(disk, u0 - c[u], u1 - c[u], w0 - c[w], w1 - c[w]);
      if (!(weight > 0.0)) continue;
      if (contacts->size() >= max_contacts) {
        fits = false;
        return;
      }
      Contact& contact = contacts->emplace_back();
      contact.n = normal;
      contact.x_o = q;
      const Vec3 x_c = c - rho * normal;
      contact.r = proxy.R.transpose() * (x_c - proxy.x);
      contact.depth = normal.dot(contact.x_o - x_c);
      contact.stiffness = k_tooth * props.stiffness_scale;
      contact.damping = b_tooth * props.damping_scale;
      contact.weight = weight;
      contact.material = material;
      if (contact_voxels != nullptr) contact_voxels->push_back(v);
    }
  });
  return fits;
}

}  // namespace dentsim::fast
