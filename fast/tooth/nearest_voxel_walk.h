// One nearest-first walk over the tooth's exposed voxels (issue #30, stop 48), shared by the sdf
// model's local distance query (LocalVoxelDistance::outside, fast/tooth/sdf.h) and the field
// model's contact material (SurfaceCutSet::material_alone, fast/tooth/cut_set.h), which until
// stop 48 each wrote it.
//
// What it finds. Over the exposed voxels v of SurfaceVoxels (fast/tooth/cut_set.h: bricks of 8^3,
// Morton order inside a brick) with D(v) < best->d2 at the call, the least (D(v), v): D is
// box_distance2's double (reference/tooth/sdf.h; per axis the squared gap (x - clamp(x, lo, hi))^2
// with lo, hi = origin + h i, summed (t_x + t_y) + t_z), and (D, v) ordered by sdf_detail::
// sdf_nearer (the smaller D, then the smaller flat index). The caller may seed *best with a voxel
// it already knows (found, voxel, d2): the answer is then the least of the seed and the exposed
// ones, and the seed itself is skipped if met. The answer does not depend on the visiting order
// (the least of a total order is unique), only the work does.
//
// How. Only the bricks within the span of r (the caller's bound: sqrt of the starting best, or the
// reach), one brick of margin each side (a brick beyond is more than r + 7 h away: the
// truncations are within one brick of the floors) are listed; a whole row of bricks is skipped
// when its box's term on z, then on y, is already no nearer (a brick's D is no less than either).
// The bricks left are searched by increasing box distance, in a brick its 4^3 words likewise, and
// a 2^3 byte's box is shrunk to its set bits per axis (kByteLayers: a byte's term on an axis is the
// least of its set voxels', so bytes in the cap about the tangent point are pruned). A block is
// skipped when sdf_prunable(bound): its bound not < best, and not = best once one is found (a tie
// with a smaller index). Sound: a block's term on an axis is no larger than any of its voxels'
// (the least over them, or the slab of a brick holding them), and rounded addition is monotone,
// so no voxel of a skipped block is nearer.
//
// The watch (a template parameter, no virtual call): watch.ruled_out(b) is called with every bound
// b by which the walk rules voxels out (a block's bound, a voxel's D not kept, a best replaced),
// so that min(b) bounds below D of every exposed voxel within the span other than the answer (the
// sdf model's balls need it); watch.tested_one() once per voxel whose D is computed. The material
// passes a watch that does nothing (the compiler drops the calls).
//
// Real-time: fixed-size arrays on the stack; nothing allocates or throws.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

#include "fast/tooth/cut_set.h"
#include "reference/tooth/sdf.h"

namespace dentsim::fast {

namespace voxel_walk {

constexpr int kB = SurfaceVoxels::kBrick;
// The largest brick span on an axis the walk holds (a wider one is refused).
constexpr int kMaxSpan = 24;

// The squared gap of coordinate x to [lo, hi], as box_distance2 computes it.
inline double gap2(double x, double lo, double hi) {
  const double q = std::clamp(x, lo, hi);
  return (x - q) * (x - q);
}

// The grid plane origin_a + h i (box_distance2's bounds, the same expression).
inline double plane(const VoxelGrid& grid, int a, int i) {
  return grid.origin[a] + grid.voxel_size * i;
}

// D of voxel (i, j, k) at x: box_distance2's terms summed in its order.
inline double voxel_distance2(const VoxelGrid& grid, int i, int j, int k, const Vec3& x) {
  return (gap2(x[0], plane(grid, 0, i), plane(grid, 0, i + 1)) +
          gap2(x[1], plane(grid, 1, j), plane(grid, 1, j + 1))) +
         gap2(x[2], plane(grid, 2, k), plane(grid, 2, k + 1));
}

// Per 2^3 byte of the bits (bit c its voxel (c & 1, (c >> 1) & 1, c >> 2)), per axis, which of its
// two layers hold a set bit: 1 the lower, 2 the upper, 3 both; packed x | y << 2 | z << 4.
inline constexpr std::array<std::uint8_t, 256> kByteLayers = [] {
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
// l, and the least of each run of 4.
struct AxisTerms {
  double t[kB];
  double pair[kB / 2][4];  // [q][l], l = 1 (the lower voxel), 2 (the upper), 3 (both)
  double m4[2];
};

inline void axis_terms(const VoxelGrid& grid, int a, int b, double x, AxisTerms* out) {
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

}  // namespace voxel_walk

// The walk's state: the best so far as sdf_nearer and sdf_prunable read it (sd.found, sd.voxel)
// and its D (d2), and the watch. One object, so that the watch's stores are known not to touch
// d2 (separate pointers to doubles would make the compiler reload it after each).
template <class Watch>
struct VoxelWalk {
  SignedDistance sd;
  double d2 = 0.0;
  Watch watch;
};

namespace voxel_walk {

// Brick (bx, by, bz) (its words `bits`, its axes' terms X, Y, Z): its words nearest first, in a
// word its bytes by their boxes shrunk to their set bits, and their voxels.
template <class Watch>
void search_brick(const std::uint64_t* bits, const AxisTerms& X, const AxisTerms& Y,
                  const AxisTerms& Z, int bx, int by, int bz, std::size_t nn,
                  VoxelWalk<Watch>* best) {
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
      best->watch.ruled_out(d2);
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
      best->watch.ruled_out(order[i].d2);
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
        best->watch.ruled_out(d2q);
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
        best->watch.tested_one();
        if (d2 > best->d2) {  // not nearer (sdf_nearer), whatever its index
          best->watch.ruled_out(d2);
          continue;
        }
        const std::size_t v = static_cast<std::size_t>(kB * bx + 2 * qx + (c & 1)) +
                              nn * (static_cast<std::size_t>(kB * by + 2 * qy + ((c >> 1) & 1)) +
                                    nn * static_cast<std::size_t>(kB * bz + 2 * qz + (c >> 2)));
        if (best->sd.found && v == best->sd.voxel) continue;  // the best itself (the seed)
        if (!sdf_detail::sdf_nearer(d2, v, best->d2, best->sd)) {
          best->watch.ruled_out(d2);
          continue;
        }
        if (best->sd.found) best->watch.ruled_out(best->d2);
        best->d2 = d2;
        best->sd.voxel = v;
        best->sd.found = true;
      }
    }
  }
}

}  // namespace voxel_walk

// The walk (header comment) at x within r over `surface` (the bits of grid's tooth): best->sd's
// found and voxel and best->d2 hold the seed (or found = false and the bound: a voxel is taken
// only with D < d2) and receive the answer; best->watch is told what the walk rules out. Returns false, nothing searched, when the span of r exceeds
// voxel_walk::kMaxSpan bricks on an axis (r finite, >= 0). No allocation, no throw.
template <class Watch>
bool walk_nearest_voxel(const SurfaceVoxels& surface, const VoxelGrid& grid, const Vec3& x,
                        double r, VoxelWalk<Watch>* best) {
  using namespace voxel_walk;
  const int n = grid.n;
  const std::size_t nn = static_cast<std::size_t>(n);
  const double side = kB * grid.voxel_size;
  const double last = surface.slots_per_axis() - 1.0;
  int b_lo[3], b_hi[3];
  double brick_term[3][kMaxSpan];
  for (int a = 0; a < 3; ++a) {
    const double t0 = std::clamp((x[a] - r - grid.origin[a]) / side, -1.0, last + 2.0);
    const double t1 = std::clamp((x[a] + r - grid.origin[a]) / side, -1.0, last + 2.0);
    b_lo[a] = std::max(0, static_cast<int>(t0) - 1);
    b_hi[a] = std::min(static_cast<int>(last), static_cast<int>(t1) + 1);
    if (b_hi[a] - b_lo[a] + 1 > kMaxSpan) return false;
    for (int b = b_lo[a]; b <= b_hi[a]; ++b) {
      brick_term[a][b - b_lo[a]] =
          gap2(x[a], plane(grid, a, kB * b), plane(grid, a, std::min(kB * (b + 1), n)));
    }
  }
  for (int a = 0; a < 3; ++a) {
    if (b_lo[a] > b_hi[a]) return true;  // no brick of the grid within r
  }
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
    search_brick(bits, axis(0, bx), axis(1, by), axis(2, bz), bx, by, bz, nn, best);
  };
  // The bricks not prunable, nearest first (by their boxes' d2); beyond the room of the list, a
  // brick is searched at once (the order decides no answer, sdf_nearer: only the work).
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
    if (sdf_detail::sdf_prunable(tz, best->d2, best->sd)) {  // (t_x + t_y) + t_z >= t_z
      best->watch.ruled_out(tz);
      continue;
    }
    for (int by = b_lo[1]; by <= b_hi[1]; ++by) {
      const double ty = brick_term[1][by - b_lo[1]];
      if (sdf_detail::sdf_prunable(ty, best->d2, best->sd)) {
        best->watch.ruled_out(ty);
        continue;
      }
      for (int bx = b_lo[0]; bx <= b_hi[0]; ++bx) {
        const std::uint64_t* bits = surface.brick(surface.slot(bx, by, bz));
        if (bits == nullptr) continue;
        const double d2b = (brick_term[0][bx - b_lo[0]] + ty) + tz;
        if (sdf_detail::sdf_prunable(d2b, best->d2, best->sd)) {
          best->watch.ruled_out(d2b);
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
    if (sdf_detail::sdf_prunable(b.d2, best->d2, best->sd)) {  // and every brick after it
      best->watch.ruled_out(b.d2);
      break;
    }
    search(b.bits, b.bx, b.by, b.bz);
  }
  return true;
}

// The watch of a caller that needs neither the bounds nor the count.
struct NoVoxelWatch {
  void ruled_out(double) {}
  void tested_one() {}
};

}  // namespace dentsim::fast
