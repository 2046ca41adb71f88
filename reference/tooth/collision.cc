#include "reference/tooth/collision.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

#include "reference/core/io.h"
#include "reference/tooth/grid_pages.h"

namespace dentsim {
namespace {

// Antiderivative of sqrt(a^2 - x^2) on [-a, a].
double half_chord_integral(double a, double x) {
  const double t = std::clamp(x / a, -1.0, 1.0);
  const double xc = a * t;
  return 0.5 * (xc * std::sqrt(std::max(0.0, a * a - xc * xc)) + a * a * std::asin(t));
}

constexpr double kInf = std::numeric_limits<double>::infinity();

// Whether exposed face f of voxel idx continues across its edge in direction s * e_axis: the
// in-plane neighbour is solid and has face f exposed as well.
bool continues(const VoxelTooth& tooth, const int idx[3], int f, int axis, int s) {
  int nb[3] = {idx[0], idx[1], idx[2]};
  nb[axis] += s;
  const VoxelGrid& g = tooth.grid();
  if (!g.inside(nb[0], nb[1], nb[2])) return false;
  return (tooth.codes.code(g.index(nb[0], nb[1], nb[2])) & (1u << f)) != 0;
}

// Bound of the run of coplanar exposed faces (face f) through voxel idx along s * e_axis: the
// coordinate of the run's end, or +-infinity once the run is longer than `reach` voxels (beyond
// the sphere, where the clamp no longer matters).
double patch_bound(const VoxelTooth& tooth, const int idx[3], int f, int axis, int s, int reach) {
  int cell[3] = {idx[0], idx[1], idx[2]};
  for (int step = 0; step < reach; ++step) {
    if (!continues(tooth, cell, f, axis, s)) {
      const VoxelGrid& g = tooth.grid();
      return g.origin[axis] + g.voxel_size * (cell[axis] + (s > 0 ? 1 : 0));
    }
    cell[axis] += s;
  }
  return s > 0 ? kInf : -kInf;
}

}  // namespace

VoxelTooth::VoxelTooth(VoxelGrid grid) : octree(std::move(grid)) {
  codes = SparseNeighborCodes(octree.grid());
  release_empty_pages(octree.grid());  // the grid's empty pages, not resident (issue #30)
}

void validate_tool_tip(const ToolTip& tip) {
  if (!(tip.radius > 0.0) || !std::isfinite(tip.radius)) {
    throw InputError("tool tip: radius = " + std::to_string(tip.radius) +
                     ", expected a finite value > 0 [m]");
  }
}

double disk_rect_area(double a, double x0, double x1, double y0, double y1) {
  if (!(a > 0.0)) return 0.0;
  const double lo = std::max(x0, -a);
  const double hi = std::min(x1, a);
  if (!(lo < hi) || !(y0 < y1)) return 0.0;
  // Breakpoints where the chord half-length s(X) = sqrt(a^2 - X^2) crosses |y0| or |y1|: between
  // them the vertical extent min(y1, s) - max(y0, -s) keeps one closed form.
  std::array<double, 6> xs;
  int count = 0;
  xs[count++] = lo;
  xs[count++] = hi;
  for (const double y : {y0, y1}) {
    if (std::abs(y) < a) {
      const double t = std::sqrt(a * a - y * y);
      for (const double x : {-t, t}) {
        if (x > lo && x < hi) xs[count++] = x;
      }
    }
  }
  for (int m = 1; m < count; ++m) {  // insertion sort of at most 6 values
    for (int q = m; q > 0 && xs[q - 1] > xs[q]; --q) std::swap(xs[q - 1], xs[q]);
  }
  double area = 0.0;
  for (int m = 0; m + 1 < count; ++m) {
    const double p = xs[m], q = xs[m + 1];
    if (!(p < q)) continue;
    const double mid = 0.5 * (p + q);
    const double s_mid = std::sqrt(std::max(0.0, a * a - mid * mid));
    const bool top_is_chord = s_mid < y1;      // top = min(y1, s)
    const bool bottom_is_chord = -s_mid > y0;  // bottom = max(y0, -s)
    const double top = top_is_chord ? s_mid : y1;
    const double bottom = bottom_is_chord ? -s_mid : y0;
    if (!(top > bottom)) continue;
    // The circular-segment integral (two asin), evaluated only where a chord bounds the piece.
    const double chord = (top_is_chord || bottom_is_chord)
                             ? half_chord_integral(a, q) - half_chord_integral(a, p)
                             : 0.0;
    const double int_top = top_is_chord ? chord : y1 * (q - p);
    const double int_bottom = bottom_is_chord ? -chord : y0 * (q - p);
    area += int_top - int_bottom;
  }
  return std::max(0.0, area);
}

bool collide_tool_tip(const VoxelTooth& tooth, const Pose& proxy, const ToolTip& tip,
                      double k_tooth, double b_tooth, CollisionScratch* scratch,
                      std::vector<Contact>* contacts, std::vector<std::size_t>* contact_voxels,
                      std::size_t max_contacts) {
  validate_tool_tip(tip);
  const double rho = tip.radius;
  const VoxelGrid& grid = tooth.grid();
  const Vec3 c = proxy.x + proxy.R * tip.offset_body;
  scratch->candidates.clear();
  tooth.octree.query_sphere(c, rho, &scratch->candidates);
  const double h = grid.voxel_size;
  const int n = grid.n;
  const int reach = static_cast<int>(std::ceil(rho / h)) + 2;  // voxels within the sphere's reach
  for (const std::size_t v : scratch->candidates) {
    const std::uint8_t code = tooth.codes.code(v);
    if (code == 0) continue;  // interior voxel: no exposed face
    const int idx[3] = {static_cast<int>(v % n), static_cast<int>((v / n) % n),
                        static_cast<int>(v / (static_cast<std::size_t>(n) * n))};
    const std::uint8_t material = grid.voxels[v];
    const MaterialProperties& props = material_properties(material);
    for (int f = 0; f < 6; ++f) {
      if ((code & (1u << f)) == 0) continue;
      const int a = face_axis(f);
      const int sign = face_sign(f);
      const int u = (a + 1) % 3, w = (a + 2) % 3;
      const double plane = grid.origin[a] + h * (idx[a] + (sign > 0 ? 1 : 0));
      const double d = sign * (c[a] - plane);  // signed distance of c outside the face plane
      if (!(std::abs(d) < rho)) continue;
      // The face region: the rectangle spanned by the runs of coplanar exposed faces through this
      // face along its two in-plane axes (the flat patch it belongs to), so that only the patch's
      // real edges clamp the nearest point and every face of a rectangular patch finds the same q.
      const double u0 = grid.origin[u] + h * idx[u], u1 = grid.origin[u] + h * (idx[u] + 1);
      const double w0 = grid.origin[w] + h * idx[w], w1 = grid.origin[w] + h * (idx[w] + 1);
      double lo[3], hi[3];
      for (const int axis : {u, w}) {
        lo[axis] = patch_bound(tooth, idx, f, axis, -1, reach);
        hi[axis] = patch_bound(tooth, idx, f, axis, +1, reach);
      }
      Vec3 q;  // nearest point of the face region to c, on the face plane
      q[a] = plane;
      q[u] = std::clamp(c[u], lo[u], hi[u]);
      q[w] = std::clamp(c[w], lo[w], hi[w]);
      const Vec3 face_n = face_normal(f);
      Vec3 normal;
      double factor;  // taper: n^T n_f, so a face seen edge-on fades out continuously
      if (d > 0.0) {
        const Vec3 gap = c - q;
        const double dist = gap.norm();
        if (!(dist < rho)) continue;
        normal = gap / dist;
        factor = d / dist;
      } else {
        // Centre behind the face plane (penetration >= rho): push out along the face normal
        // while the centre projects onto the face region.
        if (q[u] != c[u] || q[w] != c[w]) continue;
        normal = face_n;
        factor = 1.0;
      }
      // Weight: area of the face square inside the disk where the plane cuts the sphere.
      const double disk = std::sqrt(rho * rho - d * d);
      const double weight =
          factor * disk_rect_area(disk, u0 - c[u], u1 - c[u], w0 - c[w], w1 - c[w]);
      if (!(weight > 0.0)) continue;
      Contact contact;
      contact.n = normal;
      contact.x_o = q;
      const Vec3 x_c = c - rho * normal;
      contact.r = proxy.R.transpose() * (x_c - proxy.x);  // x_c = x_2 + R_2 r
      contact.depth = normal.dot(contact.x_o - x_c);      // = rho - |c - q| (2.15)
      contact.stiffness = k_tooth * props.stiffness_scale;
      contact.damping = b_tooth * props.damping_scale;
      contact.weight = weight;
      contact.material = material;
      if (contacts->size() >= max_contacts) return false;
      contacts->push_back(contact);
      if (contact_voxels != nullptr) contact_voxels->push_back(v);
    }
  }
  return true;
}

Vec3 blended_contact_force(const std::vector<Contact>& contacts) {
  double total_weight = 0.0;
  Vec3 f = Vec3::Zero();
  for (const Contact& ct : contacts) {
    total_weight += ct.weight;
    f += ct.weight * ct.stiffness * ct.depth * ct.n;
  }
  return total_weight > 0.0 ? Vec3(f / total_weight) : Vec3::Zero();
}

}  // namespace dentsim
