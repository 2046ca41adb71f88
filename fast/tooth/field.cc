// The fast twin of the "field" contact model (fast/tooth/field.h).
#include "fast/tooth/field.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdlib>

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

float FieldBricks::at(int sx, int sy, int sz) const {
  const int bx = sx / kFieldBrick, by = sy / kFieldBrick, bz = sz / kFieldBrick;
  const std::int32_t id = index_[slot(bx, by, bz)];
  if (id >= 0) {
    return bricks_[static_cast<std::size_t>(id) * kSamples +
                   static_cast<std::size_t>((sx - bx * kFieldBrick) +
                                            kE * ((sy - by * kFieldBrick) +
                                                  kE * (sz - bz * kFieldBrick)))];
  }
  if (id == kViaField) return field_.at(sx, sy, sz);
  return id == kAllOutside ? out_ : in_;
}

void FieldBricks::mirror(int sx, int sy, int sz) {
  const float v = field_.at(sx, sy, sz);
  // The bricks holding s along each axis: its own, and the one below when s is on its apron.
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
  bool changed = false;
  for (int iz = 0; iz < count[2]; ++iz) {
    for (int iy = 0; iy < count[1]; ++iy) {
      for (int ix = 0; ix < count[0]; ++ix) {
        const std::size_t sl = slot(b[0][ix], b[1][iy], b[2][iz]);
        std::int32_t id = index_[sl];
        if (id == kViaField) {
          changed = true;
          continue;
        }
        if (id < 0) {
          const float fill = id == kAllOutside ? out_ : in_;
          if (v == fill) continue;
          changed = true;
          if (bricks_.size() + kSamples > bricks_.capacity()) {  // no spare brick: read through
            index_[sl] = kViaField;
            continue;
          }
          id = static_cast<std::int32_t>(bricks_.size() / kSamples);
          bricks_.insert(bricks_.end(), static_cast<std::size_t>(kSamples), fill);  // in capacity
          index_[sl] = id;
        }
        const int local = l[0][ix] + kE * (l[1][iy] + kE * l[2][iz]);
        float& stored =
            bricks_[static_cast<std::size_t>(id) * kSamples + static_cast<std::size_t>(local)];
        if (stored != v) changed = true;
        stored = v;
      }
    }
  }
  // A new brick or a read-through slot: the kept brick pointer may name a slot that changed.
  last_slot_ = std::numeric_limits<std::size_t>::max();
  if (changed) ++generation_;
}

void FieldBricks::include_cells(const int lo[3], const int hi[3]) {
  int a[3], b[3];
  for (int k = 0; k < 3; ++k) {
    a[k] = std::max(0, lo[k] - 1);
    b[k] = std::min(m_ - 2, hi[k]);
  }
  // SampledField::cell_lipschitz's arithmetic per cell up to the square root (header comment).
  double worst = 0.0;
  float cf[8];
  for (int z = a[2]; z <= b[2]; ++z) {
    for (int y = a[1]; y <= b[1]; ++y) {
      for (int x = a[0]; x <= b[0]; ++x) {
        const int s[3] = {x, y, z};
        corners(s, cf);
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
      }
    }
  }
  if (a[0] <= b[0] && a[1] <= b[1] && a[2] <= b[2]) {
    lipschitz_ = std::max(lipschitz_, std::sqrt(worst) / h_);
  }
}

namespace {

// FieldBricks::sample's work, with internal linkage so that FieldSolid::query inlines it (the
// member itself is an exported symbol, which -fPIC keeps out of line; GCC 12 does not inline a
// function called twice of this size without the attribute).
[[gnu::always_inline]] inline FieldSample sample_bricks(const FieldBricks& bricks, const Vec3& x,
                                                       bool* deep) {
  FieldSample out;
  if (deep != nullptr) *deep = false;
  const SampledField& f = bricks.field();
  const int m = f.samples_per_axis();
  if (m < 2) return out;  // SampledField::sample's empty field (deep_inside false)
  const Vec3 origin = f.sample_position(0, 0, 0);
  const double h = f.spacing();
  int s[3];
  double t[3];
  for (int a = 0; a < 3; ++a) {  // the reference's locate()
    const double u = std::clamp((x[a] - origin[a]) / h, 0.0, static_cast<double>(m - 1));
    const int i = std::min(static_cast<int>(u), m - 2);
    s[a] = i;
    t[a] = u - i;
  }
  float cf[8];
  bricks.corners(s, cf);
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
  const FieldSample s = sample_bricks(bricks_, x, &deep);
  last_.deep = deep;
  last_.value = s.value;
  last_.gradient = s.gradient;
  return last_;
}

SignedDistance FieldSolid::distance(const Vec3& x, double reach) const {
  SignedDistance out;
  if (have_exact_ && reach > 0.0) {  // the free-space certificate (header comment)
    const double margin = 1e-9 * bricks_.field().spacing();
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
  float at(int sx, int sy, int sz) const { return bricks->at(sx, sy, sz); }
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
    if (!field->raise(sx, sy, sz, value)) return false;
    bricks->mirror(sx, sy, sz);
    return true;
  }
  void include_cells(const int lo[3], const int hi[3]) { bricks->include_cells(lo, hi); }
};

}  // namespace

bool edit_field_for_removed_voxels(SampledField* field, FieldBricks* bricks,
                                   const VoxelTooth& tooth, std::span<const std::size_t> removed,
                                   SignedDistanceFn sd, FieldEditStats* stats,
                                   VoxelDistanceCache* cache, FieldEditCursor* cursor,
                                   long budget) {
  FastFieldAccess access{field, bricks, tooth, sd, cache,
                         static_cast<std::uint64_t>(field->samples_per_axis())};
  return field_edit_detail::edit_field(*field, tooth, removed, access, stats, cursor, budget);
}

FieldContactProvider::FieldContactProvider(VoxelTooth& tooth, const PipelineToothSetup& setup)
    : dentsim::ToothContactProvider(tooth, setup.tip, setup.k_tooth, setup.b_tooth,
                                    setup.drilling, ContactModel::kField, &fast::signed_distance,
                                    setup.field),
      tooth_(tooth),
      // The reference's spare room (reserved by the base when drilling) twice: a new brick of
      // the reference may open up to 8 of the 9^3 bricks, and the copy reads through the
      // reference field where it runs out.
      bricks_(*setup.field, 2 * setup.field->spare_bricks()),
      solid_(tooth, bricks_) {}

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

std::unique_ptr<PipelineTooth> make_fast_field_tooth(VoxelTooth& tooth,
                                                     const PipelineToothSetup& setup) {
  if (setup.field == nullptr) {
    throw InputError("contact model \"field\": no field of the tooth given");
  }
  return std::make_unique<ProviderTooth<FieldContactProvider>>(tooth, setup, tooth, setup);
}

}  // namespace dentsim::fast
