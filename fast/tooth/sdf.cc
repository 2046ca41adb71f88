#include "fast/tooth/sdf.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

namespace dentsim::fast {
namespace {

// The reference's outside descent (reference/tooth/sdf.cc outside_distance, nearest_first) with
// the same doubles computed once per node instead of once per child box (header comment).
// *best2_out: the squared distance of the answer when found (the search's own double), +inf when
// nothing lies within reach.
SignedDistance outside_distance(const FullOctree& octree, const Vec3& x, double reach,
                                double* best2_out) {
  *best2_out = std::numeric_limits<double>::infinity();
  SignedDistance out;
  out.phi = reach;
  const VoxelGrid& grid = octree.grid();
  const int n = grid.n;
  const int L = octree.levels();
  // The root's occupancy (L > 0 here: the callers take the reference's descent for L = 0) is its
  // child mask, read directly (FullOctree::occupied computes the node index, ~170 instructions).
  if (n == 0 || octree.masks()[0] == 0) return out;
  double best2 = reach * reach;
  const int root_lo[3] = {0, 0, 0}, root_hi[3] = {n, n, n};
  const double root2 = sdf_detail::box_distance2(grid, root_lo, root_hi, x, nullptr);
  if (!(root2 < best2)) return out;
  const std::uint8_t* masks = octree.masks().data();
  const double h = grid.voxel_size;
  struct Node {
    double d2;          // the node box's squared distance (a lower bound for its voxels)
    std::size_t code;   // morton code of (x, y, z) within its level
    int level, x, y, z;
  };
  std::array<Node, 8 * 11 + 1> stack;
  int top = 0;
  stack[top++] = {root2, 0, 0, 0, 0, 0};
  while (top > 0) {
    const Node node = stack[--top];
    if (sdf_detail::sdf_prunable(node.d2, best2, out)) continue;  // pruned since pushed
    // Level offset (8^l - 1) / 7 of the full octree's linear index (reference/tooth/octree.h).
    const std::size_t offset = ((std::size_t{1} << (3 * node.level)) - 1) / 7;
    const std::uint8_t mask = masks[offset + node.code];
    const int child_level = node.level + 1;
    const int s = 1 << (L - child_level);
    const bool leaves = child_level == L;
    // Per axis, the two halves [c0, c1] and [c1, c2] of the node: the clamp and the squared gap
    // box_distance2 computes for a child box on that side (same expressions, same doubles).
    const int base[3] = {2 * node.x * s, 2 * node.y * s, 2 * node.z * s};
    double term[3][2], near[3][2];
    for (int a = 0; a < 3; ++a) {
      const double c0 = grid.origin[a] + h * base[a];
      const double c1 = grid.origin[a] + h * (base[a] + s);
      const double c2 = grid.origin[a] + h * (base[a] + 2 * s);
      near[a][0] = std::clamp(x[a], c0, c1);
      near[a][1] = std::clamp(x[a], c1, c2);
      term[a][0] = (x[a] - near[a][0]) * (x[a] - near[a][0]);
      term[a][1] = (x[a] - near[a][1]) * (x[a] - near[a][1]);
    }
    Node kids[8];
    int nk = 0;
    for (int child = 0; child < 8; ++child) {
      if ((mask & (1u << child)) == 0) continue;
      const int bx = child & 1, by = (child >> 1) & 1, bz = (child >> 2) & 1;
      // box_distance2's sum: 0 + t_x (exact), + t_y, + t_z, in that order.
      const double d2 = (term[0][bx] + term[1][by]) + term[2][bz];
      if (sdf_detail::sdf_prunable(d2, best2, out)) continue;
      const int cx = 2 * node.x + bx, cy = 2 * node.y + by, cz = 2 * node.z + bz;
      if (leaves) {
        const std::size_t v = grid.index(cx, cy, cz);
        if (!sdf_detail::sdf_nearer(d2, v, best2, out)) continue;
        best2 = d2;
        out.nearest = Vec3(near[0][bx], near[1][by], near[2][bz]);
        out.voxel = v;
        out.found = true;
        continue;
      }
      // Insertion by decreasing distance, so the nearest is pushed last (popped first).
      int at = nk++;
      while (at > 0 && kids[at - 1].d2 < d2) {
        kids[at] = kids[at - 1];
        --at;
      }
      kids[at] = {d2, 8 * node.code + static_cast<std::size_t>(child), child_level, cx, cy, cz};
    }
    for (int i = 0; i < nk; ++i) stack[top++] = kids[i];
  }
  if (out.found) {
    out.phi = std::sqrt(best2);
    *best2_out = best2;
  }
  return out;
}

}  // namespace

SignedDistance signed_distance(const VoxelTooth& tooth, const Vec3& x, double reach,
                               double* outside_best2) {
  *outside_best2 = -1.0;
  const VoxelGrid& grid = tooth.grid();
  int idx[3];
  if (sdf_detail::voxel_of(grid, x, idx) &&
      grid.voxels[grid.index(idx[0], idx[1], idx[2])] != kEmpty) {
    return sdf_detail::inside_distance(grid, x, idx, reach);
  }
  // A single-voxel grid (L = 0: the root is a leaf) takes the reference's descent.
  if (tooth.octree.levels() == 0) return sdf_detail::signed_distance_ordered(tooth, x, reach, true);
  return outside_distance(tooth.octree, x, reach, outside_best2);
}

SignedDistance signed_distance(const VoxelTooth& tooth, const Vec3& x, double reach) {
  double best2;
  return signed_distance(tooth, x, reach, &best2);
}

void RecallingVoxelSolid::remember(const Vec3& x, double reach, double best2,
                                   const SignedDistance& sd) const {
  memo_[next_] = {x, reach, best2, sd};
  next_ = (next_ + 1) % kEntries;
  count_ = std::max(count_, next_ == 0 ? kEntries : next_);
}

SignedDistance RecallingVoxelSolid::certified_search(const Vec3& x, double reach) const {
  const VoxelGrid& grid = tooth_.grid();
  const double wide = FreeSpaceCertificate::widened(reach, grid.voxel_size);
  double best2;
  const SignedDistance sd = outside_distance(tooth_.octree, x, wide, &best2);
  certificate_->record(x, sd.found ? sd.phi : wide, grid.voxel_size);
  remember(x, wide, best2, sd);
  // The answer within `reach` from the answer within wide >= reach (the memo's rule, below).
  if (best2 < reach * reach) return sd;
  SignedDistance none;
  none.phi = reach;
  return none;
}

SignedDistance RecallingVoxelSolid::distance(const Vec3& x, double reach) const {
  if (certificate_ != nullptr && certificate_->certifies(x, reach)) {
    certificate_->count(true);
    SignedDistance none;
    none.phi = reach;
    return none;
  }
  for (int i = 0; i < count_; ++i) {
    const Entry& e = memo_[i];
    if (!(e.x == x)) continue;
    // The search's answer is the first of the solid voxels with d2 < reach^2 in the order
    // (d2, index) (sdf_detail::sdf_nearer), and reach -> reach * reach is monotone in floating
    // point: an answer found within e.reach is the answer within any reach whose square exceeds
    // its d2; 'nothing within e.reach' is the answer within any shorter reach. (A found answer has
    // e.best2 < e.reach^2, so a reach beyond e.reach always takes the first branch; +inf, nothing
    // found, never does.)
    if (e.best2 < reach * reach) return e.sd;
    if (reach <= e.reach) {
      SignedDistance none;
      none.phi = reach;
      return none;
    }
  }
  if (certificate_ != nullptr && reach > 0.0 && tooth_.octree.levels() > 0) {
    const VoxelGrid& grid = tooth_.grid();
    int idx[3];
    if (!sdf_detail::voxel_of(grid, x, idx) ||
        grid.voxels[grid.index(idx[0], idx[1], idx[2])] == kEmpty) {
      certificate_->count(false);
      return certified_search(x, reach);
    }
  }
  double best2;
  const SignedDistance sd = signed_distance(tooth_, x, reach, &best2);
  if (best2 >= 0.0) remember(x, reach, best2, sd);  // outside (the oldest entry makes room)
  return sd;
}

}  // namespace dentsim::fast
