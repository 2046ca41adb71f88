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

// Per 2^3 byte of the bits (bit c its voxel (c & 1, (c >> 1) & 1, c >> 2)), per axis, which of its
// two layers hold a set bit: 1 the lower, 2 the upper, 3 both; packed x | y << 2 | z << 4.
constexpr std::array<std::uint8_t, 256> kByteLayers = [] {
  std::array<std::uint8_t, 256> t{};
  for (int b = 1; b < 256; ++b) {
    const int lx = ((b & 0x55) != 0 ? 1 : 0) | ((b & 0xaa) != 0 ? 2 : 0);
    const int ly = ((b & 0x33) != 0 ? 1 : 0) | ((b & 0xcc) != 0 ? 2 : 0);
    const int lz = ((b & 0x0f) != 0 ? 1 : 0) | ((b & 0xf0) != 0 ? 2 : 0);
    t[static_cast<std::size_t>(b)] = static_cast<std::uint8_t>(lx | ly << 2 | lz << 4);
  }
  return t;
}();

// One axis of a brick: its voxels' squared gaps to x (box_distance2's terms; +inf beyond the
// grid); per run q of 2 voxels and layer set l (kByteLayers' code) the least term of the voxels in
// l, and the least of each run of 4. A block's term on an axis is then no larger than any of its
// set voxels', so a block no nearer than the best holds no better voxel.
struct AxisTerms {
  double t[kB];
  double pair[kB / 2][4];  // [q][l], l = 1 (the lower voxel), 2 (the upper), 3 (both)
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
  for (int q = 0; q < kB / 2; ++q) {
    out->pair[q][1] = out->t[2 * q];
    out->pair[q][2] = out->t[2 * q + 1];
    out->pair[q][3] = std::min(out->t[2 * q], out->t[2 * q + 1]);
  }
  out->m4[0] = std::min(out->pair[0][3], out->pair[1][3]);
  out->m4[1] = std::min(out->pair[2][3], out->pair[3][3]);
}

// The search's best so far as sdf_nearer and sdf_prunable read it (found, voxel) and its d2, and
// `other`: a lower bound on D of every exposed voxel the search has ruled out (the least of the
// bounds of the blocks it pruned and of the D of the voxels it tested and did not keep).
struct Best {
  SignedDistance sd;
  double d2;
  double other = std::numeric_limits<double>::infinity();
  long tested = 0;  // voxels whose D was computed
};

// Brick (bx, by, bz) (its words `bits`, its axes' terms X, Y, Z): its words nearest first, in a
// word its bytes by their boxes shrunk to their set bits, and their voxels, each by
// box_distance2's terms summed in its order ((t_x + t_y) + t_z: the same D).
void search_brick(const std::uint64_t* bits, const AxisTerms& X, const AxisTerms& Y,
                  const AxisTerms& Z, int bx, int by, int bz, std::size_t nn, Best* best) {
  struct Word {
    double d2;
    int w;
  };
  Word order[SurfaceVoxels::kWords];
  int count = 0;
  for (int w = 0; w < SurfaceVoxels::kWords; ++w) {
    if (bits[w] == 0) continue;
    // Word w: the 4^3 block (x, y, z) = bits 0, 1, 2 of w (the Morton layout, cut_set.h).
    const double d2 = (X.m4[w & 1] + Y.m4[(w >> 1) & 1]) + Z.m4[w >> 2];
    if (sdf_detail::sdf_prunable(d2, best->d2, best->sd)) {
      best->other = std::min(best->other, d2);
      continue;
    }
    int at = count++;
    while (at > 0 && order[at - 1].d2 > d2) {
      order[at] = order[at - 1];
      --at;
    }
    order[at] = {d2, w};
  }
  for (int i = 0; i < count; ++i) {
    // In increasing order: once one is no nearer than the best, none after it is.
    if (sdf_detail::sdf_prunable(order[i].d2, best->d2, best->sd)) {
      best->other = std::min(best->other, order[i].d2);
      break;
    }
    const int w = order[i].w;
    const int wx = w & 1, wy = (w >> 1) & 1, wz = w >> 2;
    const std::uint64_t word = bits[w];
    // The word's runs of 2 on each axis: pair rows 2 w_a and 2 w_a + 1, 4 layer sets each.
    const double* px = X.pair[2 * wx];
    const double* py = Y.pair[2 * wy];
    const double* pz = Z.pair[2 * wz];
#pragma GCC unroll 8
    for (int byte = 0; byte < 8; ++byte) {
      const unsigned block = static_cast<unsigned>(word >> (8 * byte)) & 0xffu;
      if (block == 0) continue;
      // Byte `byte`: the 2^3 block (2 w_a + its bit a) of the brick; bit c its child c.
      const int ox = byte & 1, oy = (byte >> 1) & 1, oz = byte >> 2;
      const unsigned layers = kByteLayers[block];
      const double d2q = (px[4 * ox + (layers & 3)] + py[4 * oy + ((layers >> 2) & 3)]) +
                         pz[4 * oz + (layers >> 4)];
      if (sdf_detail::sdf_prunable(d2q, best->d2, best->sd)) {
        best->other = std::min(best->other, d2q);
        continue;
      }
      const int qx = 2 * wx + ox, qy = 2 * wy + oy, qz = 2 * wz + oz;
      const double* tx = X.t + 2 * qx;
      const double* ty = Y.t + 2 * qy;
      const double* tz = Z.t + 2 * qz;
#pragma GCC unroll 8
      for (int c = 0; c < 8; ++c) {
        if ((block & (1u << c)) == 0) continue;
        const double d2 = (tx[c & 1] + ty[(c >> 1) & 1]) + tz[c >> 2];  // box_distance2's sum
        ++best->tested;
        if (d2 > best->d2) {  // not nearer (sdf_nearer), whatever its index
          best->other = std::min(best->other, d2);
          continue;
        }
        const std::size_t v = static_cast<std::size_t>(kB * bx + 2 * qx + (c & 1)) +
                              nn * (static_cast<std::size_t>(kB * by + 2 * qy + ((c >> 1) & 1)) +
                                    nn * static_cast<std::size_t>(kB * bz + 2 * qz + (c >> 2)));
        if (best->sd.found && v == best->sd.voxel) continue;  // the best itself (the hint)
        if (!sdf_detail::sdf_nearer(d2, v, best->d2, best->sd)) {
          best->other = std::min(best->other, d2);
          continue;
        }
        if (best->sd.found) best->other = std::min(best->other, best->d2);
        best->d2 = d2;
        best->sd.voxel = v;
        best->sd.found = true;
      }
    }
  }
}

// D of voxel (i, j, k) at x: box_distance2's terms summed in its order.
inline double voxel_distance2(const VoxelGrid& grid, int i, int j, int k, const Vec3& x) {
  return (gap2(x[0], plane(grid, 0, i), plane(grid, 0, i + 1)) +
          gap2(x[1], plane(grid, 1, j), plane(grid, 1, j + 1))) +
         gap2(x[2], plane(grid, 2, k), plane(grid, 2, k + 1));
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
  Best best;
  best.d2 = reach * reach;  // outside_distance's bound: a candidate has D < reach^2
  // The last answer's voxel and the balls' first: any solid voxel's (D, index) bounds the answer's
  // (the exposed minimum is the solid one, header comment), and the answer is often one of them.
  auto candidate = [&](std::size_t v) {
    if (grid.voxels[v] == kEmpty) return;
    const int i = static_cast<int>(v % nn), j = static_cast<int>((v / nn) % nn);
    const int k = static_cast<int>(v / (nn * nn));
    const double d2 = voxel_distance2(grid, i, j, k, x);
    if (!sdf_detail::sdf_nearer(d2, v, best.d2, best.sd)) return;
    if (best.sd.found) best.other = std::min(best.other, best.d2);
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
  // The bricks within the bound r, one brick of margin each side (a brick beyond is more than
  // r + 7 h away: the truncations below are within one brick of the floors, and conservative),
  // and their boxes' term on each axis.
  const double r = best.sd.found ? std::sqrt(best.d2) : reach;
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
    auto search = [&](const std::uint64_t* bits, int bx, int by, int bz) {
      search_brick(bits, axis(0, bx), axis(1, by), axis(2, bz), bx, by, bz, nn, &best);
    };
    // The bricks not prunable, nearest first (by their boxes' d2); beyond the room of the list,
    // a brick is searched at once (the order decides no answer, sdf_nearer: only the work).
    struct Brick {
      double d2;
      const std::uint64_t* bits;
      int bx, by, bz;
    };
    constexpr int kRoom = 128;
    Brick order[kRoom];
    int count = 0;
    for (int bz = b_lo[2]; bz <= b_hi[2]; ++bz) {
      const double tz = brick_term[2][bz - b_lo[2]];
      if (sdf_detail::sdf_prunable(tz, best.d2, best.sd)) {  // (t_x + t_y) + t_z >= t_z
        best.other = std::min(best.other, tz);
        continue;
      }
      for (int by = b_lo[1]; by <= b_hi[1]; ++by) {
        const double ty = brick_term[1][by - b_lo[1]];
        if (sdf_detail::sdf_prunable(ty, best.d2, best.sd)) {
          best.other = std::min(best.other, ty);
          continue;
        }
        for (int bx = b_lo[0]; bx <= b_hi[0]; ++bx) {
          const std::uint64_t* bits = surface_.brick(surface_.slot(bx, by, bz));
          if (bits == nullptr) continue;
          const double d2b = (brick_term[0][bx - b_lo[0]] + ty) + tz;
          if (sdf_detail::sdf_prunable(d2b, best.d2, best.sd)) {
            best.other = std::min(best.other, d2b);
            continue;
          }
          if (count == kRoom) {
            search(bits, bx, by, bz);
            continue;
          }
          int at = count++;
          while (at > 0 && order[at - 1].d2 > d2b) {
            order[at] = order[at - 1];
            --at;
          }
          order[at] = {d2b, bits, bx, by, bz};
        }
      }
    }
    for (int i = 0; i < count; ++i) {
      const Brick& b = order[i];
      if (sdf_detail::sdf_prunable(b.d2, best.d2, best.sd)) {  // and every brick after it
        best.other = std::min(best.other, b.d2);
        break;
      }
      search(b.bits, b.bx, b.by, b.bz);
    }
    voxels_tested_ += best.tested;
  }
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
    double lower2 = std::min(best.other, (r + 4.0 * h) * (r + 4.0 * h));
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
