#include "fast/tooth/sdf.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

#include "fast/tooth/cut_set.h"

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

constexpr int kB = 8;  // SurfaceVoxels::kBrick

// The squared gap of coordinate x to [lo, hi], as box_distance2 computes it.
inline double gap2(double x, double lo, double hi) {
  const double q = std::clamp(x, lo, hi);
  return (x - q) * (x - q);
}

// The grid plane origin_a + h i (box_distance2's bounds, the same expression).
inline double plane(const VoxelGrid& grid, int a, int i) {
  return grid.origin[a] + grid.voxel_size * i;
}

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

// One axis of a brick: its voxels' squared gaps to x (box_distance2's terms; +inf beyond the
// grid), and the least of each run of 2 and of 4 (a 2^3 or 4^3 block's term on that axis: no
// larger than any of its voxels', so a block no nearer than the best holds no better voxel).
struct AxisTerms {
  double t[kB];
  double m2[kB / 2];
  double m4[2];
};

void axis_terms(const VoxelGrid& grid, int a, int b, double x, AxisTerms* out) {
  const int first = kB * b;
  double lo = plane(grid, a, first);
  for (int l = 0; l < kB; ++l) {
    const int i = first + l;
    const double hi = plane(grid, a, i + 1);
    out->t[l] = i < grid.n ? gap2(x, lo, hi) : std::numeric_limits<double>::infinity();
    lo = hi;
  }
  for (int q = 0; q < kB / 2; ++q) out->m2[q] = std::min(out->t[2 * q], out->t[2 * q + 1]);
  out->m4[0] = std::min(out->m2[0], out->m2[1]);
  out->m4[1] = std::min(out->m2[2], out->m2[3]);
}

}  // namespace

LocalVoxelDistance::LocalVoxelDistance(const VoxelTooth& tooth, const SurfaceVoxels& surface)
    : tooth_(tooth),
      surface_(surface),
      max_reach_(0x1p23 * tooth.grid().voxel_size),
      extent_(tooth.grid().origin.cwiseAbs().maxCoeff() +
              tooth.grid().n * tooth.grid().voxel_size) {}

bool LocalVoxelDistance::outside(const Vec3& x, double reach, SignedDistance* out,
                                 double* best2_out) const {
  static_assert(SurfaceVoxels::kBrick == kB && SurfaceVoxels::kWords == 8);
  ++queries_;
  const VoxelGrid& grid = tooth_.grid();
  const int n = grid.n;
  const double h = grid.voxel_size;
  // The claim's conditions (header comment); 2^-23 reach and 2^-44 (...) are exact products.
  const double eps = 0x1p-23 * reach;
  if (!surface_.current() || !(reach > 0.0) || !(reach <= max_reach_) ||
      !(eps >= 0x1p-44 * (extent_ + reach)) || !x.allFinite() || near_grid_plane(grid, x, eps)) {
    ++fallbacks_;
    return false;
  }
  const std::size_t nn = static_cast<std::size_t>(n);
  // The best so far as sdf_nearer and sdf_prunable read it (found, voxel) and its d2.
  SignedDistance best;
  double best2 = reach * reach;  // outside_distance's bound: a candidate has D < reach^2
  // The last answer's voxel first, while it is exposed.
  if (have_hint_) {
    const int i = static_cast<int>(hint_ % nn), j = static_cast<int>((hint_ / nn) % nn);
    const int k = static_cast<int>(hint_ / (nn * nn));
    if (surface_.exposed(i, j, k)) {
      const double d2 = (gap2(x[0], plane(grid, 0, i), plane(grid, 0, i + 1)) +
                         gap2(x[1], plane(grid, 1, j), plane(grid, 1, j + 1))) +
                        gap2(x[2], plane(grid, 2, k), plane(grid, 2, k + 1));
      if (d2 < best2) {
        best2 = d2;
        best.voxel = hint_;
        best.found = true;
      }
    }
  }
  // The bricks within the bound r, one brick of margin each side (a brick beyond is more than
  // r + 7 h away: the truncations below are within one brick of the floors, and conservative),
  // and their boxes' term on each axis.
  const double r = best.found ? std::sqrt(best2) : reach;
  const double side = kB * h;
  const double last = surface_.slots_per_axis() - 1.0;
  int b_lo[3], b_hi[3];
  double brick_term[3][kMaxSpan];
  bool none = false;
  for (int a = 0; a < 3; ++a) {
    const double t0 = std::clamp((x[a] - r - grid.origin[a]) / side, -1.0, last + 2.0);
    const double t1 = std::clamp((x[a] + r - grid.origin[a]) / side, -1.0, last + 2.0);
    b_lo[a] = std::max(0, static_cast<int>(t0) - 1);
    b_hi[a] = std::min(static_cast<int>(last), static_cast<int>(t1) + 1);
    none = none || b_lo[a] > b_hi[a];  // no brick of the grid within r (then no hint either)
    if (b_hi[a] - b_lo[a] + 1 > kMaxSpan) {
      ++fallbacks_;
      return false;
    }
    for (int b = b_lo[a]; b <= b_hi[a]; ++b) {
      brick_term[a][b - b_lo[a]] =
          gap2(x[a], plane(grid, a, kB * b), plane(grid, a, std::min(kB * (b + 1), n)));
    }
  }
  if (!none) {
    // Each axis's voxel terms, per brick coordinate, computed when a brick first needs them.
    AxisTerms terms[3][kMaxSpan];
    bool have[3][kMaxSpan] = {};
    auto axis = [&](int a, int b) -> const AxisTerms& {
      const int at = b - b_lo[a];
      if (!have[a][at]) {
        axis_terms(grid, a, b, x[a], &terms[a][at]);
        have[a][at] = true;
      }
      return terms[a][at];
    };
    long tested = 0;
    for (int bz = b_lo[2]; bz <= b_hi[2]; ++bz) {
      const double tz = brick_term[2][bz - b_lo[2]];
      if (sdf_detail::sdf_prunable(tz, best2, best)) continue;  // (t_x + t_y) + t_z >= t_z
      for (int by = b_lo[1]; by <= b_hi[1]; ++by) {
        const double ty = brick_term[1][by - b_lo[1]];
        if (sdf_detail::sdf_prunable(ty, best2, best)) continue;
        for (int bx = b_lo[0]; bx <= b_hi[0]; ++bx) {
          const double d2b = (brick_term[0][bx - b_lo[0]] + ty) + tz;
          if (sdf_detail::sdf_prunable(d2b, best2, best)) continue;
          const std::uint64_t* bits = surface_.brick(surface_.slot(bx, by, bz));
          if (bits == nullptr) continue;
          const AxisTerms& X = axis(0, bx);
          const AxisTerms& Y = axis(1, by);
          const AxisTerms& Z = axis(2, bz);
          for (int w = 0; w < SurfaceVoxels::kWords; ++w) {
            std::uint64_t word = bits[w];
            if (word == 0) continue;
            // Word w: the 4^3 block (x, y, z) = bits 0, 1, 2 of w (the Morton layout, cut_set.h).
            const int wx = w & 1, wy = (w >> 1) & 1, wz = w >> 2;
            const double d2w = (X.m4[wx] + Y.m4[wy]) + Z.m4[wz];
            if (sdf_detail::sdf_prunable(d2w, best2, best)) continue;
            while (word != 0) {
              const int byte = std::countr_zero(word) >> 3;
              std::uint64_t block = (word >> (8 * byte)) & 0xff;
              word &= ~(std::uint64_t{0xff} << (8 * byte));
              // Byte `byte`: the 2^3 block (qx, qy, qz) of the brick; bit c its child c.
              const int qx = 2 * wx + (byte & 1), qy = 2 * wy + ((byte >> 1) & 1);
              const int qz = 2 * wz + (byte >> 2);
              const double d2q = (X.m2[qx] + Y.m2[qy]) + Z.m2[qz];
              if (sdf_detail::sdf_prunable(d2q, best2, best)) continue;
              while (block != 0) {
                const int c = std::countr_zero(block);
                block &= block - 1;
                const int lx = 2 * qx + (c & 1), ly = 2 * qy + ((c >> 1) & 1);
                const int lz = 2 * qz + (c >> 2);
                const double d2 = (X.t[lx] + Y.t[ly]) + Z.t[lz];  // box_distance2's sum
                ++tested;
                if (d2 > best2) continue;  // not nearer (sdf_nearer), whatever its index
                const std::size_t v =
                    static_cast<std::size_t>(kB * bx + lx) +
                    nn * (static_cast<std::size_t>(kB * by + ly) +
                          nn * static_cast<std::size_t>(kB * bz + lz));
                if (!sdf_detail::sdf_nearer(d2, v, best2, best)) continue;
                best2 = d2;
                best.voxel = v;
                best.found = true;
              }
            }
          }
        }
      }
    }
    voxels_tested_ += tested;
  }
  SignedDistance sd;
  sd.phi = reach;
  *best2_out = std::numeric_limits<double>::infinity();
  if (best.found) {
    const int idx[3] = {static_cast<int>(best.voxel % nn), static_cast<int>((best.voxel / nn) % nn),
                        static_cast<int>(best.voxel / (nn * nn))};
    for (int a = 0; a < 3; ++a) {
      sd.nearest[a] = std::clamp(x[a], plane(grid, a, idx[a]), plane(grid, a, idx[a] + 1));
    }
    sd.voxel = best.voxel;
    sd.found = true;
    sd.phi = std::sqrt(best2);
    *best2_out = best2;
    hint_ = best.voxel;
    have_hint_ = true;
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
