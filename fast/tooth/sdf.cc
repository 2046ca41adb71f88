#include "fast/tooth/sdf.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

#include "fast/tooth/cut_set.h"
#include "fast/tooth/nearest_voxel_walk.h"

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

namespace {

using voxel_walk::gap2;
using voxel_walk::plane;
using voxel_walk::voxel_distance2;

// Whether x lies within eps (<= h) of a plane origin_a + h i, 0 <= i <= N, on some axis: the
// planes about x's grid coordinate u (its truncation is within one cell of its floor, and a
// coordinate more than 3 cells outside the grid is farther than h from every plane).
bool near_grid_plane(const VoxelGrid& grid, const Vec3& x, double eps) {
  for (int a = 0; a < 3; ++a) {
    const double u = (x[a] - grid.origin[a]) / grid.voxel_size;
    if (!(u > -3.0 && u < grid.n + 3.0)) continue;
    const int i = static_cast<int>(u);
    for (int d = -2; d <= 2; ++d) {
      if (std::abs(x[a] - plane(grid, a, i + d)) < eps) return true;
    }
  }
  return false;
}

// The walk's watch (fast/tooth/nearest_voxel_walk.h): `other`, a lower bound on D of every exposed
// voxel the search has ruled out (the least of the bounds of the blocks it pruned and of the D of
// the voxels it tested and did not keep), and the voxels whose D was computed.
struct BallWatch {
  double other = std::numeric_limits<double>::infinity();
  long tested = 0;
  void ruled_out(double d2) { other = std::min(other, d2); }
  void tested_one() { ++tested; }
};

}  // namespace

LocalVoxelDistance::LocalVoxelDistance(const VoxelTooth& tooth, const SurfaceVoxels& surface)
    : tooth_(tooth),
      surface_(surface),
      max_reach_(0x1p23 * tooth.grid().voxel_size),
      extent_(tooth.grid().origin.cwiseAbs().maxCoeff() +
              tooth.grid().n * tooth.grid().voxel_size) {}

bool LocalVoxelDistance::outside(const Vec3& x, double reach, SignedDistance* out,
                                 double* best2_out) const {
  static_assert(kMaxSpan == voxel_walk::kMaxSpan);
  ++queries_;
  const VoxelGrid& grid = tooth_.grid();
  const int n = grid.n;
  const double h = grid.voxel_size;
  const std::size_t nn = static_cast<std::size_t>(n);
  // A voxel certified about where it was found (header comment), the latest balls first.
  if (reach > 0.0 && x.allFinite()) {
    for (int at = 0; at < ball_count_; ++at) {
      const Ball& ball = balls_[static_cast<std::size_t>((ball_next_ - 1 - at + kBalls) % kBalls)];
      const double left = ball.lower - (x - ball.x).norm();
      if (!(left >= ball.margin) || grid.voxels[ball.voxel] == kEmpty) continue;
      const std::size_t v = ball.voxel;
      const int i = static_cast<int>(v % nn), j = static_cast<int>((v / nn) % nn);
      const int k = static_cast<int>(v / (nn * nn));
      const double d2 = voxel_distance2(grid, i, j, k, x);
      const double phi = std::sqrt(d2);
      if (!(left >= phi + ball.margin)) continue;
      ++reused_;
      SignedDistance sd;
      sd.phi = reach;
      *best2_out = std::numeric_limits<double>::infinity();
      if (d2 < reach * reach) {
        sd.nearest = Vec3(std::clamp(x[0], plane(grid, 0, i), plane(grid, 0, i + 1)),
                          std::clamp(x[1], plane(grid, 1, j), plane(grid, 1, j + 1)),
                          std::clamp(x[2], plane(grid, 2, k), plane(grid, 2, k + 1)));
        sd.voxel = v;
        sd.found = true;
        sd.phi = phi;
        *best2_out = d2;
        hint_ = v;
        have_hint_ = true;
      }
      *out = sd;
      return true;
    }
  }
  // The claim's conditions (header comment); 2^-23 reach and 2^-44 (...) are exact products.
  const double eps = 0x1p-23 * reach;
  if (!surface_.current() || !(reach > 0.0) || !(reach <= max_reach_) ||
      !(eps >= 0x1p-44 * (extent_ + reach)) || !x.allFinite() || near_grid_plane(grid, x, eps)) {
    ++fallbacks_;
    return false;
  }
  // The walk's best so far (fast/tooth/nearest_voxel_walk.h): found and voxel in best.sd, its D in
  // best.d2; best.watch the bounds it ruled voxels out by (the balls', below).
  VoxelWalk<BallWatch> best;
  best.d2 = reach * reach;  // outside_distance's bound: a candidate has D < reach^2
  // The last answer's voxel and the balls' first: any solid voxel's (D, index) bounds the answer's
  // (the exposed minimum is the solid one, header comment), and the answer is often one of them.
  auto candidate = [&](std::size_t v) {
    if (grid.voxels[v] == kEmpty) return;
    const int i = static_cast<int>(v % nn), j = static_cast<int>((v / nn) % nn);
    const int k = static_cast<int>(v / (nn * nn));
    const double d2 = voxel_distance2(grid, i, j, k, x);
    if (!sdf_detail::sdf_nearer(d2, v, best.d2, best.sd)) return;
    if (best.sd.found) best.watch.ruled_out(best.d2);
    best.d2 = d2;
    best.sd.voxel = v;
    best.sd.found = true;
  };
  if (have_hint_) candidate(hint_);
  for (int at = 0; at < ball_count_; ++at) {
    if (!have_hint_ || balls_[static_cast<std::size_t>(at)].voxel != hint_) {
      candidate(balls_[static_cast<std::size_t>(at)].voxel);
    }
  }
  // The bricks within the bound r (the walk's span: a brick beyond it is more than r + 7 h away).
  const double r = best.sd.found ? std::sqrt(best.d2) : reach;
  if (!walk_nearest_voxel(surface_, grid, x, r, &best)) {
    ++fallbacks_;
    return false;
  }
  voxels_tested_ += best.watch.tested;
  SignedDistance sd;
  sd.phi = reach;
  *best2_out = std::numeric_limits<double>::infinity();
  if (best.sd.found) {
    const std::size_t v = best.sd.voxel;
    const int idx[3] = {static_cast<int>(v % nn), static_cast<int>((v / nn) % nn),
                        static_cast<int>(v / (nn * nn))};
    for (int a = 0; a < 3; ++a) {
      sd.nearest[a] = std::clamp(x[a], plane(grid, a, idx[a]), plane(grid, a, idx[a] + 1));
    }
    sd.voxel = v;
    sd.found = true;
    sd.phi = std::sqrt(best.d2);
    *best2_out = best.d2;
    hint_ = v;
    have_hint_ = true;
    // The ball about x in which v stays the answer: every other solid voxel is at least
    // sqrt(L) from x, L the least of the search's `other`, the bricks beyond its span ((r + 7 h)^2
    // and more) and the solid face neighbours of v (header comment).
    double lower2 = std::min(best.watch.other, (r + 4.0 * h) * (r + 4.0 * h));
    for (int a = 0; a < 3; ++a) {
      for (const int d : {-1, 1}) {
        int m[3] = {idx[0], idx[1], idx[2]};
        m[a] += d;
        if (m[a] < 0 || m[a] >= n || !grid.solid(m[0], m[1], m[2])) continue;
        lower2 = std::min(lower2, voxel_distance2(grid, m[0], m[1], m[2], x));
      }
    }
    if (lower2 > best.d2) {
      const double lower = std::sqrt(lower2);
      balls_[static_cast<std::size_t>(ball_next_)] = {x, lower, 1e-9 * h + 1e-12 * lower, v};
      ball_next_ = (ball_next_ + 1) % kBalls;
      ball_count_ = std::min(ball_count_ + 1, kBalls);
    }
  }
  *out = sd;
  return true;
}

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
  RecalledAnswers& memo = answers();
  constexpr int kEntries = RecalledAnswers::kEntries;
  memo.entries[memo.next] = {x, reach, best2, sd};
  memo.next = (memo.next + 1) % kEntries;
  memo.count = std::max(memo.count, memo.next == 0 ? kEntries : memo.next);
}

SignedDistance RecallingVoxelSolid::search_outside(const Vec3& x, double reach,
                                                   double* best2) const {
  SignedDistance sd;
  if (local_ != nullptr && local_->outside(x, reach, &sd, best2)) return sd;
  return outside_distance(tooth_.octree, x, reach, best2);
}

SignedDistance RecallingVoxelSolid::certified_search(const Vec3& x, double reach) const {
  const VoxelGrid& grid = tooth_.grid();
  const double wide = FreeSpaceCertificate::widened(reach, grid.voxel_size);
  double best2;
  const SignedDistance sd = search_outside(x, wide, &best2);
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
  const RecalledAnswers& memo = answers();
  for (int i = 0; i < memo.count; ++i) {
    const RecalledAnswers::Entry& e = memo.entries[i];
    if (!(e.x == x)) continue;
    // Kept from an earlier update: its voxel may have been drilled away since (RecalledAnswers).
    if (e.sd.found && tooth_.grid().voxels[e.sd.voxel] == kEmpty) continue;
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
  if ((certificate_ != nullptr || local_ != nullptr) && reach > 0.0 &&
      tooth_.octree.levels() > 0) {
    const VoxelGrid& grid = tooth_.grid();
    int idx[3];
    if (!sdf_detail::voxel_of(grid, x, idx) ||
        grid.voxels[grid.index(idx[0], idx[1], idx[2])] == kEmpty) {
      if (certificate_ == nullptr) {
        double best2;
        const SignedDistance sd = search_outside(x, reach, &best2);
        remember(x, reach, best2, sd);
        return sd;
      }
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
