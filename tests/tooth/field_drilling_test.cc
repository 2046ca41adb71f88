// Drilling on the field model (reference/tooth/field_contact.h edit_field_for_removed_voxels;
// docs/derivations/field_contact.md §5): a bur drills a sphere along a scripted path (down, then
// sideways) with the provider's own removal rule; then the edited field agrees with the field
// rebuilt from scratch on the drilled voxels (the source sphere minus the removed cubes,
// triangulated and sampled anew) at every sample, its Lipschitz constant still bounds it, a probe
// pressed into the hole stops on the hole's floor (no phantom surface where voxels were removed),
// and the drill ticks allocate nothing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <climits>
#include <cstdio>
#include <limits>
#include <random>
#include <span>
#include <vector>

#include "reference/tooth/collision.h"
#include "reference/tooth/field_contact.h"
#include "reference/tooth/field_edit_core.h"
#include "reference/tooth/neighbors.h"
#include "reference/tooth/tooth_contacts.h"
#include "tests/support/alloc_counter.h"
#include "tests/tooth/field_shapes.h"

namespace dentsim {
namespace {

constexpr double kSide = 8e-3;     // grid edge [m]
constexpr int kN = 64;             // h = 0.125 mm
constexpr double kR = 2.5e-3;      // sphere radius [m]
constexpr double kRho = 0.4e-3;    // bur radius [m]
constexpr double kK = 3000.0;      // K_tooth [N/m]
constexpr double kT = 1e-3;        // tick [s]
constexpr int kDown = 900, kSideways = 600;  // ticks of each leg of the path

const Vec3 kCentre(4.03e-3, 3.97e-3, 3.61e-3);

bool in_sphere(const Vec3& p) { return (p - kCentre).norm() < kR; }

VoxelGrid sphere_grid() { return test::solid_grid(kN, kSide, in_sphere); }

// The samples at which two fields of the same lattice differ (bitwise).
long samples_differing(const SampledField& a, const SampledField& b) {
  const int m = a.samples_per_axis();
  long differ = 0;
  for (int z = 0; z < m; ++z) {
    for (int y = 0; y < m; ++y) {
      for (int x = 0; x < m; ++x) differ += a.at(x, y, z) != b.at(x, y, z);
    }
  }
  return differ;
}

// The top of the sphere and the bur's path: from 0.2 mm above contact straight down 1.1 mm, then
// 0.6 mm along x at that depth.
const Vec3 kTop = kCentre + Vec3(0, 0, kR);
Vec3 path(int tick) {
  const Vec3 start = kTop + Vec3(0, 0, kRho + 0.2e-3);
  if (tick < kDown) return start - Vec3(0, 0, 1.1e-3 * tick / kDown);
  return start - Vec3(0, 0, 1.1e-3) + Vec3(0.6e-3 * (tick - kDown) / kSideways, 0, 0);
}

struct Drilled {
  VoxelGrid original;
  VoxelTooth tooth;
  SampledField field;
  double lipschitz_before = 0.0;
  long removed = 0;
  long allocations = 0;
  long shortfalls = 0;
  FieldEditStats edits;
};

// The sphere drilled along the path by the field model's provider (its removal rule: the sdf
// model's, drilling.h), the drill ticks counted for allocations.
const Drilled& drilled() {
  static const Drilled* d = [] {
    auto* out = new Drilled{sphere_grid(), VoxelTooth(sphere_grid()), SampledField(), 0.0, 0, 0, 0,
                            FieldEditStats{}};
    out->field = build_sampled_field(out->original, triangulate_implicit(out->original, in_sphere),
                                     field_band_for_tip(kRho, out->original.voxel_size));
    out->lipschitz_before = out->field.lipschitz();
    const DrillParams drill;  // 300 000 rpm, mu_c 0.5
    ToothContactProvider provider(out->tooth, ToolTip{kRho, Vec3::Zero()}, kK, 0.0, &drill,
                                  ContactModel::kField, &signed_distance, &out->field);
    std::vector<Contact> contacts;
    contacts.reserve(kContactCapacity);
    Pose pose;
    {
      testing::AllocationScope scope;
      for (int tick = 0; tick < kDown + kSideways; ++tick) {
        pose.x = path(tick);
        provider.contacts(pose, contacts);
        out->removed += provider.drill(contacts, kT);
      }
      // Away from the tooth until the field has followed every cut (the provider's budget of
      // samples a tick).
      pose.x = kTop + Vec3(0, 0, 3e-3);
      while (provider.field_edits_pending() > 0) provider.contacts(pose, contacts);
      out->allocations = scope.count();
    }
    out->shortfalls = provider.field_edit_shortfalls();
    out->edits = provider.field_edits();
    return out;
  }();
  return *d;
}

// The field rebuilt from scratch on the drilled voxels: the sphere minus the removed voxels'
// cubes, triangulated (marching tetrahedra, bisection on that solid) and sampled anew.
SampledField rebuilt(const Drilled& d) {
  const VoxelGrid& now = d.tooth.grid();
  const double h = now.voxel_size;
  const auto inside = [&](const Vec3& p) {
    if (!in_sphere(p)) return false;
    const int i = static_cast<int>(std::floor(p.x() / h)), j = static_cast<int>(std::floor(p.y() / h)),
              k = static_cast<int>(std::floor(p.z() / h));
    return !(d.original.solid(i, j, k) && !now.solid(i, j, k));  // not in a removed cube
  };
  return build_sampled_field(now, triangulate_implicit(now, inside), field_band_for_tip(kRho, h));
}

TEST(FieldDrilling, DrillsWithoutAllocatingAndEditsLocally) {
  const Drilled& d = drilled();
  const FieldEditStats& e = d.edits;
  std::printf("removed %ld voxels; per removed voxel: %.0f samples scanned, %.1f queried, %.1f "
              "raised; %ld allocations, %ld shortfalls\n",
              d.removed, double(e.samples_scanned) / e.voxels, double(e.samples_queried) / e.voxels,
              double(e.samples_raised) / e.voxels, d.allocations, d.shortfalls);
  EXPECT_GT(d.removed, 100);  // the path drills (the numbers below mean something)
  EXPECT_EQ(e.voxels, d.removed);
  EXPECT_EQ(d.allocations, 0);
  EXPECT_EQ(d.shortfalls, 0);
  // The bound of field_contact.md §5: (2R + 1)^3 samples scanned per removed voxel, R =
  // ceil(c_out / h + 3/2), and at most as many queried.
  const double h = d.original.voxel_size;
  const int reach = static_cast<int>(std::ceil(d.field.outside_clamp() / h + 1.0));
  EXPECT_LE(e.samples_scanned, e.voxels * (2 * reach + 1) * (2 * reach + 1) * (2 * reach + 1));
  EXPECT_LE(e.samples_queried, e.samples_scanned);
  // Every removed voxel's centre is outside the edited field; every solid one inside or on it.
  const int pad = d.field.padding();
  for (int k = 0; k < kN; ++k) {
    for (int j = 0; j < kN; ++j) {
      for (int i = 0; i < kN; ++i) {
        const float v = d.field.at(i + pad, j + pad, k + pad);
        if (d.original.solid(i, j, k) && !d.tooth.grid().solid(i, j, k)) {
          ASSERT_GE(v, 0.5 * h - 1e-9) << i << " " << j << " " << k;
        } else if (d.tooth.grid().solid(i, j, k)) {
          ASSERT_LE(v, 0.0f) << i << " " << j << " " << k;
        }
      }
    }
  }
}

// At every sample of the lattice the edited field is within sqrt(3)/2 h of the field rebuilt from
// scratch on the drilled voxels (field_contact.md §5: the edit's voxel staircase against the
// rebuild's marching tetrahedra through the same cube faces, at most half a voxel's diagonal
// apart).
TEST(FieldDrilling, EditedFieldAgreesWithTheFieldRebuiltOnTheDrilledVoxels) {
  const Drilled& d = drilled();
  const SampledField fresh = rebuilt(d);
  ASSERT_EQ(fresh.samples_per_axis(), d.field.samples_per_axis());
  const int m = d.field.samples_per_axis();
  const double h = d.original.voxel_size;
  double worst = 0.0, worst_near = 0.0;
  long band = 0;
  for (int z = 0; z < m; ++z) {
    for (int y = 0; y < m; ++y) {
      for (int x = 0; x < m; ++x) {
        const double a = d.field.at(x, y, z), b = fresh.at(x, y, z);
        if (a == b) continue;
        ++band;
        worst = std::max(worst, std::abs(a - b));
        // Where the proxy of a bur of radius rho reads the field: phi < rho + h.
        if (std::min(a, b) < kRho + h) worst_near = std::max(worst_near, std::abs(a - b));
      }
    }
  }
  std::printf("edited vs rebuilt: %ld samples differ, max |difference| %.4f h (where phi < rho + h: "
              "%.4f h)\n",
              band, worst / h, worst_near / h);
  EXPECT_LE(worst, 0.5 * std::sqrt(3.0) * h);
}

// The field's Lipschitz constant bounds the edited field: over every cell (brute force) and
// between random point pairs around the hole (field_contact.md §2, §5).
TEST(FieldDrilling, LipschitzBoundHoldsAfterTheEdits) {
  const Drilled& d = drilled();
  const int m = d.field.samples_per_axis();
  double cells = 0.0;
  for (int z = 0; z + 1 < m; ++z) {
    for (int y = 0; y + 1 < m; ++y) {
      for (int x = 0; x + 1 < m; ++x) cells = std::max(cells, d.field.cell_lipschitz(x, y, z));
    }
  }
  const double L = d.field.lipschitz();
  std::printf("Lipschitz: before drilling %.4f, after %.4f, brute force over all cells %.4f\n",
              d.lipschitz_before, L, cells);
  EXPECT_LE(cells, L);
  // Once every queued edit is done an edge between two inside or two outside samples changes by
  // at most h (each side a max of 1-Lipschitz distances), an edge from an inside sample to an
  // outside one by at most 1.5 h (field_contact.md §5), so the cell bound is 1.5 sqrt(3) at most;
  // lipschitz() keeps the largest bound measured, including the transients while the queue
  // lagged a tick's cut (it only shortens the sweep).
  EXPECT_LE(cells, 1.5 * std::sqrt(3.0) + 1e-6);
  EXPECT_LE(L, 2.0 * std::sqrt(3.0));
  std::mt19937_64 rng(35);
  std::uniform_real_distribution<double> u(-1.2e-3, 1.2e-3);
  const Vec3 hole = kTop - Vec3(-0.3e-3, 0, 0.6e-3);
  for (int trial = 0; trial < 20000; ++trial) {
    const Vec3 x = hole + Vec3(u(rng), u(rng), u(rng));
    const Vec3 y = x + 0.1 * Vec3(u(rng), u(rng), u(rng));
    ASSERT_LE(std::abs(d.field.value(x) - d.field.value(y)), L * (x - y).norm() + 1e-12);
  }
}

// A probe (radius 0.25 mm, no drilling) pressed down the hole's axis at 1 N stops on the hole's
// floor, the drilled voxels' surface, not on removed material: its rendered centre is within
// rho + h of the remaining voxels and deeper than the original surface.
TEST(FieldDrilling, AProbeInTheFreshHoleTouchesItsFloor) {
  const Drilled& d = drilled();
  const double rho = 0.25e-3, h = d.original.voxel_size;
  SampledField field = d.field;
  VoxelTooth tooth(d.tooth.grid());
  ToothContactProvider probe(tooth, ToolTip{rho, Vec3::Zero()}, kK, 0.0, nullptr,
                             ContactModel::kField, &signed_distance, &field);
  std::vector<Contact> contacts;
  contacts.reserve(kContactCapacity);
  Pose pose;
  // Down the axis of the first leg, from above the surface to 1 N of spring below the floor.
  const Vec3 start = kTop + Vec3(0, 0, rho + 0.3e-3);
  Vec3 g = start;
  double force = 0.0;
  for (int tick = 0; tick <= 3000 && force < 1.0; ++tick) {
    pose.x = start - Vec3(0, 0, 2.0e-3 * tick / 3000);
    probe.contacts(pose, contacts);
    force = blended_contact_force(contacts).norm();
    g = probe.surface_proxy().g();
  }
  const double to_voxels = signed_distance(tooth, g, 1e-3).phi;
  std::printf("probe in the hole: held at 1 N at %.3f mm below the original top, %.4f mm from "
              "the drilled voxels (rho %.2f mm)\n",
              1e3 * (kTop.z() - (g.z() - rho)), 1e3 * to_voxels, 1e3 * rho);
  ASSERT_GE(force, 1.0);
  // Touches the drilled voxels (not held off them by removed material) ...
  EXPECT_LE(to_voxels, rho + 0.5 * h);
  EXPECT_GE(to_voxels, rho - probe.surface_proxy().skin() - 0.5 * h);
  // ... deep in the hole: the bur's first leg went 0.9 mm below the top.
  EXPECT_LT(g.z() - rho, kTop.z() - 0.5e-3);
}

// The edit's savings change no value (reference/tooth/field_edit_core.h: only the ball read,
// outside samples with a solid neighbour within |v| not asked): a provider whose edit also
// applies the rule exactly as field_edit_core.h states it (every sample of the (2R + 1)^3 box
// read; inside samples minus the distance to the removed cube, every outside candidate asked
// with reach c_out) to a copy of
// the field, call by call on the same tooth, ends with the copy equal to the edited field at
// every sample, the same samples raised and the same Lipschitz constant (the rule re-measures the
// bounding box of a call's raises; the edit only the cells with a raised corner, the same maximum
// since every other cell of the box was bounded by lipschitz() already).
class RuleAsWritten final : public ToothContactProvider {
 public:
  RuleAsWritten(VoxelTooth& tooth, const DrillParams* drill, SampledField* field,
                SampledField* plain)
      : ToothContactProvider(tooth, ToolTip{kRho, Vec3::Zero()}, kK, 0.0, drill,
                             ContactModel::kField, &signed_distance, field),
        tooth_(tooth),
        plain_(plain) {}
  long plain_raised = 0, plain_queried = 0;

 protected:
  bool edit_field(SampledField* field, std::span<const std::size_t> removed,
                  FieldEditStats* stats, FieldEditCursor* cursor, long budget) override {
    // No budget (set_field_edit_rate(inf) below): every call subtracts the whole queue.
    EXPECT_EQ(cursor->next, 0u);
    EXPECT_EQ(cursor->row, 0);
    const VoxelGrid& grid = tooth_.grid();
    const int n = grid.n, m = plain_->samples_per_axis(), pad = plain_->padding();
    const double h = grid.voxel_size, c_out = plain_->outside_clamp();
    const int r = static_cast<int>(std::ceil(c_out / h + 1.0));
    int lo[3] = {m, m, m}, hi[3] = {-1, -1, -1};
    for (const std::size_t v : removed) {
      const int c[3] = {static_cast<int>(v % n) + pad, static_cast<int>((v / n) % n) + pad,
                        static_cast<int>(v / (std::size_t(n) * n)) + pad};
      for (int z = std::max(0, c[2] - r); z <= std::min(m - 1, c[2] + r); ++z) {
        for (int y = std::max(0, c[1] - r); y <= std::min(m - 1, c[1] + r); ++y) {
          for (int x = std::max(0, c[0] - r); x <= std::min(m - 1, c[0] + r); ++x) {
            const float old = plain_->at(x, y, z);
            if (old >= static_cast<float>(c_out)) continue;
            const double e[3] = {std::max(std::abs(x - c[0]) - 1.0, 0.0),
                                 std::max(std::abs(y - c[1]) - 1.0, 0.0),
                                 std::max(std::abs(z - c[2]) - 1.0, 0.0)};
            if (h * std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]) >
                std::abs(static_cast<double>(old)) + 1e-6 * h) {
              continue;
            }
            ++plain_queried;
            // Inside (the sample's voxel solid now): minus the distance to the removed cube;
            // outside: the exact distance to the remaining voxels.
            const Vec3 p = plain_->sample_position(x, y, z);
            int idx[3];
            const bool inside = sdf_detail::voxel_of(grid, p, idx) &&
                                grid.solid(idx[0], idx[1], idx[2]);
            const double f[3] = {std::max(std::abs(x - c[0]) - 0.5, 0.0),
                                 std::max(std::abs(y - c[1]) - 0.5, 0.0),
                                 std::max(std::abs(z - c[2]) - 0.5, 0.0)};
            const double d = inside ? -h * std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2])
                                    : signed_distance(tooth_, p, c_out).phi;
            if (!(d > old) || !plain_->raise(x, y, z, d)) continue;
            ++plain_raised;
            const int s[3] = {x, y, z};
            for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], s[a]), hi[a] = std::max(hi[a], s[a]);
          }
        }
      }
    }
    if (hi[0] >= 0) plain_->include_cells(lo, hi);
    const bool whole = ToothContactProvider::edit_field(field, removed, stats, cursor, budget);
    EXPECT_EQ(cursor->next, removed.size());
    return whole;
  }

 private:
  VoxelTooth& tooth_;
  SampledField* plain_;
};

TEST(FieldDrilling, TheEditsSavingsChangeNoValue) {
  VoxelTooth tooth(sphere_grid());
  SampledField field = build_sampled_field(tooth.grid(), triangulate_implicit(tooth.grid(), in_sphere),
                                           field_band_for_tip(kRho, tooth.grid().voxel_size));
  SampledField plain = field;
  plain.reserve_spare_bricks(std::max<std::size_t>(256, plain.brick_count() / 2));
  const DrillParams drill;
  RuleAsWritten provider(tooth, &drill, &field, &plain);
  provider.set_field_edit_rate(std::numeric_limits<double>::infinity());
  std::vector<Contact> contacts;
  contacts.reserve(kContactCapacity);
  Pose pose;
  long removed = 0;
  for (int tick = 0; tick < kDown + kSideways; ++tick) {
    pose.x = path(tick);
    provider.contacts(pose, contacts);
    removed += provider.drill(contacts, kT);
  }
  pose.x = kTop + Vec3(0, 0, 3e-3);
  while (provider.field_edits_pending() > 0) provider.contacts(pose, contacts);
  const FieldEditStats& e = provider.field_edits();
  std::printf("%ld voxels removed; per voxel: rule as written %.0f read, %.1f asked; shared edit "
              "%.0f read, %.1f asked (%.1f of them answered by a solid neighbour), %.1f raised\n",
              removed, std::pow(2.0 * plain.edit_radius() + 1.0, 3.0),
              double(provider.plain_queried) / e.voxels, double(e.samples_scanned) / e.voxels,
              double(e.samples_queried) / e.voxels, double(e.samples_bounded) / e.voxels,
              double(e.samples_raised) / e.voxels);
  EXPECT_GT(removed, 100);
  EXPECT_EQ(e.samples_raised, provider.plain_raised);
  EXPECT_EQ(e.samples_queried, provider.plain_queried);
  EXPECT_GT(e.samples_bounded, 0);
  EXPECT_EQ(field.lipschitz(), plain.lipschitz());
  EXPECT_EQ(samples_differing(field, plain), 0);
}

// The largest cell bound (SampledField::cell_lipschitz, brute force) over the cells with lower
// corner in [lo, hi] (clamped to the lattice's cells).
double max_cell_lipschitz(const SampledField& f, const int lo[3], const int hi[3]) {
  const int m = f.samples_per_axis();
  double worst = 0.0;
  for (int z = std::max(0, lo[2]); z <= std::min(m - 2, hi[2]); ++z) {
    for (int y = std::max(0, lo[1]); y <= std::min(m - 2, hi[1]); ++y) {
      for (int x = std::max(0, lo[0]); x <= std::min(m - 2, hi[0]); ++x) {
        worst = std::max(worst, f.cell_lipschitz(x, y, z));
      }
    }
  }
  return worst;
}

// The cells an edit of `removed` can change: every corner within R samples of a removed voxel's
// sample (field_edit_core.h), so lower corners in the voxels' sample box grown by R + 1.
void edit_region(const SampledField& f, const VoxelGrid& grid,
                 std::span<const std::size_t> removed, int lo[3], int hi[3]) {
  const std::size_t n = static_cast<std::size_t>(grid.n);
  const int grow = f.edit_radius() + 1, pad = f.padding();
  for (int a = 0; a < 3; ++a) lo[a] = INT_MAX, hi[a] = INT_MIN;
  for (const std::size_t v : removed) {
    const int s[3] = {static_cast<int>(v % n) + pad, static_cast<int>((v / n) % n) + pad,
                      static_cast<int>(v / (n * n)) + pad};
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], s[a] - grow), hi[a] = std::max(hi[a], s[a] + grow);
  }
}

// A budgeted edit (field_edit_core.h FieldEditCursor) ends where the whole edit ends: a cap of the
// sphere (the solid voxels within 0.45 mm of its top) is removed from the tooth at once, then
// subtracted from one copy of the field in one call and from others in calls of a budget of 1
// unit of work (one row a call), 97 and 300, and no budget (LONG_MAX): every call spends at most
// max(budget - 1, 4) + field_edit_step_work(R) units of work (field_contact.h) and reads at most
// budget + 2R samples, lipschitz() bounds every cell after every call (brute force over the
// cells the edit can change; the others are the build's, bounded before), and at the end every
// sample, every count (but the work: a resumed voxel's set-up is charged again) and the raised
// samples agree with the whole edit, and the budgeted copy's Lipschitz constant is at least the
// whole edit's.
struct PlainAccess {
  SampledField* field;
  const VoxelTooth& tooth;
  float at(int sx, int sy, int sz) const { return field->at(sx, sy, sz); }
  double distance(int, int, int, const Vec3& p, double reach) const {
    return signed_distance(tooth, p, reach).phi;
  }
  bool raise(int sx, int sy, int sz, double value) { return field->raise(sx, sy, sz, value); }
  void include_cells(const int lo[3], const int hi[3]) { field->include_cells(lo, hi); }
};

TEST(FieldDrilling, ABudgetedEditEndsWhereTheWholeEditEnds) {
  const VoxelGrid grid = sphere_grid();
  VoxelTooth tooth(grid);
  SampledField whole = build_sampled_field(grid, triangulate_implicit(grid, in_sphere),
                                           field_band_for_tip(kRho, grid.voxel_size));
  const SampledField built = whole;
  whole.reserve_spare_bricks(256);
  std::vector<std::size_t> removed;
  for (int k = 0; k < kN; ++k) {
    for (int j = 0; j < kN; ++j) {
      for (int i = 0; i < kN; ++i) {
        if (!tooth.grid().solid(i, j, k) || (grid.center(i, j, k) - kTop).norm() > 0.45e-3) continue;
        removed.push_back(grid.index(i, j, k));
        tooth.octree.remove_voxel(i, j, k);
        reencode_local(tooth.octree.grid(), i, j, k, &tooth.codes);
      }
    }
  }
  ASSERT_GT(removed.size(), 30u);
  FieldEditStats a;
  PlainAccess access_a{&whole, tooth};
  ASSERT_TRUE(field_edit_detail::edit_field(whole, tooth, removed, access_a, &a));
  EXPECT_GT(a.samples_raised, 0);
  int lo[3], hi[3];
  edit_region(whole, grid, removed, lo, hi);
  const long row = 2 * whole.edit_radius() + 1;
  const long step = field_edit_step_work(whole.edit_radius());
  for (const long budget : {1L, 97L, 300L, LONG_MAX}) {
    SampledField budgeted = built;
    budgeted.reserve_spare_bricks(256);
    FieldEditStats b;
    PlainAccess access_b{&budgeted, tooth};
    field_edit_detail::FieldEditCursor cursor;
    long calls = 0, most = 0, most_work = 0;
    double worst = 0.0;  // the largest cell bound over lipschitz() after any call
    while (cursor.next < removed.size()) {
      const long before = b.samples_scanned, work_before = b.work;
      ASSERT_TRUE(field_edit_detail::edit_field(budgeted, tooth, removed, access_b, &b, &cursor,
                                                budget));
      most = std::max(most, b.samples_scanned - before);
      most_work = std::max(most_work, b.work - work_before);
      worst = std::max(worst, max_cell_lipschitz(budgeted, lo, hi) / budgeted.lipschitz());
      ASSERT_LT(++calls, 1000000);
    }
    std::printf("%zu voxels removed at once, budget %ld: %ld calls, at most %ld samples read and "
                "%ld work a call (whole edit: %ld, %ld); largest cell bound / lipschitz() after a "
                "call %.4f\n",
                removed.size(), budget, calls, most, most_work, a.samples_scanned, a.work, worst);
    EXPECT_LE(most, budget == LONG_MAX ? a.samples_scanned : std::max(budget, 1L) + row - 1)
        << budget;
    // The work's bound (field_edit_core.h): a step is begun only below the budget, but for the
    // call's first row, which may follow a voxel's set-up.
    EXPECT_LE(most_work,
              budget == LONG_MAX ? a.work : std::max(budget - 1, kFieldEditVoxelWeight) + step)
        << budget;
    EXPECT_GT(b.cells_measured, 0) << budget;
    EXPECT_LE(worst, 1.0) << budget;
    if (budget < 1000) {
      EXPECT_GT(calls, static_cast<long>(removed.size())) << budget;
    }
    EXPECT_EQ(a.voxels, b.voxels) << budget;
    EXPECT_EQ(a.samples_scanned, b.samples_scanned) << budget;
    EXPECT_EQ(a.samples_queried, b.samples_queried) << budget;
    EXPECT_EQ(a.samples_raised, b.samples_raised) << budget;
    EXPECT_EQ(a.rows_read, b.rows_read) << budget;
    EXPECT_EQ(a.cells_measured, b.cells_measured) << budget;
    EXPECT_GE(b.work, a.work) << budget;  // a resumed voxel's set-up is charged again
    EXPECT_EQ(samples_differing(whole, budgeted), 0) << budget;
    EXPECT_GE(budgeted.lipschitz(), whole.lipschitz()) << budget;
  }
  // The cells outside the region were the build's, which lipschitz() bounded from the start.
  const int all_lo[3] = {0, 0, 0}, all_hi[3] = {INT_MAX, INT_MAX, INT_MAX};
  EXPECT_LE(max_cell_lipschitz(whole, all_lo, all_hi), whole.lipschitz());
}

// The provider's budget (ToothContactProvider::set_field_edit_rate: budget(T) = rate T units of
// work a contacts() call): the bur presses once into the sphere with a cutting coefficient that
// removes every voxel it touches in that tick (a burst of removals), then waits away from the
// tooth while the queue drains. At a budget of 1 (a row a call), 300 and none, every call spends
// at most max(budget - 1, 4) + field_edit_step_work(R) and reads at most budget + 2R samples,
// lipschitz() bounds every cell after every call (brute force),
// nothing allocates, and once the queue is empty every sample of the field equals the unbudgeted
// run's, with the same counts: the grid no longer changes while the queue drains.
TEST(FieldDrilling, TheProvidersBudgetedEditEndsWhereTheWholeEditEnds) {
  const VoxelGrid grid = sphere_grid();
  const SampledField built = build_sampled_field(grid, triangulate_implicit(grid, in_sphere),
                                                 field_band_for_tip(kRho, grid.voxel_size));
  DrillParams drill;
  drill.cutting_coefficient = 1e6;  // every voxel the bur touches goes in its first tick
  struct Run {
    SampledField field;
    FieldEditStats edits;
    long removed = 0, calls = 0, most = 0, most_work = 0, allocations = 0;
    double worst = 0.0;
  };
  const auto run = [&](double rate) {
    Run out{built, FieldEditStats{}};
    VoxelTooth tooth(grid);
    ToothContactProvider provider(tooth, ToolTip{kRho, Vec3::Zero()}, kK, 0.0, &drill,
                                  ContactModel::kField, &signed_distance, &out.field);
    provider.set_field_edit_rate(rate);
    std::vector<Contact> contacts;
    contacts.reserve(kContactCapacity);
    Pose pose;
    pose.x = kTop + Vec3(0, 0, kRho + 0.2e-3);  // above the top, then pressed 0.3 mm in
    provider.contacts(pose, contacts);
    pose.x = kTop + Vec3(0, 0, kRho - 0.3e-3);
    provider.contacts(pose, contacts);
    EXPECT_EQ(contacts.size(), 1u);
    out.removed = provider.drill(contacts, kT);
    std::vector<std::size_t> removed(provider.last_removed());
    int lo[3], hi[3];
    edit_region(out.field, grid, removed, lo, hi);
    const long row = 2 * out.field.edit_radius() + 1;
    const long step = field_edit_step_work(out.field.edit_radius());
    pose.x = kTop + Vec3(0, 0, 3e-3);  // away: nothing more is drilled
    while (provider.field_edits_pending() > 0) {
      const long before = provider.field_edits().samples_scanned;
      const long work_before = provider.field_edits().work;
      long allocations = 0;
      {
        testing::AllocationScope scope;
        provider.contacts(pose, contacts);
        allocations = scope.count();
      }
      out.allocations += allocations;
      const long read = provider.field_edits().samples_scanned - before;
      out.most = std::max(out.most, read);
      const long work = provider.field_edits().work - work_before;
      out.most_work = std::max(out.most_work, work);
      if (provider.field_edit_budget() < LONG_MAX - step) {  // else no budget
        EXPECT_LE(read, provider.field_edit_budget() + row - 1);
        EXPECT_LE(work, std::max(provider.field_edit_budget() - 1, kFieldEditVoxelWeight) + step);
      }
      out.worst = std::max(out.worst, max_cell_lipschitz(out.field, lo, hi) / out.field.lipschitz());
      if (++out.calls > 1000000) break;
    }
    out.edits = provider.field_edits();
    EXPECT_EQ(provider.field_edit_shortfalls(), 0);
    return out;
  };
  const Run whole = run(std::numeric_limits<double>::infinity());
  std::printf("one tick's burst: %ld voxels removed, the whole edit %ld samples read in %ld call\n",
              whole.removed, whole.edits.samples_scanned, whole.calls);
  ASSERT_GT(whole.removed, 10);
  EXPECT_EQ(whole.calls, 1);
  EXPECT_EQ(whole.edits.voxels, whole.removed);
  EXPECT_LE(whole.worst, 1.0);
  EXPECT_EQ(whole.allocations, 0);
  for (const double samples : {1.0, 300.0}) {
    const Run b = run(samples / kT);  // budget(kT) = samples
    std::printf("budget %.0f a call: %ld calls, at most %ld samples read and %ld work a call; "
                "largest cell bound / lipschitz() after a call %.4f\n",
                samples, b.calls, b.most, b.most_work, b.worst);
    EXPECT_EQ(b.removed, whole.removed);
    EXPECT_GT(b.calls, samples == 1.0 ? whole.removed : 1);
    EXPECT_LE(b.worst, 1.0);
    EXPECT_EQ(b.allocations, 0);
    EXPECT_EQ(b.edits.voxels, whole.edits.voxels);
    EXPECT_EQ(b.edits.samples_scanned, whole.edits.samples_scanned);
    EXPECT_EQ(b.edits.samples_queried, whole.edits.samples_queried);
    EXPECT_EQ(b.edits.samples_raised, whole.edits.samples_raised);
    EXPECT_EQ(b.edits.cells_measured, whole.edits.cells_measured);
    EXPECT_EQ(samples_differing(b.field, whole.field), 0) << samples;
    EXPECT_GE(b.field.lipschitz(), whole.field.lipschitz());
  }
}

// The cut set's query (drilling.h collect_cut_set) lists every solid voxel the bur's band meets:
// inside a cavity (the solid all around the bur) ~5.7 (rho / h)^3 of them, far more than the
// collision scratch's default room (4096) once rho / h >= 10 (the 0.5 mm bur at 512^3: 12). The
// provider reserves room for the ball's bound at construction, so pressing and drilling there
// allocates nothing (before, the query's vector grew inside the tick). A block with a bore just
// wider than the bur, h = 0.125 mm, a 1.5 mm bur (rho / h = 12) pressed onto the bore's floor:
// the band's ball (r = 2 mm) holds ~8 000 solid voxels.
TEST(FieldDrilling, WideBurOnAFineGridCutsWithoutAllocating) {
  constexpr int n = 64;
  constexpr double side = 8e-3, rho = 1.5e-3, surface = 4e-3;
  constexpr double floor = 2e-3, bore = rho + 0.05e-3;  // the bore: radius, and its floor's z
  const VoxelGrid grid = test::solid_grid(n, side, [](const Vec3& p) {
    const bool in_bore = p.z() > floor && std::hypot(p.x() - 4e-3, p.y() - 4e-3) < bore;
    return p.z() < surface && !in_bore;
  });
  DrillParams drill;
  drill.cutting_coefficient = 1e6;  // every voxel the band reaches goes in its first tick
  {  // the sdf model (the field model shares collect_cut_set and the reserve)
    const ContactModel model = ContactModel::kSurfaceProxy;
    VoxelTooth tooth(grid);
    ToothContactProvider provider(tooth, ToolTip{rho, Vec3::Zero()}, kK, 0.0, &drill, model,
                                  &signed_distance, nullptr);
    std::vector<Contact> contacts;
    contacts.reserve(kContactCapacity);
    Pose pose;
    pose.x = Vec3(4e-3, 4e-3, surface + rho + 0.5e-3);  // above the surface
    provider.contacts(pose, contacts);
    EXPECT_TRUE(contacts.empty());
    long allocations = 0, removed = 0;
    {
      testing::AllocationScope scope;
      pose.x.z() = floor + rho - 0.2e-3;  // down the bore, pressed 0.2 mm into its floor
      provider.contacts(pose, contacts);
      removed = provider.drill(contacts, kT);
      allocations = scope.count();
    }
    std::printf("wide bur: %ld voxels removed, %ld allocations\n", removed, allocations);
    EXPECT_EQ(contacts.size(), 1u);
    EXPECT_GT(removed, 100);  // signal: the wide band cut a disc of many voxels
    EXPECT_EQ(allocations, 0);
  }
}

// The field model removes what the sdf model removes (issue #30; docs/derivations/drilling.md §6):
// the sphere drilled along the path (the tool's centre scripted, the force K |g - c| the model's)
// by each model's provider, at h = 0.125 and 0.0625 mm (stride 1 and 2 for the 0.4 mm bur). Both
// models share the cut set and the law (drilling.h collect_cut_set, drill_tick); the field's proxy
// stands on the field, which follows the removed voxels through the edit. When the edit keeps up
// (no budget: each tick's removals are in the field by the next tick), the field's surface lies
// within a fraction of a voxel of the voxels' (field_contact.md §7: 3 H^2 / (8 rho) in a drilled
// hole, 0.005 mm here) against the cut band's b = rho / 3 = 0.13 mm, so the two models cut the same
// band and their removed volumes agree within the 10 % at each resolution. With the
// default budget (kFieldEditSamplesPerSecond) the edit keeps up at h = 0.125 mm (the same 10 %);
// at 0.0625 mm its queue grows to thousands of voxels, the proxy stands on material the voxels
// have lost, the band empties and the field model removes less (printed, not asserted: the
// budget's throughput, not the cut, is what fails there; drilling.md §6 measures it at 512^3).
struct PathRun {
  double volume_m3 = 0.0, delivered_j = 0.0;
  std::size_t most_pending = 0;
  long shortfalls = 0;
};

PathRun drill_the_path(int n, ContactModel model, double edit_rate) {
  const VoxelGrid grid = test::solid_grid(n, kSide, in_sphere);
  VoxelTooth tooth{VoxelGrid(grid)};
  SampledField field;
  if (model == ContactModel::kField) {
    field = build_sampled_field(grid, triangulate_implicit(grid, in_sphere),
                                field_band_for_tip(kRho, grid.voxel_size));
  }
  const DrillParams drill;
  ToothContactProvider provider(tooth, ToolTip{kRho, Vec3::Zero()}, kK, 0.0, &drill, model,
                                &signed_distance,
                                model == ContactModel::kField ? &field : nullptr);
  provider.set_field_edit_rate(edit_rate);
  std::vector<Contact> contacts;
  contacts.reserve(kContactCapacity);
  Pose pose;
  PathRun run;
  for (int tick = 0; tick < kDown + kSideways; ++tick) {
    pose.x = path(tick);
    provider.contacts(pose, contacts);  // the edit first: the voxels still queued after it
    run.most_pending = std::max(run.most_pending, provider.field_edits_pending());
    provider.drill(contacts, kT);
  }
  const DrillState& state = provider.drill_state();
  for (int m = kEnamel; m < kMaterialCount; ++m) run.volume_m3 += state.removed_volume_m3(m);
  run.delivered_j = state.delivered_j;
  run.shortfalls = provider.field_edit_shortfalls();
  return run;
}

TEST(FieldDrilling, TheFieldModelRemovesWhatTheSdfModelRemovesAtTwoResolutions) {
  const int ns[2] = {kN, 2 * kN};
  const double unbounded = std::numeric_limits<double>::infinity();
  const double budgeted = ToothContactProvider::kFieldEditSamplesPerSecond;
  for (int r = 0; r < 2; ++r) {
    const PathRun sdf = drill_the_path(ns[r], ContactModel::kSurfaceProxy, budgeted);
    const PathRun whole = drill_the_path(ns[r], ContactModel::kField, unbounded);
    const PathRun paced = drill_the_path(ns[r], ContactModel::kField, budgeted);
    std::printf("h %.4f mm: removed sdf %.4f mm^3 (E %.4f J); field, edit unbounded %.4f mm^3 "
                "(E %.4f J); field, default budget %.4f mm^3 (E %.4f J, queue at most %zu "
                "voxels)\n",
                1e3 * kSide / ns[r], 1e9 * sdf.volume_m3, sdf.delivered_j, 1e9 * whole.volume_m3,
                whole.delivered_j, 1e9 * paced.volume_m3, paced.delivered_j, paced.most_pending);
    ASSERT_GT(sdf.volume_m3, 0.0);
    EXPECT_EQ(whole.most_pending, 0u);  // each tick's removals in the field by the next tick
    EXPECT_EQ(whole.shortfalls + paced.shortfalls, 0);
    EXPECT_NEAR(whole.volume_m3, sdf.volume_m3, 0.1 * sdf.volume_m3) << "n " << ns[r];
    if (r == 0) {
      EXPECT_NEAR(paced.volume_m3, sdf.volume_m3, 0.1 * sdf.volume_m3);
    }
  }
}

}  // namespace
}  // namespace dentsim
