// Signed distance to the voxel tooth and the surface proxy (reference/tooth/sdf.h; derivation in
// docs/derivations/sdf_contact.md). Beyond the thesis.
#include "reference/tooth/sdf.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "reference/tooth/materials.h"
#include "reference/tooth/surface_proxy_core.h"

namespace dentsim {
namespace sdf_detail {

// Squared distance from x to the box of cells [i0, i1) x [j0, j1) x [k0, k1), and its nearest
// point.
double box_distance2(const VoxelGrid& grid, const int lo_idx[3], const int hi_idx[3], const Vec3& x,
                     Vec3* nearest) {
  double d2 = 0.0;
  for (int a = 0; a < 3; ++a) {
    const double lo = grid.origin[a] + grid.voxel_size * lo_idx[a];
    const double hi = grid.origin[a] + grid.voxel_size * hi_idx[a];
    const double q = std::clamp(x[a], lo, hi);
    if (nearest != nullptr) (*nearest)[a] = q;
    d2 += (x[a] - q) * (x[a] - q);
  }
  return d2;
}

// The voxel holding x (floor of the grid coordinates); false outside the grid.
bool voxel_of(const VoxelGrid& grid, const Vec3& x, int idx[3]) {
  for (int a = 0; a < 3; ++a) {
    const double u = std::floor((x[a] - grid.origin[a]) / grid.voxel_size);
    if (!(u >= 0.0 && u < grid.n)) return false;
    idx[a] = static_cast<int>(u);
  }
  return true;
}

}  // namespace sdf_detail

namespace {

using sdf_detail::box_distance2;

// Outside: nearest point of the solid (union of solid voxel boxes) within `reach`, by a
// depth-first octree descent pruning every node at distance >= the best so far (ties: the
// order-free rule of sdf_nearer). A node's children are pushed in child order 0..7 (popped 7..0)
// or, with `nearest_first`, sorted so that the nearest is popped first (the fast pipeline's
// order: the bound tightens sooner; the answer is the same).
SignedDistance outside_distance(const FullOctree& octree, const Vec3& x, double reach,
                                bool nearest_first) {
  SignedDistance out;
  out.phi = reach;
  const VoxelGrid& grid = octree.grid();
  const int n = grid.n;
  if (n == 0 || !octree.occupied(0, 0, 0, 0)) return out;
  double best2 = reach * reach;
  const int L = octree.levels();
  const int root_lo[3] = {0, 0, 0}, root_hi[3] = {n, n, n};
  const double root2 = box_distance2(grid, root_lo, root_hi, x, nullptr);
  if (!(root2 < best2)) return out;
  struct Node {
    double d2;  // the node box's squared distance (a lower bound for its voxels)
    int level, x, y, z;
  };
  // At most 8 pending children per level (levels <= 10 for N <= 1024), and the root.
  std::array<Node, 8 * 11 + 1> stack;
  int top = 0;
  stack[top++] = {root2, 0, 0, 0, 0};
  Vec3 q;
  while (top > 0) {
    const Node node = stack[--top];
    if (sdf_detail::sdf_prunable(node.d2, best2, out)) continue;  // pruned since pushed
    if (node.level == L) {  // a leaf pushed by a single-voxel grid (L = 0)
      const int lo[3] = {node.x, node.y, node.z}, hi[3] = {node.x + 1, node.y + 1, node.z + 1};
      const double d2 = box_distance2(grid, lo, hi, x, &q);
      const std::size_t v = grid.index(node.x, node.y, node.z);
      if (sdf_detail::sdf_nearer(d2, v, best2, out)) {
        best2 = d2;
        out.nearest = q;
        out.voxel = v;
        out.found = true;
      }
      continue;
    }
    const std::uint8_t mask = octree.child_mask(node.level, node.x, node.y, node.z);
    const int child_level = node.level + 1;
    const int s = 1 << (L - child_level);
    Node kids[8];
    int nk = 0;
    for (int child = 0; child < 8; ++child) {
      if ((mask & (1u << child)) == 0) continue;
      const int cx = 2 * node.x + (child & 1);
      const int cy = 2 * node.y + ((child >> 1) & 1);
      const int cz = 2 * node.z + ((child >> 2) & 1);
      const int lo[3] = {cx * s, cy * s, cz * s}, hi[3] = {lo[0] + s, lo[1] + s, lo[2] + s};
      const double d2 = box_distance2(grid, lo, hi, x, child_level == L ? &q : nullptr);
      if (sdf_detail::sdf_prunable(d2, best2, out)) continue;
      if (child_level == L) {
        const std::size_t v = grid.index(cx, cy, cz);
        if (!sdf_detail::sdf_nearer(d2, v, best2, out)) continue;
        best2 = d2;
        out.nearest = q;
        out.voxel = v;
        out.found = true;
        continue;
      }
      // nearest_first: insertion by decreasing distance, so the nearest is pushed last.
      int at = nk++;
      while (nearest_first && at > 0 && kids[at - 1].d2 < d2) {
        kids[at] = kids[at - 1];
        --at;
      }
      kids[at] = {d2, child_level, cx, cy, cz};
    }
    for (int i = 0; i < nk; ++i) stack[top++] = kids[i];
  }
  if (out.found) out.phi = std::sqrt(best2);
  return out;
}

}  // namespace

namespace sdf_detail {

// Inside solid voxel idx: nearest point of the complement (empty voxels and the outside of the
// grid) within `reach`, by shells of Chebyshev radius m around idx. A voxel of shell m is at
// least (m - 1) h away, so the search stops once (m - 1) h >= the best distance.
SignedDistance inside_distance(const VoxelGrid& grid, const Vec3& x, const int idx[3],
                               double reach) {
  SignedDistance out;
  out.found = true;
  out.voxel = grid.index(idx[0], idx[1], idx[2]);
  const double h = grid.voxel_size;
  // The outside of the grid: the nearest of its six boundary planes.
  double best = reach;
  out.nearest = x;
  int best_axis = 2, best_side = 1;
  for (int a = 0; a < 3; ++a) {
    const double to_lo = x[a] - grid.origin[a];
    const double to_hi = grid.origin[a] + h * grid.n - x[a];
    if (to_lo < best) best = to_lo, best_axis = a, best_side = -1;
    if (to_hi < best) best = to_hi, best_axis = a, best_side = 1;
  }
  out.nearest[best_axis] += best_side * best;
  for (int m = 1; (m - 1) * h < best; ++m) {
    for (int dk = -m; dk <= m; ++dk) {
      for (int dj = -m; dj <= m; ++dj) {
        const bool face_kj = std::abs(dk) == m || std::abs(dj) == m;
        for (int di = -m; di <= m; di += (face_kj ? 1 : 2 * m)) {
          const int i = idx[0] + di, j = idx[1] + dj, k = idx[2] + dk;
          if (!grid.inside(i, j, k) || grid.voxels[grid.index(i, j, k)] != kEmpty) continue;
          const int lo[3] = {i, j, k}, hi[3] = {i + 1, j + 1, k + 1};
          Vec3 q;
          const double d = std::sqrt(box_distance2(grid, lo, hi, x, &q));
          if (d < best) {
            best = d;
            out.nearest = q;
          }
        }
      }
    }
  }
  out.phi = -best;
  return out;
}

}  // namespace sdf_detail

namespace sdf_detail {

SignedDistance signed_distance_ordered(const VoxelTooth& tooth, const Vec3& x, double reach,
                                       bool nearest_first) {
  const VoxelGrid& grid = tooth.grid();
  int idx[3];
  if (voxel_of(grid, x, idx) && grid.voxels[grid.index(idx[0], idx[1], idx[2])] != kEmpty) {
    return inside_distance(grid, x, idx, reach);
  }
  return outside_distance(tooth.octree, x, reach, nearest_first);
}

}  // namespace sdf_detail

SignedDistance signed_distance(const VoxelTooth& tooth, const Vec3& x, double reach) {
  return sdf_detail::signed_distance_ordered(tooth, x, reach, false);
}

Vec3 distance_gradient(const VoxelTooth& tooth, const Vec3& x, const SignedDistance& sd) {
  const Vec3 gap = sd.phi >= 0.0 ? Vec3(x - sd.nearest) : Vec3(sd.nearest - x);
  const double len = gap.norm();
  if (len > 0.0) return gap / len;
  const VoxelGrid& grid = tooth.grid();
  const std::size_t n = static_cast<std::size_t>(grid.n);
  const Vec3 centre =
      grid.center(static_cast<int>(sd.voxel % n), static_cast<int>((sd.voxel / n) % n),
                  static_cast<int>(sd.voxel / (n * n)));
  const Vec3 out = x - centre;
  return out.norm() > 0.0 ? Vec3(out.normalized()) : Vec3::UnitZ();
}

SurfaceProxy::SurfaceProxy(double rho, double voxel_size, SignedDistanceFn sd)
    : rho_(rho), skin_(std::min(0.25 * rho, 0.5 * voxel_size)), tol_(1e-9 * rho), sd_(sd) {}

namespace {

// The exact distance to the voxel solid as the proxy's Solid (surface_proxy_core.h): L = 1.
struct VoxelSolid {
  const VoxelTooth& voxels;
  SignedDistanceFn sd;
  const VoxelTooth& tooth() const { return voxels; }
  SignedDistance distance(const Vec3& x, double reach) const { return sd(voxels, x, reach); }
  Vec3 normal(const Vec3& x, const SignedDistance& s) const {
    return distance_gradient(voxels, x, s);
  }
  double lipschitz() const { return 1.0; }
};
// The thesis's steps only (surface_proxy_core.h: no field-only path), so the `sdf` model's proxy
// is the same doubles whatever the core adds for the field.
static_assert(!proxy_detail::kFieldPaths<VoxelSolid>);

}  // namespace

double SurfaceProxy::push_out(const VoxelTooth& tooth, Vec3* x) const {
  return proxy_detail::push_out(constants(), VoxelSolid{tooth, sd_}, x);
}

bool SurfaceProxy::sweep(const VoxelTooth& tooth, Vec3* from, const Vec3& to) const {
  return proxy_detail::sweep(constants(), VoxelSolid{tooth, sd_}, from, to);
}

const Vec3& SurfaceProxy::update(const VoxelTooth& tooth, const Vec3& c) {
  proxy_detail::update(constants(), VoxelSolid{tooth, sd_}, &valid_, &g_, c);
  return g_;
}

bool surface_proxy_geometry(const Pose& proxy, const ToolTip& tip, const Vec3& g, Contact* out) {
  const Vec3 c = proxy.x + proxy.R * tip.offset_body;
  const Vec3 gap = g - c;
  const double depth = gap.norm();
  if (!(depth > 1e-9 * tip.radius)) return false;
  const Vec3 n = gap / depth;
  out->n = n;
  out->x_o = g - tip.radius * n;
  const Vec3 x_c = c - tip.radius * n;
  out->r = proxy.R.transpose() * (x_c - proxy.x);
  out->depth = n.dot(out->x_o - x_c);  // = |g - c|  (2.15)
  out->weight = 1.0;
  return true;
}

std::uint8_t proxy_material(const VoxelTooth& tooth, const Vec3& g, double rho,
                            SignedDistanceFn sd) {
  const SignedDistance near = sd(tooth, g, proxy_material_reach(rho));
  return near.found ? tooth.grid().voxels[near.voxel] : std::uint8_t{kEmpty};
}

void set_contact_material(std::uint8_t material, double k_tooth, double b_tooth, Contact* out) {
  // The material under the proxy (enamel if, after a slide, no solid is within 2 rho of g).
  if (material == kEmpty) material = kEnamel;
  const MaterialProperties& props = material_properties(material);
  out->stiffness = k_tooth * props.stiffness_scale;
  out->damping = b_tooth * props.damping_scale;
  out->material = material;
}

bool surface_proxy_contact(const VoxelTooth& tooth, const Pose& proxy, const ToolTip& tip,
                           const Vec3& g, double k_tooth, double b_tooth, Contact* out,
                           SignedDistanceFn sd_fn) {
  if (!surface_proxy_geometry(proxy, tip, g, out)) return false;
  set_contact_material(proxy_material(tooth, g, tip.radius, sd_fn), k_tooth, b_tooth, out);
  return true;
}

}  // namespace dentsim
