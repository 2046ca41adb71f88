#include "fast/tooth/sdf.h"

#include <array>
#include <cmath>

namespace dentsim::fast {
namespace {

using sdf_detail::box_distance2;

// Outside: the reference's pruned descent (reference/tooth/sdf.cc outside_distance), children
// nearest first.
SignedDistance outside_distance(const FullOctree& octree, const Vec3& x, double reach) {
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
    double d2;
    int level, x, y, z;
  };
  // Depth first: at most 8 pending children per level (levels <= 10 for N <= 1024), the root.
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
      } else {
        // Insertion by decreasing distance: the nearest ends last, on top of the stack.
        int at = nk++;
        while (at > 0 && kids[at - 1].d2 < d2) {
          kids[at] = kids[at - 1];
          --at;
        }
        kids[at] = {d2, child_level, cx, cy, cz};
      }
    }
    for (int i = 0; i < nk; ++i) stack[top++] = kids[i];
  }
  if (out.found) out.phi = std::sqrt(best2);
  return out;
}

}  // namespace

SignedDistance signed_distance(const VoxelTooth& tooth, const Vec3& x, double reach) {
  const VoxelGrid& grid = tooth.grid();
  int idx[3];
  if (sdf_detail::voxel_of(grid, x, idx) &&
      grid.voxels[grid.index(idx[0], idx[1], idx[2])] != kEmpty) {
    return sdf_detail::inside_distance(grid, x, idx, reach);
  }
  return outside_distance(tooth.octree, x, reach);
}

}  // namespace dentsim::fast
