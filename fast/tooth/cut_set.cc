// The cut set and the contact's material over the tooth's exposed voxels (fast/tooth/cut_set.h).
#include "fast/tooth/cut_set.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>

#include "fast/tooth/nearest_voxel_walk.h"
#include "reference/tooth/drilling.h"
#include "reference/tooth/sdf.h"

namespace dentsim::fast {

namespace {

constexpr int kB = SurfaceVoxels::kBrick;

// Spreads the low 10 bits of v to every third bit (the Morton code of brick coordinates).
std::uint64_t spread3(std::uint64_t v) {
  v &= 0x3ff;
  v = (v | (v << 16)) & 0x30000ffull;
  v = (v | (v << 8)) & 0x300f00full;
  v = (v | (v << 4)) & 0x30c30c3ull;
  v = (v | (v << 2)) & 0x9249249ull;
  return v;
}

}  // namespace

SurfaceVoxels::SurfaceVoxels(const VoxelTooth& tooth) {
  const VoxelGrid& grid = tooth.grid();
  n_ = grid.n;
  nb_ = (n_ + kB - 1) / kB;
  const std::size_t slots = static_cast<std::size_t>(nb_) * nb_ * nb_;
  index_.assign(slots, kNoRoom);
  // A brick's room for every slot holding a solid voxel (the octree's node of the brick's level
  // says so at once; a grid smaller than a brick is one slot).
  const int L = tooth.octree.levels();
  std::size_t room = 0;
  for (int bz = 0; bz < nb_; ++bz) {
    for (int by = 0; by < nb_; ++by) {
      for (int bx = 0; bx < nb_; ++bx) {
        const bool solid = L >= 3 ? tooth.octree.occupied(L - 3, bx, by, bz)
                                  : (n_ > 0 && tooth.octree.occupied(0, 0, 0, 0));
        if (!solid) continue;
        index_[slot(bx, by, bz)] = kNone;
        ++room;
      }
    }
  }
  bits_.reserve(room * kWords);
  for (int bz = 0; bz < nb_; ++bz) {
    for (int by = 0; by < nb_; ++by) {
      for (int bx = 0; bx < nb_; ++bx) {
        if (index_[slot(bx, by, bz)] == kNoRoom) continue;
        const int i1 = std::min(n_, kB * (bx + 1)), j1 = std::min(n_, kB * (by + 1));
        const int k1 = std::min(n_, kB * (bz + 1));
        for (int k = kB * bz; k < k1; ++k) {
          for (int j = kB * by; j < j1; ++j) {
            for (int i = kB * bx; i < i1; ++i) {
              if (tooth.codes.code(grid.index(i, j, k)) != 0) set(i, j, k, true);
            }
          }
        }
      }
    }
  }
}

bool SurfaceVoxels::set(int i, int j, int k, bool on) {
  const std::size_t s = slot(i / kB, j / kB, k / kB);
  std::int32_t id = index_[s];
  if (id < 0) {
    if (!on) return true;
    if (id == kNoRoom || bits_.size() + kWords > bits_.capacity()) return false;
    id = static_cast<std::int32_t>(bits_.size() / kWords);
    bits_.resize(bits_.size() + kWords, 0);  // within the reserve: no allocation
    index_[s] = id;
  }
  const int m = local_bit(i % kB, j % kB, k % kB);
  std::uint64_t& word = bits_[static_cast<std::size_t>(id) * kWords + static_cast<std::size_t>(m / 64)];
  const std::uint64_t bit = std::uint64_t{1} << (m % 64);
  word = on ? (word | bit) : (word & ~bit);
  return true;
}

bool SurfaceVoxels::update(const VoxelTooth& tooth, std::span<const std::size_t> removed) {
  const VoxelGrid& grid = tooth.grid();
  const std::size_t n = static_cast<std::size_t>(n_);
  for (const std::size_t v : removed) {
    const int i = static_cast<int>(v % n), j = static_cast<int>((v / n) % n);
    const int k = static_cast<int>(v / (n * n));
    for (int f = -1; f < 6; ++f) {  // the voxel, then its six face neighbours
      int u[3] = {i, j, k};
      if (f >= 0) u[face_axis(f)] += face_sign(f);
      if (!grid.inside(u[0], u[1], u[2])) continue;
      const bool on = tooth.codes.code(grid.index(u[0], u[1], u[2])) != 0;
      if (!set(u[0], u[1], u[2], on)) current_ = false;
    }
  }
  return current_;
}

bool SurfaceVoxels::remove(VoxelTooth& tooth, std::span<const std::size_t> removed) {
  const VoxelGrid& grid = tooth.grid();
  const std::size_t n = static_cast<std::size_t>(n_);
  for (const std::size_t v : removed) {
    const int i = static_cast<int>(v % n), j = static_cast<int>((v / n) % n);
    const int k = static_cast<int>(v / (n * n));
    if (tooth.octree.remove_voxel(i, j, k) == kEmpty) continue;  // its codes and bits hold
    if (!tooth.codes.set(v, 0) || !set(i, j, k, false)) current_ = false;
    for (int f = 0; f < 6; ++f) {
      int u[3] = {i, j, k};
      u[face_axis(f)] += face_sign(f);
      if (!grid.inside(u[0], u[1], u[2])) continue;
      const std::size_t w = grid.index(u[0], u[1], u[2]);
      if (grid.voxels[w] == kEmpty) continue;  // code 0 and bit clear, as before
      // Face f ^ 1 of u is the one toward v (the faces come in pairs -a, +a).
      const std::uint8_t before = tooth.codes.code(w);
      const bool stored = tooth.codes.set(w, static_cast<std::uint8_t>(before | (1u << (f ^ 1))));
      // A code not stored (impossible while the tooth only loses voxels) keeps the bit update()
      // would read.
      if (!set(u[0], u[1], u[2], stored || before != 0)) current_ = false;
    }
  }
  return current_;
}

bool SurfaceVoxels::exposed(int i, int j, int k) const {
  const std::uint64_t* b = brick(slot(i / kB, j / kB, k / kB));
  if (b == nullptr) return false;
  const int m = local_bit(i % kB, j % kB, k % kB);
  return ((b[m / 64] >> (m % 64)) & 1) != 0;
}

std::size_t SurfaceVoxels::count() const {
  std::size_t c = 0;
  for (const std::uint64_t w : bits_) c += static_cast<std::size_t>(std::popcount(w));
  return c;
}

bool SurfaceVoxels::replace(std::size_t s, const std::uint64_t* words) {
  std::int32_t id = index_[s];
  if (id < 0) {
    if (words == nullptr) return current_;  // an absent brick reads clear already
    if (id == kNoRoom || bits_.size() + kWords > bits_.capacity()) {
      current_ = false;
      return false;
    }
    id = static_cast<std::int32_t>(bits_.size() / kWords);
    bits_.resize(bits_.size() + kWords, 0);  // within the reserve: no allocation
    index_[s] = id;
  }
  static constexpr std::uint64_t kClear[kWords] = {};
  std::copy_n(words != nullptr ? words : kClear, kWords,
              &bits_[static_cast<std::size_t>(id) * kWords]);
  return current_;
}

namespace {

constexpr std::size_t kBrickCodes = static_cast<std::size_t>(kB) * kB * kB;

}  // namespace

void ToothBricks::reserve(const VoxelTooth& tooth, std::size_t capacity) {
  level_ = std::max(tooth.octree.levels() - 3, 0);
  per_axis_ = static_cast<std::size_t>((tooth.grid().n + kB - 1) / kB);
  node_bytes_ = tooth.octree.node_bytes(level_);
  capacity_ = capacity;
  count_ = 0;
  fits_ = true;
  entries_ = std::make_unique<Entry[]>(capacity);
  codes_ = std::make_unique_for_overwrite<std::uint8_t[]>(capacity * kBrickCodes);
  bits_ = std::make_unique_for_overwrite<std::uint64_t[]>(capacity * SurfaceVoxels::kWords);
  nodes_ = std::make_unique_for_overwrite<std::uint8_t[]>(capacity * node_bytes_);
}

bool ToothBricks::take(const VoxelTooth& tooth, const SurfaceVoxels& surface,
                       std::span<const std::size_t> removed, std::span<std::uint8_t> marks) {
  count_ = 0;
  fits_ = true;
  const VoxelGrid& grid = tooth.grid();
  const std::size_t n = static_cast<std::size_t>(grid.n);
  // marks[s]: 1 a face neighbour's brick (codes and bits), 2 a removed voxel's (and its node).
  // The slots listed in entries_ are the marked ones (a slot past the capacity is not marked).
  const auto mark = [&](const int u[3], std::uint8_t what) {
    const std::size_t s = surface.slot(u[0] / kB, u[1] / kB, u[2] / kB);
    if (marks[s] == 0) {
      if (count_ == capacity_) {
        fits_ = false;
        return;
      }
      entries_[count_].rows = 0;
      entries_[count_++].slot = static_cast<std::uint32_t>(s);
    }
    marks[s] = std::max(marks[s], what);
  };
  std::size_t last = 0;  // the entry of the last removed voxel's brick (they come in runs)
  for (const std::size_t v : removed) {
    const int c[3] = {static_cast<int>(v % n), static_cast<int>((v / n) % n),
                      static_cast<int>(v / (n * n))};
    mark(c, 2);
    if (!fits_) break;
    // v's row in its brick (Entry::rows): its entry, the last one's or found from the newest.
    const std::uint32_t s =
        static_cast<std::uint32_t>(surface.slot(c[0] / kB, c[1] / kB, c[2] / kB));
    if (entries_[last].slot != s) {
      last = count_ - 1;
      while (entries_[last].slot != s) --last;  // marked: listed
    }
    entries_[last].rows |= std::uint64_t{1} << ((c[1] % kB) + kB * (c[2] % kB));
    for (int f = 0; f < 6; ++f) {  // the face neighbours in another brick
      int u[3] = {c[0], c[1], c[2]};
      const int a = face_axis(f);
      u[a] += face_sign(f);
      if (!grid.inside(u[0], u[1], u[2]) || u[a] / kB == c[a] / kB) continue;
      mark(u, 1);
    }
    if (!fits_) break;
  }
  for (std::size_t e = 0; e < count_; ++e) {
    Entry& entry = entries_[e];
    std::uint8_t& m = marks[entry.slot];
    entry.node = m == 2;
    m = 0;
    if (!fits_) continue;  // the marks cleared only
    const std::uint8_t* codes = tooth.codes.brick(entry.slot);  // the same slots as the bits'
    entry.codes = codes != nullptr;
    if (entry.codes) std::copy_n(codes, kBrickCodes, &codes_[e * kBrickCodes]);
    const std::uint64_t* bits = surface.brick(entry.slot);
    entry.bits = bits != nullptr;
    if (entry.bits) {
      std::copy_n(bits, SurfaceVoxels::kWords, &bits_[e * SurfaceVoxels::kWords]);
    }
    if (entry.node) {
      const std::array<int, 3> b = brick_of(entry.slot);
      tooth.octree.save_node(level_, b[0], b[1], b[2], &nodes_[e * node_bytes_]);
    }
  }
  if (!fits_) count_ = 0;
  return fits_;
}

bool ToothBricks::apply(VoxelTooth& tooth, SurfaceVoxels& surface) const {
  bool stored = true;
  for (std::size_t e = 0; e < count_; ++e) {
    const Entry& entry = entries_[e];
    stored = tooth.codes.replace_brick(entry.slot,
                                       entry.codes ? &codes_[e * kBrickCodes] : nullptr) &&
             stored;
    stored = surface.replace(entry.slot,
                             entry.bits ? &bits_[e * SurfaceVoxels::kWords] : nullptr) &&
             stored;
    if (entry.node) {
      const std::array<int, 3> b = brick_of(entry.slot);
      tooth.octree.load_node_rows(level_, b[0], b[1], b[2], &nodes_[e * node_bytes_], entry.rows);
    }
  }
  return stored;
}

SurfaceCutSet::SurfaceCutSet(const VoxelTooth& tooth, double rho, SignedDistanceFn sd,
                             bool material_pyramid)
    : tooth_(tooth),
      rho_(rho),
      sd_(sd),
      surface_(tooth),
      pyramid_(material_pyramid),
      blocks_(material_pyramid ? MaterialBlocks(tooth.grid()) : MaterialBlocks()) {
  const VoxelGrid& grid = tooth.grid();
  const double h = grid.voxel_size;
  const double reach = std::max(cut_band(rho).reach, proxy_material_reach(rho));  // R'
  eps_ = std::ldexp(reach, -23);
  const double extent = grid.origin.cwiseAbs().maxCoeff() + grid.n * h + reach;
  certify_ = h >= eps_ && eps_ >= std::ldexp(extent, -44);
  // The ball's box spans at most 2 R / h + 4 voxels per axis (a voxel of margin each side, and
  // the floors' rounding; collect), hence at most (that + 6) / 8 + 1 bricks; the tables cover
  // those bricks' voxels.
  const double across = std::min<double>(grid.n, std::floor(2.0 * cut_band(rho).reach / h) + 6.0);
  const std::size_t voxels = static_cast<std::size_t>(std::max(1.0, across));
  const std::size_t bricks = std::min<std::size_t>(
      static_cast<std::size_t>(surface_.slots_per_axis()), (voxels + kB - 2) / kB + 1);
  bricks_across_ = static_cast<int>(bricks);
  for (int a = 0; a < 3; ++a) {
    terms_[a].resize(bricks * kB);
    centre_[a].resize(bricks * kB);
    least2_[a].resize(bricks * kB / 2);
    least4_[a].resize(bricks * kB / 4);
    least8_[a].resize(bricks);
  }
  order_.reserve(bricks * bricks * bricks);
  keys_.reserve(bricks * bricks * bricks);
}

void SurfaceCutSet::order_bricks(const int b_lo[3], const int b_hi[3]) {
  if (std::equal(b_lo, b_lo + 3, box_lo_) && std::equal(b_hi, b_hi + 3, box_hi_)) return;
  keys_.clear();
  for (int bz = b_lo[2]; bz <= b_hi[2]; ++bz) {
    for (int by = b_lo[1]; by <= b_hi[1]; ++by) {
      for (int bx = b_lo[0]; bx <= b_hi[0]; ++bx) {
        // (Morton code, place in the box): the code in the high bits (at most 30), the place
        // x | y << 8 | z << 16 in the low 32.
        const std::uint64_t morton = spread3(static_cast<std::uint64_t>(bx)) |
                                     (spread3(static_cast<std::uint64_t>(by)) << 1) |
                                     (spread3(static_cast<std::uint64_t>(bz)) << 2);
        const std::uint64_t place = static_cast<std::uint64_t>(bx - b_lo[0]) |
                                    (static_cast<std::uint64_t>(by - b_lo[1]) << 8) |
                                    (static_cast<std::uint64_t>(bz - b_lo[2]) << 16);
        keys_.push_back((morton << 32) | place);
      }
    }
  }
  std::sort(keys_.begin(), keys_.end(), [](std::uint64_t a, std::uint64_t b) { return a > b; });
  order_.clear();
  for (const std::uint64_t key : keys_) {
    const int x = static_cast<int>(key & 0xff), y = static_cast<int>((key >> 8) & 0xff);
    const int z = static_cast<int>((key >> 16) & 0xff);
    const std::size_t s = surface_.slot(b_lo[0] + x, b_lo[1] + y, b_lo[2] + z);
    order_.push_back({static_cast<std::uint32_t>(s), static_cast<std::uint8_t>(x),
                      static_cast<std::uint8_t>(y), static_cast<std::uint8_t>(z)});
  }
  std::copy(b_lo, b_lo + 3, box_lo_);
  std::copy(b_hi, b_hi + 3, box_hi_);
}

bool SurfaceCutSet::near_grid_plane(const Vec3& g) const {
  const VoxelGrid& grid = tooth_.grid();
  for (int a = 0; a < 3; ++a) {
    const double u = std::floor((g[a] - grid.origin[a]) / grid.voxel_size);
    for (int d = -1; d <= 2; ++d) {
      const double p = grid.origin[a] + grid.voxel_size * (u + d);  // origin + h i, i = u + d
      if (std::abs(g[a] - p) < eps_) return true;
    }
  }
  return false;
}

int SurfaceCutSet::box_about(const Vec3& g, double r, int lo[3], int hi[3], int b_lo[3],
                             int b_hi[3]) const {
  // The ball's box of voxels, one voxel wider each side than its bounds (their rounding), clipped
  // to the grid, and the box's bricks [b_lo, b_hi].
  const VoxelGrid& grid = tooth_.grid();
  const int n = grid.n;
  const double h = grid.voxel_size;
  bool empty = false;
  for (int a = 0; a < 3; ++a) {
    const double u0 = std::floor((g[a] - r - grid.origin[a]) / h) - 1.0;
    const double u1 = std::floor((g[a] + r - grid.origin[a]) / h) + 1.0;
    empty = empty || u1 < 0.0 || u0 > n - 1.0;
    lo[a] = empty ? 0 : static_cast<int>(std::max(u0, 0.0));
    hi[a] = empty ? 0 : static_cast<int>(std::min(u1, n - 1.0));
    b_lo[a] = lo[a] / kB;
    b_hi[a] = hi[a] / kB;
    // Within the constructor's bound (a guard: the reference answers otherwise).
    if (b_hi[a] - b_lo[a] + 1 > bricks_across_) return -1;
  }
  return empty ? 1 : 0;
}

void SurfaceCutSet::fill_tables(const Vec3& g, const int lo[3], const int hi[3],
                                const int b_lo[3], const int b_hi[3]) {
  // Per axis over the bricks' voxels i = 8 b_lo + r: the squared gap t (sphere_intersects_cells's
  // term, +inf outside [lo, hi]: such a voxel is never a candidate), the squared centre offset c
  // (cut_band_depth's term), and the least t of each aligned run of 2, 4 and 8. A run's
  // least, summed as a voxel's terms are, bounds every voxel of the block below (the sums round
  // monotonically): a block whose bound is not < R^2 holds no voxel of the ball.
  constexpr double kFar = std::numeric_limits<double>::infinity();
  const VoxelGrid& grid = tooth_.grid();
  for (int a = 0; a < 3; ++a) {
    const int origin_voxel = kB * b_lo[a];
    double* t = terms_[a].data();
    double* c = centre_[a].data();
    const int count = kB * (b_hi[a] - b_lo[a] + 1);
    for (int r = 0; r < count; ++r) {
      const int i = origin_voxel + r;
      if (i < lo[a] || i > hi[a]) {
        t[r] = kFar;
        continue;
      }
      // sphere_intersects_cells's term: box_distance2's squared gap (the same double).
      t[r] = voxel_walk::gap2(g[a], voxel_walk::plane(grid, a, i),
                              voxel_walk::plane(grid, a, i + 1));
      const double e = (grid.origin[a] + grid.voxel_size * (i + 0.5)) - g[a];  // centre - g
      c[r] = e * e;
    }
    double* l2 = least2_[a].data();
    double* l4 = least4_[a].data();
    double* l8 = least8_[a].data();
    for (int r = 0; r < count / 2; ++r) l2[r] = std::min(t[2 * r], t[2 * r + 1]);
    for (int r = 0; r < count / 4; ++r) l4[r] = std::min(l2[2 * r], l2[2 * r + 1]);
    for (int r = 0; r < count / 8; ++r) l8[r] = std::min(l4[2 * r], l4[2 * r + 1]);
  }
}

bool SurfaceCutSet::answer(const Vec3& g, bool found, std::size_t best, Nearest* nearest) {
  if (found && certify_ && !near_grid_plane(g)) {
    nearest->found = true;
    nearest->voxel = best;
    seed_ = best;
    seeded_ = true;
    return true;
  }
  ++fallbacks_;
  const SignedDistance sd = sd_(tooth_, g, proxy_material_reach(rho_));
  nearest->found = sd.found;
  nearest->voxel = sd.voxel;
  seeded_ = sd.found;  // a seed only if exposed (material_alone checks)
  seed_ = sd.voxel;
  return true;
}

bool SurfaceCutSet::material_alone(const Vec3& g, Nearest* nearest) {
  // The minimum of (D, v) over the exposed voxels with D < min(R^2, (2 rho)^2), as collect's pass
  // finds it, but by the nearest-first walk (fast/tooth/nearest_voxel_walk.h) seeded by the last
  // answer's voxel if it is still exposed and within reach (the contact moves little from tick to
  // tick): the walk reads only the bricks, words and 2^3 blocks whose bound can hold a voxel with
  // D < best, or D = best and a smaller index; the others cannot hold the minimiser (header
  // comment). The visiting order does not matter: the minimum of a total order is unique.
  const VoxelGrid& grid = tooth_.grid();
  const double R = cut_band(rho_).reach;
  const double m = proxy_material_reach(rho_);
  VoxelWalk<NoVoxelWatch> best;             // found and voxel in best.sd, as the walk reads them
  best.d2 = std::min(R * R, m * m);  // collect's ball test and outside_distance's reach
  const std::size_t nn = static_cast<std::size_t>(grid.n);
  if (seeded_ && seed_ < grid.voxels.size()) {
    const int i = static_cast<int>(seed_ % nn), j = static_cast<int>((seed_ / nn) % nn);
    const int k = static_cast<int>(seed_ / (nn * nn));
    if (surface_.exposed(i, j, k)) {
      const double d2 = voxel_walk::voxel_distance2(grid, i, j, k, g);
      if (d2 < best.d2) {
        best.d2 = d2;
        best.sd.voxel = seed_;
        best.sd.found = true;
        ++seeded_queries_;
      }
    }
  }
  // The walk's span: the ball of radius sqrt(best) (every voxel with D <= best lies within it).
  const double r = best.sd.found ? std::sqrt(best.d2) : std::min(R, m);
  if (!walk_nearest_voxel(surface_, grid, g, r, &best)) return false;
  return answer(g, best.sd.found, best.sd.voxel, nearest);
}

bool SurfaceCutSet::certified_material(const Vec3& g, std::uint8_t* material) {
  const VoxelGrid& grid = tooth_.grid();
  if (!pyramid_ || !seeded_ || seed_ >= grid.voxels.size()) return false;
  const std::size_t nn = static_cast<std::size_t>(grid.n);
  int u[3] = {static_cast<int>(seed_ % nn), static_cast<int>((seed_ / nn) % nn),
              static_cast<int>(seed_ / (nn * nn))};
  if (grid.voxels[seed_] == kEmpty) {
    // Drilling took the seed (the voxel nearest to the bur goes first): the first solid voxel
    // behind it, along the axis on which its centre lies farthest from g, within a few voxels.
    const Vec3 off = grid.center(u[0], u[1], u[2]) - g;
    int a = 0;
    for (int b = 1; b < 3; ++b) {
      if (std::abs(off[b]) > std::abs(off[a])) a = b;
    }
    const int step = off[a] < 0.0 ? -1 : 1;
    constexpr int kBehind = 4;
    bool solid = false;
    for (int t = 0; t < kBehind && !solid; ++t) {
      u[a] += step;
      if (u[a] < 0 || u[a] >= grid.n) return false;
      solid = grid.voxels[grid.index(u[0], u[1], u[2])] != kEmpty;
    }
    if (!solid) return false;
  }
  // The seed follows g: up to kSteps moves to the solid face neighbour with the least D below its
  // own (a smaller D(s), a smaller ball for the pyramid; any solid voxel would do).
  double d2 = voxel_walk::voxel_distance2(grid, u[0], u[1], u[2], g);
  constexpr int kSteps = 2;
  for (int step = 0; step < kSteps; ++step) {
    int to = -1;
    double to2 = d2;
    for (int f = 0; f < 6; ++f) {
      int w[3] = {u[0], u[1], u[2]};
      w[face_axis(f)] += face_sign(f);
      if (!grid.inside(w[0], w[1], w[2]) || grid.voxels[grid.index(w[0], w[1], w[2])] == kEmpty) {
        continue;
      }
      const double e2 = voxel_walk::voxel_distance2(grid, w[0], w[1], w[2], g);
      if (e2 < to2) {
        to2 = e2;
        to = f;
      }
    }
    if (to < 0) break;
    u[face_axis(to)] += face_sign(to);
    d2 = to2;
  }
  // s = u: solid, within the reference's reach, and the pyramid holds nothing else within D(s).
  // Where it refuses naming a witness w (solid, of another material, D(w) < D(s): g near a
  // junction of materials), w is such an s too, with a smaller ball: asked again, up to kRounds
  // times (each round's D smaller, so no cycle).
  const double m = proxy_material_reach(rho_);
  if (!(d2 < m * m)) return false;
  std::size_t s = grid.index(u[0], u[1], u[2]);
  // The held certificate (servo51): a pyramid pass for a wider ball, kept for the next queries.
  // Claim: if only(grid, x0, W^2, m) passed (W = held_r_ + margin, margin = 1e-9 h), s is solid
  // now of material m, and sqrt(d2) + |g - x0| + margin <= held_r_ (computed), then every voxel
  // v solid now with D_g(v) <= d2 is of material m, so the reference's v* (D_g(v*) <= d2) is.
  // Proof: v's box is within sqrt(D_g(v)) (1 + 3u) of g (D: correctly rounded terms summed,
  // relative error < 3u, u = 2^-53), hence within sqrt(d2) + |g - x0| (1 + 3u) + 4u sqrt(d2)
  // <= held_r_ - margin / 2 of x0 (the margin, some 10^6 times the rounding of lengths below a
  // metre, covers the computed sum's and norm's rounding), so D_x0(v) <= (W - 1.5 margin)^2
  // (1 + 3u) < fl(W^2): v was solid then (removals only) and within the passed ball, so it is of
  // material m. The proxy moves a few micrometres a tick while the ball's radius (about rho)
  // barely changes, so a ball wider by kWiden rho stays held for many ticks.
  const std::uint8_t ms = grid.voxels[s];
  const double margin = 1e-9 * grid.voxel_size;
  const double r = std::sqrt(d2);
  if (held_ && ms == held_m_ && r + (g - held_x_).norm() + margin <= held_r_) {
    ++held_hits_;
    *material = ms;
    seed_ = s;
    return true;
  }
  constexpr double kWiden = 0.125;
  const double wide = r + kWiden * rho_;
  if (blocks_.only(grid, g, wide * wide, ms)) {
    held_ = true;
    held_x_ = g;
    held_r_ = wide - margin;
    held_m_ = ms;
    *material = ms;
    seed_ = s;
    return true;
  }
  constexpr int kRounds = 4;
  for (int round = 0; round < kRounds; ++round) {
    MaterialBlocks::Witness w;
    if (blocks_.only(grid, g, d2, grid.voxels[s], &w)) {
      *material = grid.voxels[s];
      seed_ = s;
      return true;
    }
    if (!w.found) return false;
    ++reseeded_;
    s = w.voxel;
    d2 = w.d2;
  }
  return false;
}

bool SurfaceCutSet::material(const Vec3& g, std::uint8_t* material) {
  if (!surface_.current() || !g.allFinite()) return false;
  const VoxelGrid& grid = tooth_.grid();
  // The inside case of signed_distance: g in a solid voxel's cell, that voxel.
  int cell[3];
  if (sdf_detail::voxel_of(grid, g, cell) &&
      grid.voxels[grid.index(cell[0], cell[1], cell[2])] != kEmpty) {
    ++queries_;
    *material = grid.voxels[grid.index(cell[0], cell[1], cell[2])];
    return true;
  }
  if (certified_material(g, material)) {
    ++queries_;
    ++certified_;
    return true;
  }
  Nearest nearest;
  if (!collect(g, Contact{}, nullptr, nullptr, &nearest)) return false;
  *material = nearest.found ? grid.voxels[nearest.voxel] : std::uint8_t{kEmpty};
  return true;
}

bool SurfaceCutSet::collect(const Vec3& g, const Contact& contact, std::vector<Contact>* shares,
                            std::vector<std::size_t>* voxels, Nearest* nearest) {
  if (!surface_.current() || !g.allFinite()) return false;
  ++queries_;
  const VoxelGrid& grid = tooth_.grid();
  const int n = grid.n;
  const double h = grid.voxel_size;
  // The inside case of signed_distance: g in a solid voxel's cell.
  int cell[3];
  const bool inside = sdf_detail::voxel_of(grid, g, cell) &&
                      grid.voxels[grid.index(cell[0], cell[1], cell[2])] != kEmpty;
  if (inside && shares == nullptr) {
    nearest->found = true;
    nearest->voxel = grid.index(cell[0], cell[1], cell[2]);
    return true;
  }
  if (shares == nullptr) return material_alone(g, nearest);
  const CutBand cut = cut_band(rho_);
  const double R2 = cut.reach * cut.reach;  // sphere_intersects_cells's rho * rho
  const double m = proxy_material_reach(rho_);
  bool found = false;
  double best2 = m * m;  // outside_distance's reach * reach
  std::size_t best = 0;
  int lo[3], hi[3], b_lo[3], b_hi[3];
  const int box = box_about(g, cut.reach, lo, hi, b_lo, b_hi);
  if (box < 0) return false;
  if (inside) {
    nearest->found = true;
    nearest->voxel = grid.index(cell[0], cell[1], cell[2]);
  }
  if (box == 0) {
    fill_tables(g, lo, hi, b_lo, b_hi);
    order_bricks(b_lo, b_hi);
    const double *tx = terms_[0].data(), *ty = terms_[1].data(), *tz = terms_[2].data();
    const double *cx = centre_[0].data(), *cy = centre_[1].data(), *cz = centre_[2].data();
    const double *x2 = least2_[0].data(), *y2 = least2_[1].data(), *z2 = least2_[2].data();
    const double *x4 = least4_[0].data(), *y4 = least4_[1].data(), *z4 = least4_[2].data();
    const double *x8 = least8_[0].data(), *y8 = least8_[1].data(), *z8 = least8_[2].data();
    const int origin_voxel[3] = {kB * b_lo[0], kB * b_lo[1], kB * b_lo[2]};
    bool cutting = true;
    const std::size_t nn = static_cast<std::size_t>(n);
    for (const BoxBrick& b : order_) {
      if (!((x8[b.x] + y8[b.y]) + z8[b.z] < R2)) continue;  // the brick misses the ball
      const std::uint64_t* bits = surface_.brick(b.slot);
      if (bits == nullptr) continue;
      // Word w is the brick's 4^3 block (w & 1, w >> 1 & 1, w >> 2); byte q of it the 2^3 block
      // (q & 1, q >> 1 & 1, q >> 2) within; bit c of the byte the voxel (c & 1, c >> 1 & 1,
      // c >> 2) within (SurfaceVoxels). Indices below are runs of the tables.
      for (int w = SurfaceVoxels::kWords - 1; w >= 0; --w) {
        const int wx = 2 * b.x + (w & 1), wy = 2 * b.y + ((w >> 1) & 1), wz = 2 * b.z + (w >> 2);
        std::uint64_t word = bits[w];
        if (word == 0 || !((x4[wx] + y4[wy]) + z4[wz] < R2)) continue;
        while (word != 0) {
          // The highest 2^3 block (byte) left, its voxels in child order.
          const int q = (63 - std::countl_zero(word)) >> 3;
          std::uint64_t block = (word >> (8 * q)) & 0xff;
          word &= ~(std::uint64_t{0xff} << (8 * q));
          const int qx = 2 * wx + (q & 1), qy = 2 * wy + ((q >> 1) & 1), qz = 2 * wz + (q >> 2);
          if (!((x2[qx] + y2[qy]) + z2[qz] < R2)) continue;
          while (block != 0) {
            const int c = std::countr_zero(block);
            block &= block - 1;
            const int rx = 2 * qx + (c & 1), ry = 2 * qy + ((c >> 1) & 1), rz = 2 * qz + (c >> 2);
            const double d2 = (tx[rx] + ty[ry]) + tz[rz];
            if (!(d2 < R2)) continue;  // not in the ball: the reference never lists it
            const std::size_t v =
                static_cast<std::size_t>(origin_voxel[0] + rx) +
                nn * (static_cast<std::size_t>(origin_voxel[1] + ry) +
                      nn * static_cast<std::size_t>(origin_voxel[2] + rz));
            if (d2 < best2 || (found && d2 == best2 && v < best)) {  // sdf_nearer
              best2 = d2;
              best = v;
              found = true;
            }
            if (!cutting) continue;
            if (shares->size() >= shares->capacity() || voxels->size() >= voxels->capacity()) {
              cutting = false;  // collect_cut_set stops here
              continue;
            }
            // cut_band_depth: |centre - g|^2 summed as Eigen's squaredNorm sums it.
            const double depth = cut_band_depth_at((cx[rx] + cy[ry]) + cz[rz], rho_, h, cut.depth);
            if (!(depth > 0.0)) continue;
            shares->push_back(contact);
            shares->back().material = grid.voxels[v];
            shares->back().weight = depth;
            voxels->push_back(v);
          }
        }
      }
    }
  }
  if (inside) return true;
  return answer(g, found, best, nearest);
}

CutSetProvider::CutSetProvider(VoxelTooth& tooth, ToolTip tip, double k_tooth, double b_tooth,
                               const DrillParams* drill, ContactModel model, SignedDistanceFn sd,
                               SampledField* field)
    : dentsim::ToothContactProvider(tooth, tip, k_tooth, b_tooth, drill, model, sd, field),
      cut_(tooth, tip.radius, sd) {}

int CutSetProvider::drill(std::span<const Contact> contacts, double T) {
  const int removed = dentsim::ToothContactProvider::drill(contacts, T);
  // drills_late(): the voxels were removed by the tick's publish (surface_removed then).
  if (removed > 0 && !drills_late()) cut_.update(last_removed());
  return removed;
}

void CutSetProvider::surface_contact_voxels(const Vec3& g, Contact* contact,
                                            std::vector<Contact>* shares,
                                            std::vector<std::size_t>* voxels) {
  if (shares == nullptr) {  // the material alone: without its voxel where the pyramid certifies it
    std::uint8_t material = kEmpty;
    if (!cut_.material(g, &material)) {
      dentsim::ToothContactProvider::surface_contact_voxels(g, contact, shares, voxels);
      return;
    }
    set_contact_material(material, k_tooth_, b_tooth_, contact);
    return;
  }
  const std::size_t first = shares->size();
  SurfaceCutSet::Nearest nearest;
  if (!cut_.collect(g, *contact, shares, voxels, &nearest)) {
    dentsim::ToothContactProvider::surface_contact_voxels(g, contact, shares, voxels);
    return;
  }
  const std::uint8_t material =
      nearest.found ? voxel_tooth().grid().voxels[nearest.voxel] : std::uint8_t{kEmpty};
  set_contact_material(material, k_tooth_, b_tooth_, contact);
  // The members were copied from the contact before its material was known: its stiffness and
  // damping (the same doubles collect_cut_set copies).
  for (std::size_t i = first; i < shares->size(); ++i) {
    (*shares)[i].stiffness = contact->stiffness;
    (*shares)[i].damping = contact->damping;
  }
}

}  // namespace dentsim::fast
