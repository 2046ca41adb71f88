// The fast twin of the "field" contact model (fast/tooth/field.h).
#include "fast/tooth/field.h"

#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <cstring>

#include "fast/tooth/sdf.h"
#include "reference/core/io.h"
#include "reference/tooth/field_edit_core.h"
#include "reference/tooth/surface_proxy_core.h"

namespace dentsim::fast {

namespace {

constexpr int kE = FieldBricks::kEdge;
// Offsets of a cell's corners c[dx + 2 dy + 4 dz] in a 9^3 brick.
constexpr int kCorner[8] = {0, 1, kE, kE + 1, kE * kE, kE * kE + 1, kE * kE + kE, kE * kE + kE + 1};

}  // namespace

FieldBricks::FieldBricks(const SampledField& field, std::size_t spare)
    : field_(field),
      m_(field.samples_per_axis()),
      nb_(field.samples_per_axis() / kFieldBrick),
      out_(static_cast<float>(field.outside_clamp())),
      in_(static_cast<float>(-field.inside_clamp())),
      h_(field.spacing()),
      lipschitz_(field.lipschitz()) {
  const std::size_t slots = static_cast<std::size_t>(nb_) * nb_ * nb_;
  index_.assign(slots, kAllOutside);
  std::vector<float> values(kSamples);
  std::vector<float> kept;
  for (int bz = 0; bz < nb_; ++bz) {
    for (int by = 0; by < nb_; ++by) {
      for (int bx = 0; bx < nb_; ++bx) {
        bool all_out = true, all_in = true;
        for (int l = 0; l < kSamples; ++l) {
          // Samples beyond the lattice (the apron of the last bricks) are never a corner of a
          // cell; they repeat the last sample.
          const int sx = std::min(bx * kFieldBrick + l % kE, m_ - 1);
          const int sy = std::min(by * kFieldBrick + (l / kE) % kE, m_ - 1);
          const int sz = std::min(bz * kFieldBrick + l / (kE * kE), m_ - 1);
          values[l] = field.at(sx, sy, sz);
          all_out = all_out && values[l] == out_;
          all_in = all_in && values[l] == in_;
        }
        std::int32_t& id = index_[slot(bx, by, bz)];
        if (all_out || all_in) {
          id = all_out ? kAllOutside : kAllInside;
          continue;
        }
        id = static_cast<std::int32_t>(kept.size() / kSamples);
        kept.insert(kept.end(), values.begin(), values.end());
      }
    }
  }
  bricks_.reserve(kept.size() + spare * kSamples);
  bricks_.assign(kept.begin(), kept.end());
}

void FieldBricks::corners(const int s[3], float c[8]) const {
  const int bx = s[0] / kFieldBrick, by = s[1] / kFieldBrick, bz = s[2] / kFieldBrick;
  const std::size_t sl = slot(bx, by, bz);
  const float* brick = nullptr;
  if (sl == last_slot_) {
    brick = last_brick_;
  } else {
    const std::int32_t id = index_[sl];
    if (id >= 0) {
      brick = bricks_.data() + static_cast<std::size_t>(id) * kSamples;
      last_slot_ = sl;
      last_brick_ = brick;
    } else if (id == kViaField) {
      for (int d = 0; d < 8; ++d) {
        c[d] = field_.at(s[0] + (d & 1), s[1] + ((d >> 1) & 1), s[2] + (d >> 2));
      }
      return;
    } else {
      const float v = id == kAllOutside ? out_ : in_;
      for (int d = 0; d < 8; ++d) c[d] = v;
      return;
    }
  }
  const float* p = brick + (s[0] - bx * kFieldBrick) +
                   kE * ((s[1] - by * kFieldBrick) + kE * (s[2] - bz * kFieldBrick));
  for (int d = 0; d < 8; ++d) c[d] = p[kCorner[d]];
}

float FieldBricks::value_on(const std::int32_t* table, int sx, int sy, int sz) const {
  const int bx = sx / kFieldBrick, by = sy / kFieldBrick, bz = sz / kFieldBrick;
  const std::int32_t id = table[slot(bx, by, bz)];
  if (id >= 0) {
    return bricks_[static_cast<std::size_t>(id) * kSamples +
                   static_cast<std::size_t>((sx - bx * kFieldBrick) +
                                            kE * ((sy - by * kFieldBrick) +
                                                  kE * (sz - bz * kFieldBrick)))];
  }
  if (id == kViaField) return field_.at(sx, sy, sz);
  return id == kAllOutside ? out_ : in_;
}

float FieldBricks::at(int sx, int sy, int sz) const { return value_on(index_.data(), sx, sy, sz); }

void FieldBricks::mirror(int sx, int sy, int sz) {
  const float v = field_.at(sx, sy, sz);
  std::size_t sl[8];
  int local[8];
  const int count = holders(sx, sy, sz, sl, local);
  bool changed = false;
  for (int k = 0; k < count; ++k) {
    std::int32_t id = index_[sl[k]];
    if (id == kViaField) {
      changed = true;
      continue;
    }
    if (id < 0) {
      const float fill = id == kAllOutside ? out_ : in_;
      if (v == fill) continue;
      changed = true;
      if (bricks_.size() + kSamples > bricks_.capacity()) {  // no spare brick: read through
        index_[sl[k]] = kViaField;
        continue;
      }
      id = static_cast<std::int32_t>(bricks_.size() / kSamples);
      bricks_.insert(bricks_.end(), static_cast<std::size_t>(kSamples), fill);  // in capacity
      index_[sl[k]] = id;
    }
    float& stored =
        bricks_[static_cast<std::size_t>(id) * kSamples + static_cast<std::size_t>(local[k])];
    if (stored != v) changed = true;
    stored = v;
  }
  // A new brick or a read-through slot: the kept brick pointer may name a slot that changed.
  last_slot_ = std::numeric_limits<std::size_t>::max();
  if (changed) ++generation_;
}

double FieldBricks::worst_cells(const std::int32_t* table, const int lo[3],
                                const int hi[3]) const {
  int a[3], b[3];
  for (int k = 0; k < 3; ++k) {
    a[k] = std::max(0, lo[k] - 1);
    b[k] = std::min(m_ - 2, hi[k]);
  }
  // SampledField::cell_lipschitz's arithmetic per cell up to the square root (header comment).
  double worst = -1.0;  // no cell
  const auto measure = [&worst](const float* cf) {
    double c[8];
    for (int d = 0; d < 8; ++d) c[d] = cf[d];
    double mx = 0.0, my = 0.0, mz = 0.0;
    for (int e = 0; e < 4; ++e) {
      const int ix = 2 * e;
      const int iy = (e & 1) + 4 * (e >> 1);
      const int iz = e;
      mx = std::max(mx, std::abs(c[ix + 1] - c[ix]));
      my = std::max(my, std::abs(c[iy + 2] - c[iy]));
      mz = std::max(mz, std::abs(c[iz + 4] - c[iz]));
    }
    worst = std::max(worst, mx * mx + my * my + mz * mz);
  };
  float cf[8];
  for (int z = a[2]; z <= b[2]; ++z) {
    for (int y = a[1]; y <= b[1]; ++y) {
      // The row's cells in runs of one 9^3 brick (all 8 corners of a cell are in its lower
      // corner's brick): the table is read once a run, the corners at fixed offsets (edit51).
      for (int x = a[0]; x <= b[0];) {
        const int bx = x / kFieldBrick, by = y / kFieldBrick, bz = z / kFieldBrick;
        const int last = std::min(b[0], bx * kFieldBrick + kFieldBrick - 1);
        const std::int32_t id = table[slot(bx, by, bz)];
        if (id >= 0) {
          const float* p = bricks_.data() + static_cast<std::size_t>(id) * kSamples +
                           (x - bx * kFieldBrick) +
                           kE * ((y - by * kFieldBrick) + kE * (z - bz * kFieldBrick));
          for (; x <= last; ++x, ++p) {
            for (int d = 0; d < 8; ++d) cf[d] = p[kCorner[d]];
            measure(cf);
          }
        } else {
          for (; x <= last; ++x) {
            const int s[3] = {x, y, z};
            corners_on(table, s, cf);
            measure(cf);
          }
        }
      }
    }
  }
  return worst;
}

void FieldBricks::include_cells(const int lo[3], const int hi[3]) {
  const double worst = worst_cells(index_.data(), lo, hi);
  if (worst >= 0.0) lipschitz_ = std::max(lipschitz_, std::sqrt(worst) / h_);
}

void FieldBricks::corners_on(const std::int32_t* table, const int s[3], float c[8]) const {
  const int bx = s[0] / kFieldBrick, by = s[1] / kFieldBrick, bz = s[2] / kFieldBrick;
  const std::int32_t id = table[slot(bx, by, bz)];
  if (id >= 0) {
    const float* p = bricks_.data() + static_cast<std::size_t>(id) * kSamples +
                     (s[0] - bx * kFieldBrick) +
                     kE * ((s[1] - by * kFieldBrick) + kE * (s[2] - bz * kFieldBrick));
    for (int d = 0; d < 8; ++d) c[d] = p[kCorner[d]];
  } else if (id == kViaField) {
    for (int d = 0; d < 8; ++d) {
      c[d] = field_.at(s[0] + (d & 1), s[1] + ((d >> 1) & 1), s[2] + (d >> 2));
    }
  } else {
    const float v = id == kAllOutside ? out_ : in_;
    for (int d = 0; d < 8; ++d) c[d] = v;
  }
}

int FieldBricks::holders(int sx, int sy, int sz, std::size_t sl[8], int local[8]) const {
  // Its own brick along each axis, and the one below when s is on that one's apron.
  int b[3][2] = {}, l[3][2] = {}, count[3] = {};
  const int s[3] = {sx, sy, sz};
  for (int a = 0; a < 3; ++a) {
    b[a][0] = s[a] / kFieldBrick;
    l[a][0] = s[a] - b[a][0] * kFieldBrick;
    count[a] = 1;
    if (l[a][0] == 0 && b[a][0] > 0) {
      b[a][1] = b[a][0] - 1;
      l[a][1] = kFieldBrick;
      count[a] = 2;
    }
  }
  int k = 0;
  for (int iz = 0; iz < count[2]; ++iz) {
    for (int iy = 0; iy < count[1]; ++iy) {
      for (int ix = 0; ix < count[0]; ++ix) {
        sl[k] = slot(b[0][ix], b[1][iy], b[2][iz]);
        local[k] = l[0][ix] + kE * (l[1][iy] + kE * l[2][iz]);
        ++k;
      }
    }
  }
  return k;
}

void FieldBricks::enable_copy_on_write(std::size_t pool) {
  const std::size_t used = bricks_.size() / kSamples;
  const std::size_t total = used + spare_bricks() + pool;
  bricks_.reserve(total * kSamples);
  bricks_.resize(total * kSamples, 0.0f);
  free_.clear();
  free_.reserve(total);
  for (std::size_t id = total; id-- > used;) free_.push_back(static_cast<std::int32_t>(id));
  fresh_.assign(total, 0);
  swaps_.clear();
  swaps_.reserve(total);
  worker_index_ = index_;
  worker_lipschitz_ = lipschitz_;
  cow_ = true;
}

float FieldBricks::worker_at(int sx, int sy, int sz) const {
  return value_on(worker_index_.data(), sx, sy, sz);  // no read-through slot in the worker's
}

bool FieldBricks::worker_prepare(int sx, int sy, int sz) {
  std::size_t sl[8];
  int local[8];
  const int count = holders(sx, sy, sz, sl, local);
  int missing = 0;
  for (int k = 0; k < count; ++k) {
    const std::int32_t id = worker_index_[sl[k]];
    if (id < 0 || fresh_[static_cast<std::size_t>(id)] == 0) ++missing;
  }
  if (static_cast<std::size_t>(missing) > free_.size()) return false;  // the pool is empty
  for (int k = 0; k < count; ++k) {
    const std::int32_t old = worker_index_[sl[k]];
    if (old >= 0 && fresh_[static_cast<std::size_t>(old)] != 0) continue;  // this batch's copy
    const std::int32_t id = free_.back();
    free_.pop_back();
    float* copy = bricks_.data() + static_cast<std::size_t>(id) * kSamples;
    if (old >= 0) {  // the published brick, read only
      std::copy_n(bricks_.data() + static_cast<std::size_t>(old) * kSamples, kSamples, copy);
    } else {
      std::fill_n(copy, kSamples, old == kAllOutside ? out_ : in_);
    }
    fresh_[static_cast<std::size_t>(id)] = 1;
    worker_index_[sl[k]] = id;
    swaps_.push_back(Swap{sl[k], id, old});  // within capacity: one per brick of the pool
  }
  return true;
}

void FieldBricks::worker_mirror(int sx, int sy, int sz) {
  const float v = field_.at(sx, sy, sz);
  std::size_t sl[8];
  int local[8];
  const int count = holders(sx, sy, sz, sl, local);
  for (int k = 0; k < count; ++k) {
    const std::int32_t id = worker_index_[sl[k]];  // this batch's copy (worker_prepare)
    bricks_[static_cast<std::size_t>(id) * kSamples + static_cast<std::size_t>(local[k])] = v;
  }
}

void FieldBricks::worker_include_cells(const int lo[3], const int hi[3]) {
  const double worst = worst_cells(worker_index_.data(), lo, hi);
  if (worst >= 0.0) worker_lipschitz_ = std::max(worker_lipschitz_, std::sqrt(worst) / h_);
}

void FieldBricks::worker_end_batch() {
  for (const Swap& w : swaps_) fresh_[static_cast<std::size_t>(w.brick)] = 0;
  swaps_.clear();
}

void FieldBricks::publish(std::span<const Swap> swaps, double lipschitz) {
  for (const Swap& w : swaps) index_[w.slot] = w.brick;
  lipschitz_ = lipschitz;
  // The kept brick pointer may name a retired brick; the kept queries are stale.
  last_slot_ = std::numeric_limits<std::size_t>::max();
  if (!swaps.empty()) ++generation_;
}

namespace {

// FieldBricks::sample's work, with internal linkage so that FieldSolid::query inlines it (the
// member itself is an exported symbol, which -fPIC keeps out of line; GCC 12 does not inline a
// function called twice of this size without the attribute).
// The cell a sample read (FieldSolid keeps it for sweep_advance).
struct SampledCell {
  float corners[8];
  double t[3];
  bool in_lattice;
};

[[gnu::always_inline]] inline FieldSample sample_bricks(const FieldBricks& bricks, const Vec3& x,
                                                       bool* deep, SampledCell* cell = nullptr) {
  FieldSample out;
  if (deep != nullptr) *deep = false;
  const SampledField& f = bricks.field();
  const int m = f.samples_per_axis();
  if (m < 2) return out;  // SampledField::sample's empty field (deep_inside false)
  const Vec3 origin = f.sample_position(0, 0, 0);
  const double h = f.spacing();
  int s[3];
  double t[3];
  bool in_lattice = true;
  for (int a = 0; a < 3; ++a) {  // the reference's locate()
    const double w = (x[a] - origin[a]) / h;
    in_lattice = in_lattice && w >= 0.0 && w <= static_cast<double>(m - 1);
    const double u = std::clamp(w, 0.0, static_cast<double>(m - 1));
    const int i = std::min(static_cast<int>(u), m - 2);
    s[a] = i;
    t[a] = u - i;
  }
  float cf[8];
  bricks.corners(s, cf);
  if (cell != nullptr) {
    std::copy_n(cf, 8, cell->corners);
    std::copy_n(t, 3, cell->t);
    cell->in_lattice = in_lattice;
  }
  if (deep != nullptr) {
    bool all_in = true;
    const float floor_value = static_cast<float>(-f.inside_clamp());
    for (int d = 0; d < 8; ++d) all_in = all_in && cf[d] == floor_value;
    *deep = all_in;
  }
  // SampledField::sample's arithmetic, c[dx][dy][dz] = cf[dx + 2 dy + 4 dz].
  const auto c = [&](int dx, int dy, int dz) {
    return static_cast<double>(cf[dx + 2 * dy + 4 * dz]);
  };
  const double tx = t[0], ty = t[1], tz = t[2];
  double ex[2][2], dx_edge[2][2];
  for (int dz = 0; dz < 2; ++dz) {
    for (int dy = 0; dy < 2; ++dy) {
      ex[dy][dz] = c(0, dy, dz) + tx * (c(1, dy, dz) - c(0, dy, dz));
      dx_edge[dy][dz] = c(1, dy, dz) - c(0, dy, dz);
    }
  }
  const double ey0 = ex[0][0] + ty * (ex[1][0] - ex[0][0]);
  const double ey1 = ex[0][1] + ty * (ex[1][1] - ex[0][1]);
  out.value = ey0 + tz * (ey1 - ey0);
  const double gx0 = dx_edge[0][0] + ty * (dx_edge[1][0] - dx_edge[0][0]);
  const double gx1 = dx_edge[0][1] + ty * (dx_edge[1][1] - dx_edge[0][1]);
  const double gx = gx0 + tz * (gx1 - gx0);
  const double gy = (ex[1][0] - ex[0][0]) + tz * ((ex[1][1] - ex[0][1]) - (ex[1][0] - ex[0][0]));
  const double gz = ey1 - ey0;
  out.gradient = Vec3(gx, gy, gz) / h;
  return out;
}

}  // namespace

// The twin takes the proxy core's field-only paths as dentsim::FieldSolid does.
static_assert(proxy_detail::kFieldPaths<FieldSolid> && proxy_detail::FieldPathSolid<FieldSolid>);

FieldSample FieldBricks::sample(const Vec3& x, bool* deep) const {
  return sample_bricks(*this, x, deep);
}

const FieldSolid::Query& FieldSolid::query(const Vec3& x) const {
  if (last_.generation == bricks_.generation() && last_.x.x() == x.x() && last_.x.y() == x.y() &&
      last_.x.z() == x.z()) {
    return last_;
  }
  ++evaluated_;
  last_.x = x;
  last_.generation = bricks_.generation();
  bool deep = false;
  SampledCell cell{};
  const FieldSample s = sample_bricks(bricks_, x, &deep, &cell);
  std::copy_n(cell.corners, 8, last_.corners);
  std::copy_n(cell.t, 3, last_.t);
  last_.in_lattice = cell.in_lattice;
  last_.deep = deep;
  last_.value = s.value;
  last_.gradient = s.gradient;
  return last_;
}

SignedDistance FieldSolid::distance(const Vec3& x, double reach) const {
  ++distances_;
  SignedDistance out;
  // The free-space certificate (header comment); its norm only where phi0 >= reach + margin
  // could make it hold (L |x - x0| >= 0, so the test is the same).
  const double margin = 1e-9 * bricks_.field().spacing();
  if (have_exact_ && reach > 0.0 && phi0_ >= reach + margin) {
    if (phi0_ - bricks_.lipschitz() * (x - x0_).norm() >= reach + margin) {
      ++certified_;
      out.phi = reach;
      out.found = false;
      return out;
    }
  }
  const Query& q = query(x);
  if (q.deep) return fast::signed_distance(tooth_, x, reach);
  have_exact_ = true;
  x0_ = x;
  phi0_ = q.value;
  if (q.value >= reach) {
    out.phi = reach;
    out.found = false;
    return out;
  }
  out.phi = q.value;
  out.found = true;
  const double g = q.gradient.norm();
  out.nearest = g > 0.0 ? Vec3(x - (q.value / g) * q.gradient) : x;
  return out;
}

double FieldSolid::slope(const Vec3& x) const {
  const Query& q = query(x);
  return q.deep ? 0.0 : q.gradient.norm();
}

double FieldSolid::sweep_advance(const Vec3& y, const SignedDistance&, const Vec3& dir,
                                 double clearance, double slack, double left) const {
  const Query& q = query(y);  // the kept query of distance(y): its cell's corners, no second gather
  if (!q.in_lattice) return 0.0;
  return field_cell_advance(q.corners, q.t, bricks_.field().spacing(), dir, clearance, slack, left,
                            bricks_.lipschitz());
}

Vec3 FieldSolid::normal(const Vec3& x, const SignedDistance& sd) const {
  const Query& q = query(x);
  const bool deep = q.deep;
  if (!deep) {
    const Vec3 grad = q.gradient;
    const double g = grad.norm();
    if (g > 0.0) return grad / g;
  }
  const VoxelGrid& grid = tooth_.grid();
  const SignedDistance exact =
      deep ? sd : fast::signed_distance(tooth_, x, grid.voxel_size * grid.n);
  return distance_gradient(tooth_, x, exact);
}

bool VoxelDistanceCache::lookup(const VoxelTooth& tooth, std::uint64_t key, double* phi) const {
  const Entry& e = entries_[key % kEntries];
  if (e.key != key + 1 || (e.found && tooth.grid().voxels[e.voxel] == kEmpty)) {
    ++misses_;
    return false;
  }
  ++hits_;
  *phi = e.phi;
  return true;
}

void VoxelDistanceCache::keep(const VoxelTooth& tooth, std::uint64_t key, const Vec3& x,
                              const SignedDistance& sd) {
  const VoxelGrid& grid = tooth.grid();
  int idx[3];
  if (sdf_detail::voxel_of(grid, x, idx) &&
      grid.voxels[grid.index(idx[0], idx[1], idx[2])] != kEmpty) {
    return;  // inside: not kept (the edit asks outside samples only; field.h)
  }
  Entry& e = entries_[key % kEntries];
  e.key = key + 1;
  e.phi = sd.phi;
  e.voxel = sd.voxel;
  e.found = sd.found;
}

namespace {

// The fast reads and writes for the shared edit (reference/tooth/field_edit_core.h): samples from
// the 9^3 bricks, voxel distances kept across edits (VoxelDistanceCache), raises on the reference
// field then mirrored into the bricks, the Lipschitz update on the bricks.
struct FastFieldAccess {
  SampledField* field;
  FieldBricks* bricks;
  const VoxelTooth& tooth;
  SignedDistanceFn sd;
  VoxelDistanceCache* cache;
  std::uint64_t m;
  bool worker;  // copy-on-write: the worker's table (FieldBricks::worker_*)
  float at(int sx, int sy, int sz) const {
    return worker ? bricks->worker_at(sx, sy, sz) : bricks->at(sx, sy, sz);
  }
  double distance(int sx, int sy, int sz, const Vec3& p, double reach) const {
    const std::uint64_t key =
        static_cast<std::uint64_t>(sx) +
        m * (static_cast<std::uint64_t>(sy) + m * static_cast<std::uint64_t>(sz));
    double d = 0.0;
    if (cache != nullptr && cache->lookup(tooth, key, &d)) return d;
    const SignedDistance q = sd(tooth, p, reach);
    if (cache != nullptr) cache->keep(tooth, key, p, q);
    return q.phi;
  }
  bool raise(int sx, int sy, int sz, double value) {
    if (worker) {  // the copies first: without a pool brick, the field is not raised either
      if (!bricks->worker_prepare(sx, sy, sz) || !field->raise(sx, sy, sz, value)) return false;
      bricks->worker_mirror(sx, sy, sz);
      return true;
    }
    if (!field->raise(sx, sy, sz, value)) return false;
    bricks->mirror(sx, sy, sz);
    return true;
  }
  void include_cells(const int lo[3], const int hi[3]) {
    if (worker) {
      bricks->worker_include_cells(lo, hi);
    } else {
      bricks->include_cells(lo, hi);
    }
  }
};

}  // namespace

bool edit_field_for_removed_voxels(SampledField* field, FieldBricks* bricks,
                                   const VoxelTooth& tooth, std::span<const std::size_t> removed,
                                   SignedDistanceFn sd, FieldEditStats* stats,
                                   VoxelDistanceCache* cache, FieldEditCursor* cursor,
                                   long budget) {
  FastFieldAccess access{field, bricks, tooth, sd, cache,
                         static_cast<std::uint64_t>(field->samples_per_axis()),
                         bricks->copy_on_write()};
  return field_edit_detail::edit_field(*field, tooth, removed, access, stats, cursor, budget);
}

namespace {

// The ring's batches beyond L: in real time a late batch holds its slot until it is published,
// and a full ring leaves the tick's voxels in the field (a shortfall, a fault). 8 filled in 2.2 s
// of `dentsim run drill --realtime` (field model, 1 kHz) on the 2 loaded cores (load 11, the
// worker niced against the SCHED_FIFO servo: 163 late publishes); 64 batches of room (4 MB).
constexpr int kWorkerSlack = 64;
// The copy-on-write pool, per batch in flight (L + 2: the batches of the last L ticks, the one
// being edited, and the one whose retired bricks wait for the next publish): 512 bricks (1.5 MB).
constexpr std::size_t kPoolPerBatch = 512;
// The 8^3 bricks of the tooth one batch's removal may change (ToothBricks: ~1.2 kB each at 512^3,
// written only as used).
constexpr std::size_t kReplayBricks = 256;

// A spin-wait hint to the core (x86 PAUSE; elsewhere nothing).
inline void spin_pause() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#endif
}

}  // namespace

FieldEditWorker::FieldEditWorker(SampledField* field, FieldBricks* bricks,
                                 const VoxelTooth& tooth, int latency, bool real_time,
                                 std::size_t batch_capacity, const ToolTip& tip,
                                 const DrillParams& params, const DrillState& state,
                                 std::chrono::nanoseconds spin)
    : spin_(spin),
      field_(field),
      bricks_(bricks),
      tooth_(tooth),
      cut_set_(tooth_, tip.radius, &fast::signed_distance, /*material_pyramid=*/false),
      tip_(tip),
      params_(params),
      drill_state_(state),
      latency_(latency),
      real_time_(real_time) {
  const std::size_t pool = kPoolPerBatch * static_cast<std::size_t>(latency + 2);
  bricks_->enable_copy_on_write(pool);
  candidates_.reserve(
      dentsim::ToothContactProvider::cut_candidates_capacity(tooth_.grid(), tip.radius));
  shares_.reserve(kContactCapacity);
  share_voxels_.reserve(kContactCapacity);
  brick_marks_.assign(tooth_.codes.slot_count(), 0);
  ring_.resize(static_cast<std::size_t>(latency + kWorkerSlack));
  const std::size_t total = bricks_->brick_count();
  for (Batch& b : ring_) {
    b.voxels.reserve(std::min(batch_capacity, kContactCapacity));
    b.cut.removed.reserve(kContactCapacity);
    b.cut.bricks.reserve(tooth_, kReplayBricks);
    b.swaps.reserve(total);
  }
  retired_.reserve(total);
  thread_ = std::thread([this] { run(); });
}

FieldEditWorker::~FieldEditWorker() {
  stop_.store(true, std::memory_order_release);
  signal_.fetch_add(1, std::memory_order_release);
  signal_.notify_one();
  thread_.join();
}

bool FieldEditWorker::submit(const FieldDrillCut& cut, std::size_t limit) {
  if (submitted_here_ - published_here_ >= static_cast<int>(ring_.size())) return false;
  Batch& b = ring_[static_cast<std::size_t>(submitted_here_) % ring_.size()];
  b.cut.cut = cut;
  b.limit = limit;
  ++submitted_here_;
  // Sequentially consistent with the worker's parking (run()): either the worker sees this
  // signal before it sleeps, or this sees it parked and wakes it. A worker that is editing or
  // spinning is not woken: the futex wake of a sleeping thread is the dearest step of a drilling
  // tick (~6 us of the servo's 10 at 128^3 on an idle 2-core VM, docs/benchmarks.md "lead50").
  submitted_.store(submitted_here_, std::memory_order_seq_cst);
  signal_.fetch_add(1, std::memory_order_seq_cst);
  if (parked_.load(std::memory_order_seq_cst)) {
    signal_.notify_one();
    ++wakes_;
  }
  return true;
}

void FieldEditWorker::publish(long tick, Sink& sink, FieldEditStats* stats, long* shortfalls,
                              long* late, StandIn* stand_in) {
  bool took_over = false;  // at most one batch's edit in this tick
  while (published_here_ < submitted_here_ && sink.room()) {
    Batch& b = ring_[static_cast<std::size_t>(published_here_) % ring_.size()];
    if (b.cut.cut.tick > tick - latency_) return;  // not due yet (the later ones neither)
    int done = done_.load(std::memory_order_acquire);
    if (done <= published_here_) {
      if (real_time_) return;  // published at the first tick it is done (counted late then)
      // Simulation. done == published_here_: every earlier batch is done (and published), so
      // whoever claims this one edits it on the state they left. Timed: the worker's work, not
      // the servo's (the run's servo_tick leaves it out).
      const auto t0 = std::chrono::steady_clock::now();
      int unclaimed = published_here_;
      if (!took_over &&
          claimed_.compare_exchange_strong(unclaimed, published_here_ + 1,
                                           std::memory_order_acq_rel,
                                           std::memory_order_acquire)) {
        edit(b, published_here_);  // the worker has not started it: the servo does it
        done_.store(published_here_ + 1, std::memory_order_release);
        done_.notify_all();  // the worker waits for it when it lost the claim
        took_over = true;
        ++stand_in->takeovers;
      } else {
        while (done <= published_here_) {  // the worker is on it: the rest of one batch
          done_.wait(done, std::memory_order_acquire);
          done = done_.load(std::memory_order_acquire);
        }
        ++stand_in->waits;
      }
      stand_in->ns += std::chrono::duration_cast<std::chrono::nanoseconds>(
                          std::chrono::steady_clock::now() - t0)
                          .count();
    }
    sink.done(b.cut);
    bricks_->publish(b.swaps, b.lipschitz);
    *stats = b.stats;
    *shortfalls += b.dropped;
    if (!b.complete) ++*shortfalls;
    if (b.cut.cut.tick < tick - latency_) ++*late;
    ++published_here_;
    published_.store(published_here_, std::memory_order_release);
  }
}

void FieldEditWorker::run() {
  for (;;) {
    const int seen = signal_.load(std::memory_order_acquire);
    if (stop_.load(std::memory_order_acquire)) return;
    const int next = done_.load(std::memory_order_acquire);  // every earlier batch is done
    if (submitted_.load(std::memory_order_acquire) <= next ||
        held_.load(std::memory_order_acquire)) {
      // Nothing to do: watch the signal for the spin window (the servo's next cut comes within a
      // tick while it drills), then park on it.
      if (spin_until_signalled(seen)) continue;
      parked_.store(true, std::memory_order_seq_cst);
      if (signal_.load(std::memory_order_seq_cst) == seen) {
        signal_.wait(seen, std::memory_order_acquire);
      }
      parked_.store(false, std::memory_order_relaxed);
      continue;
    }
    int unclaimed = next;
    if (!claimed_.compare_exchange_strong(unclaimed, next + 1, std::memory_order_acq_rel,
                                          std::memory_order_acquire)) {
      done_.wait(next, std::memory_order_acquire);  // the servo took it over: until it is done
      continue;
    }
    edit(ring_[static_cast<std::size_t>(next) % ring_.size()], next);
    worker_batches_.fetch_add(1, std::memory_order_relaxed);
    done_.store(next + 1, std::memory_order_release);
    done_.notify_all();
  }
}

bool FieldEditWorker::spin_until_signalled(int seen) const {
  if (spin_.count() <= 0) return false;
  using Clock = std::chrono::steady_clock;
  const Clock::time_point start = Clock::now();
  Clock::time_point yielded = start;
  for (;;) {
    for (int i = 0; i < 64; ++i) {
      if (signal_.load(std::memory_order_acquire) != seen) return true;
      spin_pause();
    }
    const Clock::time_point now = Clock::now();
    if (now - start >= spin_) return false;
    // Every 50 us the core goes to whatever else is ready to run on it (another process, the
    // view): the spin only takes time nobody else wants.
    if (now - yielded >= std::chrono::microseconds(50)) {
      sched_yield();
      yielded = now;
    }
  }
}

std::string FieldEditWorker::set_fifo_priority(int priority) {
  sched_param p{};
  p.sched_priority = priority;
  const int rc = pthread_setschedparam(thread_.native_handle(), SCHED_FIFO, &p);
  if (rc == 0) return {};
  return "the field edit's worker thread: SCHED_FIFO " + std::to_string(priority) + " refused (" +
         std::strerror(rc) + "): it runs at normal priority";
}

void FieldEditWorker::hold(bool held) {
  held_.store(held, std::memory_order_release);
  signal_.fetch_add(1, std::memory_order_release);
  signal_.notify_one();
}

void FieldEditWorker::wait_until_done() const {
  for (int done = done_.load(std::memory_order_acquire); done < submitted_here_;
       done = done_.load(std::memory_order_acquire)) {
    done_.wait(done, std::memory_order_acquire);
  }
}

void FieldEditWorker::edit(Batch& b, int number) {
  // The bricks retired by batches published before the last publish: the servo can no longer
  // hold a pointer to them (it drops its kept brick at every publish).
  const int published = published_.load(std::memory_order_acquire);
  while (retired_head_ < retired_.size() && retired_[retired_head_].second + 1 < published) {
    bricks_->recycle(retired_[retired_head_].first);
    ++retired_head_;
  }
  // The grid right after this batch's tick (the batches come in tick order).
  drill(b);
  FieldEditStats& stats = b.stats;
  b.complete = b.voxels.empty() ||
               edit_field_for_removed_voxels(field_, bricks_, tooth_, b.voxels,
                                             &fast::signed_distance, &worker_stats_, &cache_);
  stats = worker_stats_;
  b.lipschitz = bricks_->worker_lipschitz();
  b.swaps.assign(bricks_->worker_swaps().begin(), bricks_->worker_swaps().end());
  // The bricks this batch's publish retires, in batch order (compacted first: within capacity).
  if (retired_head_ > 0) {
    std::copy(retired_.begin() + static_cast<std::ptrdiff_t>(retired_head_), retired_.end(),
              retired_.begin());
    retired_.resize(retired_.size() - retired_head_);
    retired_head_ = 0;
  }
  for (const FieldBricks::Swap& w : b.swaps) {
    if (w.retired >= 0) retired_.emplace_back(w.retired, number);
  }
  bricks_->worker_end_batch();
}

void FieldEditWorker::drill(Batch& b) {
  // The reference's publish_field_edits, on the worker's grid: the cut set about g (the contact
  // as handed over: its stiffness and damping are the members'), the work and the removal.
  Cut& c = b.cut;
  const FieldDrillCut& cut = c.cut;
  shares_.clear();
  share_voxels_.clear();
  c.removed.clear();
  b.voxels.clear();
  b.dropped = 0;
  SurfaceCutSet::Nearest nearest;
  if (!cut_set_.collect(cut.g, cut.contact, &shares_, &share_voxels_, &nearest)) {
    shares_.clear();
    share_voxels_.clear();
    collect_cut_set(tooth_, cut.contact, cut.g, tip_.radius, &candidates_, &shares_,
                    &share_voxels_);
  }
  c.collected = !shares_.empty();
  if (c.collected) {
    c.material = heaviest_material(shares_);
    dentsim::drill_tick(shares_, share_voxels_, tip_, params_, cut.T, &tooth_, &drill_state_,
                        &c.removed);
    if (!c.removed.empty()) cut_set_.update(c.removed);
    c.bricks.take(tooth_, cut_set_.surface(), c.removed, brick_marks_);
    const std::size_t fit = std::min({c.removed.size(), b.limit, b.voxels.capacity()});
    b.voxels.assign(c.removed.begin(), c.removed.begin() + static_cast<std::ptrdiff_t>(fit));
    b.dropped = static_cast<long>(c.removed.size() - fit);
    dentsim::ToothContactProvider::sort_by_field_box(b.voxels.data(),
                                                     b.voxels.data() + b.voxels.size(),
                                                     tooth_.grid().n, field_->stride());
  }
  c.removed_voxels = drill_state_.removed_voxels;
  c.pulp_exposed = drill_state_.pulp_exposed;
  c.work_table_full = drill_state_.work_table_full;
  c.delivered_j = drill_state_.delivered_j;
  c.carry_j = drill_state_.carry_j;
}

FieldContactProvider::FieldContactProvider(VoxelTooth& tooth, const PipelineToothSetup& setup)
    : CutSetProvider(tooth, setup.tip, setup.k_tooth, setup.b_tooth, setup.drilling,
                     ContactModel::kField, &fast::signed_distance, setup.field),
      tooth_(tooth),
      field_(setup.field),
      real_time_(setup.real_time),
      // The reference's spare room (reserved by the base when drilling) twice: a new brick of
      // the reference may open up to 8 of the 9^3 bricks, and the copy reads through the
      // reference field where it runs out.
      bricks_(*setup.field, 2 * setup.field->spare_bricks()),
      solid_(tooth, bricks_) {
  if (setup.field_edit_latency > 0) set_field_edit_latency(setup.field_edit_latency);
}

FieldContactProvider::~FieldContactProvider() = default;

double FieldContactProvider::field_value(const Vec3& x) const { return bricks_.sample(x).value; }

const Vec3& FieldContactProvider::update_field_proxy(SurfaceProxy* proxy, const Vec3& c) {
  return proxy->update_on(solid_, c);
}

bool FieldContactProvider::edit_field(SampledField* field, std::span<const std::size_t> removed,
                                      FieldEditStats* stats, FieldEditCursor* cursor,
                                      long budget) {
  return fast::edit_field_for_removed_voxels(field, &bricks_, tooth_, removed,
                                             &fast::signed_distance, stats, &cache_, cursor,
                                             budget);
}

void FieldContactProvider::prepare_field_latency(int ticks) {
  worker_ = std::make_unique<FieldEditWorker>(field_, &bricks_, tooth_, ticks, real_time_,
                                              kFieldEditQueue, tip_, drill_params_,
                                              drill_state_);
}

void FieldContactProvider::hand_off_field_cut(const FieldDrillCut& cut) {
  // As the reference's: a full ring (a late real-time worker) leaves the tick uncut.
  if (!worker_->submit(cut, field_batch_limit())) ++field_edit_shortfalls_;
  field_edit_worker_wakes_ = worker_->wakes();
}

void FieldContactProvider::publish_field_edits(long tick) {
  worker_->publish(tick, *this, &field_edits_, &field_edit_shortfalls_,
                   &field_edit_late_publishes_, &stand_in_);
  field_edit_servo_takeovers_ = stand_in_.takeovers;
  field_edit_worker_waits_ = stand_in_.waits;
  field_edit_stand_in_ns_ = stand_in_.ns;
}

bool FieldContactProvider::room() const {
  // The reference's condition: last_removed() has room for a whole cut set.
  return removed_.size() + kContactCapacity <= removed_.capacity();
}

void FieldContactProvider::done(const FieldEditWorker::Cut& cut) {
  // The worker's drilling of tick cut.cut.tick on the servo's grid: the state the same voxels
  // removed in the same order leave (drill_tick's removal: the octree, then the codes), the drill
  // state's figures, the drill log's record (the reference's publish_field_edits).
  if (!cut.collected) return;
  const std::array<std::int64_t, kMaterialCount> removed_before = drill_state_.removed_voxels;
  const bool pulp_before = drill_state_.pulp_exposed;
  // The octree, the codes and the surface bits: the worker's bricks the removal changed, copied
  // (the servo's tooth was the worker's before it); else, from the codes held, the state of
  // remove_voxel and reencode_local for each, then surface_removed (SurfaceVoxels::remove).
  if (cut.bricks.fits()) {
    replace_bricks(tooth_, cut.bricks);
  } else {
    remove_voxels(tooth_, cut.removed);
    ++replay_shortfalls_;
  }
  removed_.insert(removed_.end(), cut.removed.begin(), cut.removed.end());  // within capacity
  drill_state_.removed_voxels = cut.removed_voxels;
  drill_state_.pulp_exposed = cut.pulp_exposed;
  drill_state_.work_table_full = cut.work_table_full;
  drill_state_.delivered_j = cut.delivered_j;
  drill_state_.carry_j = cut.carry_j;
  record_drill_at(cut.cut.tick, cut.cut.surface_z, cut.cut.force_n, cut.material,
                  removed_before, pulp_before);
}

std::string FieldContactProvider::set_worker_priority(int priority) {
  return worker_ != nullptr ? worker_->set_fifo_priority(priority) : std::string();
}

std::unique_ptr<PipelineTooth> make_fast_field_tooth(VoxelTooth& tooth,
                                                     const PipelineToothSetup& setup) {
  if (setup.field == nullptr) {
    throw InputError("contact model \"field\": no field of the tooth given");
  }
  return std::make_unique<ProviderTooth<FieldContactProvider>>(tooth, setup, tooth, setup);
}

}  // namespace dentsim::fast
