// The fast twin of the field contact model (fast/tooth/field.h) against the reference
// (reference/tooth/field_contact.h, itself checked in tests/tooth/field_*_test.cc), on a drilled
// sphere at 64^3:
// - the kernels alone: the 9^3 bricks hold the field's every sample, a cell's corners are the
//   field's, the sample (value, gradient, deep-inside flag) is the field's bitwise, before and
//   after mirrored raises, and the Lipschitz update equals the reference's (include_cells);
// - the query: fast::FieldSolid's distance (phi, found, nearest, voxel) and normal bitwise equal
//   to dentsim::FieldSolid's at random points, reaches and along paths (the kept query and the
//   free-space certificate in use);
// - the provider: the reference's and the fast provider driven along the same bur path (free
//   space, down into the sphere drilling, sideways, away): every tick's contact, g, held fraction
//   and removed voxels bitwise equal, and at the end the two edited fields equal at every sample,
//   the same edit counts and the same Lipschitz constant (the edit's kept voxel distances in
//   use); the fast ticks allocate nothing.
// Bitwise because the arithmetic is the same (docs/tolerance_policy.md item 9: equal where the
// operations are the same).
#include "fast/tooth/field.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <thread>
#include <vector>

#include "fast/tooth/sdf.h"
#include "reference/tooth/surface_proxy_core.h"
#include "reference/tooth/tooth_contacts.h"
#include "tests/support/alloc_counter.h"
#include "tests/tooth/field_shapes.h"

namespace dentsim {
namespace {

constexpr double kSide = 8e-3;   // grid edge [m]
constexpr int kN = 64;           // h = 0.125 mm
constexpr double kR = 2.5e-3;    // sphere radius [m]
constexpr double kRho = 0.4e-3;  // bur radius [m]
constexpr double kK = 3000.0, kB = 5.0, kT = 1e-3;
const Vec3 kCentre(4.03e-3, 3.97e-3, 3.61e-3);

bool in_sphere(const Vec3& p) { return (p - kCentre).norm() < kR; }

VoxelGrid sphere_grid() { return test::solid_grid(kN, kSide, in_sphere); }

// The sphere's field at `stride` (k = 2: a sample at every other voxel centre, H = 0.25 mm).
SampledField sphere_field(const VoxelGrid& g, int stride = 1) {
  return build_sampled_field(g, triangulate_implicit(g, in_sphere),
                             field_band_for_tip(kRho, g.voxel_size, stride));
}

bool same(const SignedDistance& a, const SignedDistance& b) {
  return a.phi == b.phi && a.found == b.found && a.nearest == b.nearest && a.voxel == b.voxel;
}

// Points over the lattice and beyond it (clamped coordinates), `count` of them: how many of
// fast::FieldBricks::sample's value, gradient or deep flag differ from the reference field's
// sample() and deep_inside(); *deep_count counts the deep points.
long sample_mismatches(const SampledField& field, const fast::FieldBricks& bricks,
                       std::uint64_t seed, int count, long* deep_count) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> anywhere(-0.1 * kSide, 1.1 * kSide);
  std::uniform_real_distribution<double> dir(-1.0, 1.0), radial(kR - 1.0e-3, kR + 1.5e-3);
  long differ = 0;
  for (int trial = 0; trial < count; ++trial) {
    const Vec3 d(dir(rng), dir(rng), dir(rng));
    const Vec3 x = trial % 4 == 0 || d.norm() < 1e-3
                       ? Vec3(anywhere(rng), anywhere(rng), anywhere(rng))
                       : Vec3(kCentre + radial(rng) * d.normalized());
    bool deep = false;
    const FieldSample f = bricks.sample(x, &deep);
    const FieldSample r = field.sample(x);
    differ += !(f.value == r.value && f.gradient == r.gradient &&
                deep == field.deep_inside(x) && bricks.sample(x).value == r.value);
    *deep_count += deep ? 1 : 0;
  }
  return differ;
}

TEST(FastFieldBricks, HoldEverySampleAndTheCellCorners) {
  const VoxelGrid g = sphere_grid();
  const SampledField field = sphere_field(g);
  const fast::FieldBricks bricks(field, 0);
  const int m = field.samples_per_axis();
  long differ = 0;
  for (int z = 0; z < m; ++z) {
    for (int y = 0; y < m; ++y) {
      for (int x = 0; x < m; ++x) differ += bricks.at(x, y, z) != field.at(x, y, z);
    }
  }
  EXPECT_EQ(differ, 0);
  std::mt19937_64 rng(36);
  std::uniform_int_distribution<int> u(0, m - 2);
  for (int trial = 0; trial < 20000; ++trial) {
    const int s[3] = {u(rng), u(rng), u(rng)};
    float c[8];
    bricks.corners(s, c);
    for (int d = 0; d < 8; ++d) {
      ASSERT_EQ(c[d], field.at(s[0] + (d & 1), s[1] + ((d >> 1) & 1), s[2] + (d >> 2)));
    }
  }
  EXPECT_EQ(bricks.lipschitz(), field.lipschitz());
  EXPECT_GT(bricks.brick_count(), 0u);
}

// The fast sample (value, gradient and the deep-inside flag from one gather) is the reference's
// bitwise: the same arithmetic on the same samples.
void sample_equals_the_reference(int stride) {
  const VoxelGrid g = sphere_grid();
  const SampledField field = sphere_field(g, stride);
  ASSERT_EQ(field.stride(), stride);
  const fast::FieldBricks bricks(field, 0);
  long deep = 0;
  EXPECT_EQ(sample_mismatches(field, bricks, 41, 20000, &deep), 0);
  EXPECT_GT(deep, 100);  // the deep-inside flag was exercised both ways
}
TEST(FastFieldBricks, SampleEqualsTheReferenceSampleBitwise) { sample_equals_the_reference(1); }
// The same at stride 2 (the spacing set by the tool, issue #30).
TEST(FastFieldBricks, SampleEqualsTheReferenceSampleBitwiseAtStride2) {
  sample_equals_the_reference(2);
}

TEST(FastFieldBricks, MirroredRaisesAndTheLipschitzUpdateEqualTheReference) {
  const VoxelGrid g = sphere_grid();
  SampledField reference = sphere_field(g);
  SampledField mirrored = reference;
  reference.reserve_spare_bricks(64);
  mirrored.reserve_spare_bricks(64);
  // Few spare bricks in the copy: some slots read through the field.
  fast::FieldBricks bricks(mirrored, 4);
  const int m = reference.samples_per_axis();
  std::mt19937_64 rng(2026);
  std::uniform_int_distribution<int> u(0, m - 1);
  std::uniform_real_distribution<double> v(-0.3e-3, 1.5e-3);
  for (int round = 0; round < 40; ++round) {
    int lo[3] = {m, m, m}, hi[3] = {-1, -1, -1};
    const int c[3] = {u(rng), u(rng), u(rng)};
    for (int k = 0; k < 30; ++k) {
      int s[3];
      for (int a = 0; a < 3; ++a) s[a] = std::clamp(c[a] + u(rng) % 7 - 3, 0, m - 1);
      const double value = v(rng);
      const bool r = reference.raise(s[0], s[1], s[2], value);
      ASSERT_EQ(r, mirrored.raise(s[0], s[1], s[2], value));
      if (!r) continue;
      bricks.mirror(s[0], s[1], s[2]);
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], s[a]);
        hi[a] = std::max(hi[a], s[a]);
      }
    }
    if (hi[0] < 0) continue;
    reference.include_cells(lo, hi);
    bricks.include_cells(lo, hi);
    ASSERT_EQ(bricks.lipschitz(), reference.lipschitz()) << "round " << round;
  }
  long differ = 0;
  for (int z = 0; z < m; ++z) {
    for (int y = 0; y < m; ++y) {
      for (int x = 0; x < m; ++x) {
        differ += bricks.at(x, y, z) != reference.at(x, y, z);
        differ += mirrored.at(x, y, z) != reference.at(x, y, z);
      }
    }
  }
  EXPECT_EQ(differ, 0);
  EXPECT_GT(bricks.lipschitz(), sphere_field(g).lipschitz());  // the raises did raise it
  long deep = 0;  // the sample on mirrored bricks and read-through slots
  EXPECT_EQ(sample_mismatches(reference, bricks, 42, 20000, &deep), 0);
}

void query_equals_the_reference(int stride) {
  const VoxelGrid g = sphere_grid();
  const VoxelTooth tooth(g);
  const SampledField field = sphere_field(g, stride);
  const dentsim::FieldSolid reference(tooth, field);
  const fast::FieldBricks bricks(field, 0);
  const fast::FieldSolid solid(tooth, bricks);
  const double h = g.voxel_size;
  std::mt19937_64 rng(30);
  std::uniform_real_distribution<double> dir(-1.0, 1.0), radial(kR - 1.5e-3, kR + 2.5e-3),
      anywhere(-0.1 * kSide, 1.1 * kSide);
  const double reaches[] = {kRho, kRho + 4 * h, 2 * kRho, kSide};
  long found = 0, mismatches = 0;
  const auto check = [&](const Vec3& x, double reach) {
    const SignedDistance r = reference.distance(x, reach);
    const SignedDistance f = solid.distance(x, reach);
    if (r.found) ++found;
    if (!same(r, f)) {
      ++mismatches;
      ADD_FAILURE() << "distance at " << x.transpose() << " reach " << reach << ": " << r.phi
                    << " vs " << f.phi;
      return;
    }
    if (r.found && !(reference.normal(x, r) == solid.normal(x, f))) {
      ++mismatches;
      ADD_FAILURE() << "normal at " << x.transpose();
    }
  };
  for (int trial = 0; trial < 20000; ++trial) {
    Vec3 d(dir(rng), dir(rng), dir(rng));
    if (d.norm() < 1e-3) continue;
    const Vec3 x = trial % 5 == 0 ? Vec3(anywhere(rng), anywhere(rng), anywhere(rng))
                                  : Vec3(kCentre + radial(rng) * d.normalized());
    check(x, reaches[trial % 4]);
  }
  // Along paths of small steps (the certificate and the kept query at work): 2 um a step, in
  // free space and through the surface.
  for (int path = 0; path < 40; ++path) {
    Vec3 d(dir(rng), dir(rng), dir(rng));
    Vec3 x = kCentre + (kR + 1.2e-3) * d.normalized();
    const Vec3 step = -2e-6 * d.normalized() + 1e-6 * Vec3(dir(rng), dir(rng), dir(rng));
    for (int k = 0; k < 800; ++k, x += step) {
      check(x, kRho);
      check(x, kRho + 1e-5);
    }
  }
  std::printf("%ld found, %ld certified, %ld evaluated, %ld mismatches\n", found,
              solid.certified(), solid.evaluated(), mismatches);
  EXPECT_EQ(mismatches, 0);
  EXPECT_GT(found, 1000);
  EXPECT_GT(solid.certified(), 10000);  // free space answered without reading the field
}
TEST(FastFieldSolid, EqualsTheReferenceQueryBitwise) { query_equals_the_reference(1); }
TEST(FastFieldSolid, EqualsTheReferenceQueryBitwiseAtStride2) { query_equals_the_reference(2); }

// The sweep's step from the cell's slope (reference/tooth/field_contact.h field_cell_advance,
// docs/derivations/field_contact.md §3) against brute force: at random points near the sphere's
// and a box mesh's surface, random directions and clearances, phi sampled densely along the
// certified step never falls below rho - s + slack (the step is safe), and the fast twin's advance
// is the reference's bitwise.
// One shape's two solids on its field: the reference's and the fast twin on its bricks.
struct TwinSolids {
  TwinSolids(const VoxelGrid& grid, const SampledField& field)
      : tooth(grid), reference(tooth, field), bricks(field, 0), solid(tooth, bricks) {}
  const VoxelTooth tooth;
  const dentsim::FieldSolid reference;
  const fast::FieldBricks bricks;
  const fast::FieldSolid solid;
};

// The box mesh of the brute-force tests (corners kBoxLo, kBoxHi), its grid and its field.
const Vec3 kBoxLo(1e-3, 1e-3, 1e-3), kBoxHi(7e-3, 6e-3, 4e-3);
VoxelGrid box_grid() {
  return test::solid_grid(kN, kSide, [](const Vec3& p) {
    return (p.array() > kBoxLo.array()).all() && (p.array() < kBoxHi.array()).all();
  });
}
SampledField box_field(const VoxelGrid& box) {
  return build_sampled_field(box, test::box_mesh(kBoxLo, kBoxHi),
                             field_band_for_tip(kRho, box.voxel_size));
}

TEST(FastFieldSolid, TheSweepsCellStepNeverLeavesTheSkinByBruteForce) {
  const VoxelGrid sphere = sphere_grid();
  const Vec3& hi = kBoxHi;
  const VoxelGrid box = box_grid();
  const SampledField fields[2] = {sphere_field(sphere), box_field(box)};
  const VoxelGrid* grids[2] = {&sphere, &box};
  std::mt19937_64 rng(45);
  std::uniform_real_distribution<double> u01(0.0, 1.0), dir(-1.0, 1.0);
  long steps = 0, longer = 0, unsafe = 0, differ = 0;
  for (int shape = 0; shape < 2; ++shape) {
    const TwinSolids twins(*grids[shape], fields[shape]);
    const SampledField& field = fields[shape];
    const dentsim::FieldSolid& reference = twins.reference;
    const fast::FieldSolid& solid = twins.solid;
    const double h = field.spacing(), skin = std::min(0.25 * kRho, 0.5 * grids[shape]->voxel_size);
    const double slack = proxy_detail::kSweepSlack * skin;
    for (int trial = 0; trial < 4000; ++trial) {
      Vec3 d(dir(rng), dir(rng), dir(rng));
      if (d.norm() < 1e-3) continue;
      d.normalize();
      // A point at phi in (rho - s, rho + s): on the sphere along a random radius, on the box
      // above its top face or beside its +x face.
      Vec3 y;
      const double off = kRho + (2.0 * u01(rng) - 1.0) * skin;
      if (shape == 0) {
        Vec3 r(dir(rng), dir(rng), dir(rng));
        if (r.norm() < 1e-3) continue;
        y = kCentre + (kR + off) * r.normalized();
      } else if (trial % 2 == 0) {
        y = Vec3(2e-3 + 4e-3 * u01(rng), 2e-3 + 3e-3 * u01(rng), hi.z() + off);
      } else {
        y = Vec3(hi.x() + off, 2e-3 + 3e-3 * u01(rng), 1.5e-3 + 2e-3 * u01(rng));
      }
      const double phi = field.sample(y).value;
      const double floor_phi = phi - (1e-3 + u01(rng)) * skin;  // clearance in (1e-3 s, 1.001 s)
      const SignedDistance sr = reference.distance(y, 1.0);
      const SignedDistance sf = solid.distance(y, 1.0);
      ASSERT_TRUE(sr.found && sf.found && sr.phi == phi);
      const double clearance = phi - floor_phi;
      const double a = reference.sweep_advance(y, sr, d, clearance, slack, 1.0);
      differ += a != solid.sweep_advance(y, sf, d, clearance, slack, 1.0);
      ++steps;
      if (a > clearance / field.lipschitz()) ++longer;
      for (int k = 0; k <= 200; ++k) {
        const double v = field.sample(y + (a * k / 200.0) * d).value;
        if (v < floor_phi + slack - 1e-9 * h) {
          ++unsafe;
          ADD_FAILURE() << "shape " << shape << " at " << y.transpose() << " dir " << d.transpose()
                        << ": phi " << v << " below " << floor_phi + slack << " at " << k;
          break;
        }
      }
    }
  }
  std::printf("%ld cell steps, %ld longer than the Lipschitz step, %ld unsafe, %ld differ\n", steps,
              longer, unsafe, differ);
  EXPECT_EQ(unsafe, 0);
  EXPECT_EQ(differ, 0);
  EXPECT_GT(longer, steps / 2);  // the cell's slope certifies more than the global bound
}

// Query counts of the sweep on a flat face (the box's top, a plane in the field to float rounding):
// from g at phi = rho towards a point 1 mm inside at tilt theta, the Lipschitz step alone closes
// the clearance by the factor 1 - cos(theta) / L a query (ln(1e-3) / ln(1 - cos(theta) / L)
// queries to block); the cell's slope is exact on a plane, so each query steps to the floor (+
// slack) or to the cell's exit: at most one query per cell the segment crosses, plus the one
// that blocks, plus one per face crossed in a negative axis direction (below). Both twins end at the same point, with clearance in (0, 1e-3 s].
TEST(FastFieldSolid, TheSweepOnAFlatFaceTakesOneQueryPerCellCrossed) {
  const Vec3 lo(1e-3, 1e-3, 1e-3), hi(7e-3, 7e-3, 4e-3);
  const auto in_box = [&](const Vec3& p) {
    return (p.array() > lo.array()).all() && (p.array() < hi.array()).all();
  };
  const VoxelGrid g = test::solid_grid(kN, kSide, in_box);
  const VoxelTooth tooth(g);
  const SampledField field =
      build_sampled_field(g, test::box_mesh(lo, hi), field_band_for_tip(kRho, g.voxel_size));
  const dentsim::FieldSolid reference(tooth, field);
  const fast::FieldBricks bricks(field, 0);
  const fast::FieldSolid solid(tooth, bricks);
  const SurfaceProxy proxy(kRho, g.voxel_size);
  const proxy_detail::ProxyConstants k = proxy.constants();
  const double h = field.spacing();
  const Vec3 origin = field.sample_position(0, 0, 0);
  const auto cell_of = [&](const Vec3& x) {
    const Vec3 u = (x - origin) / h;
    return Eigen::Vector3i(static_cast<int>(u.x()), static_cast<int>(u.y()), static_cast<int>(u.z()));
  };
  long sweeps = 0, queries = 0, lipschitz_queries = 0;
  for (int tilt = 0; tilt < 5; ++tilt) {
    const double theta = 0.3 * tilt;
    for (int azimuth = 0; azimuth < 8; ++azimuth) {
      const double psi = 0.785 * azimuth;
      const Vec3 d(std::sin(theta) * std::cos(psi), std::sin(theta) * std::sin(psi), -std::cos(theta));
      const Vec3 g0(3.0e-3 + 0.11e-3 * azimuth, 3.5e-3 + 0.07e-3 * tilt, hi.z() + kRho);
      const Vec3 to = g0 + 1e-3 * d;
      Vec3 yr = g0, yf = g0;
      ASSERT_FALSE(proxy_detail::sweep(k, reference, &yr, to));
      const long before = solid.distances();
      ASSERT_FALSE(proxy_detail::sweep(k, solid, &yf, to));
      const long used = solid.distances() - before;
      ASSERT_EQ(yr, yf);
      const double clearance = field.sample(yf).value - (kRho - k.skin);
      EXPECT_GT(clearance, 0.0);
      EXPECT_LE(clearance, 1e-3 * k.skin);
      // The cells the segment g0 -> yf passes through (sampled densely).
      int cells = 1;
      Eigen::Vector3i last = cell_of(g0);
      for (int i = 1; i <= 10000; ++i) {
        const Eigen::Vector3i c = cell_of(g0 + (yf - g0) * (i / 10000.0));
        if (c != last) ++cells;
        last = c;
      }
      // One query a cell, one that blocks, and one Lipschitz step for each face crossed towards
      // -x, -y or -z (the step to the exit lands on the face, which locates in the cell left:
      // t_exit = 0 there).
      EXPECT_LE(used, 2 * cells) << "tilt " << theta << " azimuth " << psi;
      ++sweeps;
      queries += used;
      lipschitz_queries += static_cast<long>(
          std::ceil(std::log(1e-3) / std::log(1.0 - std::cos(theta) / field.lipschitz())));
    }
  }
  std::printf("%ld blocked sweeps on a plane: %ld queries (%.2f a sweep); the Lipschitz step "
              "alone: about %ld (L = %.4f)\n",
              sweeps, queries, static_cast<double>(queries) / sweeps, lipschitz_queries,
              field.lipschitz());
}

// A Solid that forwards to the fast FieldSolid and records where distance() was asked (the
// push-out's iterates, the sweep's steps); with kNewton false it claims no field-only path
// (surface_proxy_core.h kFieldPaths) and hides slope(), so push_out takes the unit step (the sdf
// model's, and the field's before stop 46).
template <bool kNewton>
struct RecordingSolid {
  static constexpr bool kFieldPaths = kNewton;
  const fast::FieldSolid& solid;
  std::vector<Vec3>* asked;
  const VoxelTooth& tooth() const { return solid.tooth(); }
  SignedDistance distance(const Vec3& x, double reach) const {
    asked->push_back(x);
    return solid.distance(x, reach);
  }
  Vec3 normal(const Vec3& x, const SignedDistance& sd) const { return solid.normal(x, sd); }
  double lipschitz() const { return solid.lipschitz(); }
  double slope(const Vec3& x) const
    requires kNewton
  {
    return solid.slope(x);
  }
  double sweep_advance(const Vec3& y, const SignedDistance& sd, const Vec3& d, double clearance,
                       double slack, double left) const {
    return solid.sweep_advance(y, sd, d, clearance, slack, left);
  }
};

// The gate of the field-only paths is the Solid's claim (surface_proxy_core.h kFieldPaths), not
// the methods it has: a Solid that answers slope() and sweep_advance() but claims nothing takes
// the thesis's steps, the unit push-out and the Lipschitz sweep (the sdf model's).
template <bool kClaim>
struct ForwardingSolid {
  static constexpr bool kFieldPaths = kClaim;
  const fast::FieldSolid& solid;
  long* queries;
  const VoxelTooth& tooth() const { return solid.tooth(); }
  SignedDistance distance(const Vec3& x, double reach) const {
    ++*queries;
    return solid.distance(x, reach);
  }
  Vec3 normal(const Vec3& x, const SignedDistance& sd) const { return solid.normal(x, sd); }
  double lipschitz() const { return solid.lipschitz(); }
  double slope(const Vec3& x) const { return solid.slope(x); }
  double sweep_advance(const Vec3& y, const SignedDistance& sd, const Vec3& d, double clearance,
                       double slack, double left) const {
    return solid.sweep_advance(y, sd, d, clearance, slack, left);
  }
};
// Without the claim the field's methods are not reached; with it they are required.
static_assert(!proxy_detail::kFieldPaths<ForwardingSolid<false>>);
static_assert(proxy_detail::kFieldPaths<ForwardingSolid<true>>);
static_assert(proxy_detail::kFieldPaths<fast::FieldSolid>);
static_assert(proxy_detail::kFieldPaths<dentsim::FieldSolid>);

// A Solid claiming nothing computes the sweep the Lipschitz step alone computes (its own loop
// below, the core's before stop 45), the same doubles, and takes more queries than the claim.
TEST(FastFieldSolid, TheFieldPathsAreTakenOnlyByTheSolidsClaim) {
  const VoxelGrid sphere = sphere_grid();
  const SampledField field = sphere_field(sphere);
  const TwinSolids twins(sphere, field);
  const SurfaceProxy proxy(kRho, sphere.voxel_size);
  const proxy_detail::ProxyConstants k = proxy.constants();
  long plain_queries = 0, claimed_queries = 0, sweeps = 0, differ = 0;
  const ForwardingSolid<false> plain{twins.solid, &plain_queries};
  const ForwardingSolid<true> claimed{twins.solid, &claimed_queries};
  std::mt19937_64 rng(48);
  std::uniform_real_distribution<double> dir(-1.0, 1.0);
  for (int trial = 0; trial < 400; ++trial) {
    Vec3 r(dir(rng), dir(rng), dir(rng));
    if (r.norm() < 1e-3) continue;
    r.normalize();
    // From rho off the sphere towards a point 1 mm inside it: a blocked sweep.
    const Vec3 from = kCentre + (kR + kRho) * r;
    const Vec3 to = kCentre + (kR - 1e-3) * r + 0.5e-3 * Vec3(dir(rng), dir(rng), dir(rng));
    Vec3 yp = from, yc = from, yl = from;
    const bool reached = proxy_detail::sweep(k, plain, &yp, to);
    proxy_detail::sweep(k, claimed, &yc, to);
    // The Lipschitz step alone (conservative advancement, surface_proxy_core.h sweep without the
    // cell's step).
    bool lip_reached = false;
    for (int step = 0; step < kSurfaceProxySweepSteps; ++step) {
      const Vec3 gap = to - yl;
      const double left = gap.norm();
      if (left <= k.tol) {
        yl = to;
        lip_reached = true;
        break;
      }
      const double floor_phi = k.rho - k.skin;
      const double reach =
          floor_phi + twins.solid.lipschitz() * std::min(left, 4.0 * sphere.voxel_size) + k.skin;
      const double clearance = twins.solid.distance(yl, reach).phi - floor_phi;
      const double advance = clearance / twins.solid.lipschitz();
      if (advance >= left) {
        yl = to;
        lip_reached = true;
        break;
      }
      if (clearance <= 1e-3 * k.skin) break;
      yl += (advance / left) * gap;
    }
    ++sweeps;
    differ += !(yp == yl && reached == lip_reached);
  }
  std::printf("%ld sweeps: %ld queries claiming nothing, %ld claiming the field paths; %ld differ "
              "from the Lipschitz step alone\n",
              sweeps, plain_queries, claimed_queries, differ);
  EXPECT_GT(sweeps, 300);
  EXPECT_EQ(differ, 0);
  EXPECT_LT(claimed_queries, plain_queries);
}

// The push-out's Newton step (reference/tooth/surface_proxy_core.h plain_step,
// docs/derivations/field_contact.md §3): from random points in the skin {rho - s <= phi < rho}
// (where a blocked sweep leaves g) near the sphere's and a box mesh's surface (faces, edges,
// corners) and in a spherical cavity a little wider than the tip, the fast twin's push-out
// equals the reference's bitwise; it converges (phi >= rho - push_tol); it asks fewer queries
// than the unit step; and by brute force phi along every step of it (200 points a step) stays
// >= rho - s (the floor the sweep keeps; the proof gives phi >= 0 by the ball rule,
// |step| <= phi / L).
TEST(FastFieldSolid, ThePushOutsNewtonStepEqualsTheReferenceAndKeepsTheFloor) {
  const VoxelGrid sphere = sphere_grid();
  const Vec3& lo = kBoxLo;
  const Vec3& hi = kBoxHi;
  const VoxelGrid box = box_grid();
  // A cavity the bur has cut: a solid block with a spherical hole of radius rho + 0.1 mm (the
  // tip's admissible set there is a ball of radius 0.1 mm, a concave wall all round).
  const double hole = kRho + 0.1e-3;
  const auto in_block = [&](const Vec3& p) {
    return (p - kCentre).cwiseAbs().maxCoeff() < 2e-3 && (p - kCentre).norm() > hole;
  };
  const VoxelGrid block = test::solid_grid(kN, kSide, in_block);
  const SampledField fields[3] = {
      sphere_field(sphere), box_field(box),
      build_sampled_field(block, triangulate_implicit(block, in_block),
                          field_band_for_tip(kRho, block.voxel_size))};
  const VoxelGrid* grids[3] = {&sphere, &box, &block};
  std::mt19937_64 rng(46);
  std::uniform_real_distribution<double> u01(0.0, 1.0), dir(-1.0, 1.0);
  long pushes = 0, differ = 0, unconverged = 0, below = 0, newton_queries = 0, unit_queries = 0;
  double least = 1.0;
  long cavity_newton = 0, cavity_unit = 0;
  for (int shape = 0; shape < 3; ++shape) {
    const TwinSolids twins(*grids[shape], fields[shape]);
    const SampledField& field = fields[shape];
    const dentsim::FieldSolid& reference = twins.reference;
    const fast::FieldSolid& solid = twins.solid;
    const SurfaceProxy proxy(kRho, grids[shape]->voxel_size);
    const proxy_detail::ProxyConstants k = proxy.constants();
    std::vector<Vec3> asked, unit_asked;
    asked.reserve(64);
    unit_asked.reserve(64);
    const RecordingSolid<true> newton{solid, &asked};
    const RecordingSolid<false> unit{solid, &unit_asked};
    for (int trial = 0; trial < 3000; ++trial) {
      // Near the sphere along a random radius; near the box anywhere within 0.8 mm of it (its
      // edges and corners too).
      Vec3 y;
      if (shape == 0) {
        Vec3 r(dir(rng), dir(rng), dir(rng));
        if (r.norm() < 1e-3) continue;
        y = kCentre + (kR + kRho + (2.0 * u01(rng) - 1.0) * k.skin) * r.normalized();
      } else if (shape == 1) {
        y = lo - Vec3::Constant(0.8e-3) +
            Vec3(u01(rng), u01(rng), u01(rng)).cwiseProduct(hi - lo + Vec3::Constant(1.6e-3));
      } else {
        Vec3 r(dir(rng), dir(rng), dir(rng));
        if (r.norm() < 1e-3) continue;
        y = kCentre + (hole - kRho + u01(rng) * k.skin) * r.normalized();
      }
      const double phi = field.sample(y).value;
      if (!(phi >= k.rho - k.skin && phi < k.rho)) continue;
      Vec3 xr = y, xf = y, xu = y;
      const double er = proxy_detail::push_out(k, reference, &xr);
      asked.clear();
      const double ef = proxy_detail::push_out(k, newton, &xf);
      unit_asked.clear();
      proxy_detail::push_out(k, unit, &xu);
      ++pushes;
      differ += !(xr == xf && er == ef);
      unconverged += ef < -k.push_tol;
      newton_queries += static_cast<long>(asked.size());
      unit_queries += static_cast<long>(unit_asked.size());
      if (shape == 2) {
        cavity_newton += static_cast<long>(asked.size());
        cavity_unit += static_cast<long>(unit_asked.size());
      }
      // The iterates are the points asked, in order (the last one is the result's).
      for (std::size_t i = 1; i < asked.size(); ++i) {
        for (int j = 0; j <= 200; ++j) {
          const double v = field.sample(asked[i - 1] + (asked[i] - asked[i - 1]) * (j / 200.0)).value;
          least = std::min(least, v - (k.rho - k.skin));
          if (v < k.rho - k.skin) {
            ++below;
            ADD_FAILURE() << "shape " << shape << " from " << y.transpose() << ": phi " << v;
            break;
          }
        }
      }
    }
  }
  std::printf("%ld push-outs from the skin: %ld queries with the Newton step (%.2f each), %ld with "
              "the unit step (%.2f); %ld differ, %ld unconverged, least phi - (rho - s) %.3g m\n",
              pushes, newton_queries, static_cast<double>(newton_queries) / pushes, unit_queries,
              static_cast<double>(unit_queries) / pushes, differ, unconverged, least);
  std::printf("in the cavity: %ld queries with the Newton step, %ld with the unit step\n",
              cavity_newton, cavity_unit);
  EXPECT_GT(pushes, 3000);
  EXPECT_EQ(differ, 0);
  EXPECT_EQ(unconverged, 0);
  EXPECT_EQ(below, 0);
  EXPECT_LE(newton_queries, unit_queries);
  EXPECT_LT(cavity_newton, cavity_unit);
}

// The slide cap in a cavity (docs/derivations/field_contact.md §3, "The slide cap"): the tool
// pressed from inside a spherical hole and a cubic hole (concave walls, edges and corners) into
// their walls, a tick at a time. Both twins' proxies are the same doubles with the stalled-slide
// stop; every proxy keeps phi >= rho - s (Claim 1); the stop asks fewer queries than the
// tangent-plane slides up to the cap (the old rule, run from the same g each tick), and where it
// ends is printed against the old rule's.
TEST(FastFieldSolid, TheStalledSlideStopEqualsTheReferenceAndKeepsTheFloor) {
  const double ball = kRho + 0.1e-3;   // the spherical hole's radius
  const double cube = kRho + 0.25e-3;  // the cubic hole's half side
  const auto in_ball_block = [&](const Vec3& p) {
    return (p - kCentre).cwiseAbs().maxCoeff() < 2e-3 && (p - kCentre).norm() > ball;
  };
  const auto in_cube_block = [&](const Vec3& p) {
    const double m = (p - kCentre).cwiseAbs().maxCoeff();
    return m < 2e-3 && m > cube;
  };
  const VoxelGrid grids[2] = {test::solid_grid(kN, kSide, in_ball_block),
                              test::solid_grid(kN, kSide, in_cube_block)};
  const SampledField fields[2] = {
      build_sampled_field(grids[0], triangulate_implicit(grids[0], in_ball_block),
                          field_band_for_tip(kRho, grids[0].voxel_size)),
      build_sampled_field(grids[1], triangulate_implicit(grids[1], in_cube_block),
                          field_band_for_tip(kRho, grids[1].voxel_size))};
  const double reach[2] = {ball - kRho, cube - kRho};
  std::mt19937_64 rng(47);
  std::uniform_real_distribution<double> dir(-1.0, 1.0), depth(0.0, 0.3e-3);
  long updates = 0, differ = 0, below = 0, stop_queries = 0, cap_queries = 0, apart = 0;
  double least = 1.0, farthest = 0.0;
  for (int shape = 0; shape < 2; ++shape) {
    const TwinSolids twins(grids[shape], fields[shape]);
    const SurfaceProxy proxy(kRho, grids[shape].voxel_size);
    const proxy_detail::ProxyConstants k = proxy.constants();
    std::vector<Vec3> asked, cap_asked;
    asked.reserve(1024);
    cap_asked.reserve(1024);
    const RecordingSolid<true> stop{twins.solid, &asked};
    const RecordingSolid<true> capped{twins.solid, &cap_asked};
    for (int trial = 0; trial < 60; ++trial) {
      Vec3 r(dir(rng), dir(rng), dir(rng));
      if (r.norm() < 1e-3) continue;
      // In the cube, towards its corners and edges as often as its faces.
      if (shape == 1) r = r.cwiseSign().cwiseProduct(r.cwiseAbs().cwiseSqrt().cwiseSqrt());
      const Vec3 end = kCentre + (reach[shape] * 1.8 + depth(rng)) * r.normalized();
      bool valid_r = false, valid_f = false, valid_t = false;
      Vec3 gr = kCentre, gf = kCentre, gt = kCentre;
      for (int tick = 0; tick <= 40; ++tick) {
        const Vec3 c = kCentre + (end - kCentre) * (tick / 40.0);
        Vec3 g_cap = gf;
        bool valid_cap = valid_f;
        proxy_detail::update(k, twins.reference, &valid_r, &gr, c);
        proxy_detail::update(k, twins.solid, &valid_t, &gt, c);
        asked.clear();
        proxy_detail::update(k, stop, &valid_f, &gf, c);
        cap_asked.clear();
        proxy_detail::update<RecordingSolid<true>, false>(k, capped, &valid_cap, &g_cap, c);
        ++updates;
        differ += !(gr == gt && gt == gf);
        stop_queries += static_cast<long>(asked.size());
        cap_queries += static_cast<long>(cap_asked.size());
        const double phi = fields[shape].sample(gf).value;
        least = std::min(least, phi - (k.rho - k.skin));
        below += phi < k.rho - k.skin;
        farthest = std::max(farthest, (gf - g_cap).norm());
        apart += (gf - g_cap).norm() > k.push_tol;
      }
    }
  }
  std::printf("%ld updates in the holes: %ld queries with the stalled-slide stop, %ld with the "
              "slides to the cap; %ld differ, least phi - (rho - s) %.3g m; the two rules' g "
              "apart by %.3g m at most, by more than push_tol in %ld\n",
              updates, stop_queries, cap_queries, differ, least, farthest, apart);
  EXPECT_GT(updates, 4000);
  EXPECT_EQ(differ, 0);
  EXPECT_EQ(below, 0);
  EXPECT_LT(stop_queries, cap_queries);
}

// The bur's path: free space, down 1.1 mm into the sphere (drilling), sideways 0.6 mm, away.
constexpr int kFree = 200, kDown = 900, kSideways = 600, kAway = 300;
const Vec3 kTop = kCentre + Vec3(0, 0, kR);
Vec3 bur(int tick) {
  const Vec3 start = kTop + Vec3(0, 0, kRho + 0.2e-3);
  if (tick < kFree) return start + Vec3(0.3e-3, 0, 1e-3) * (1.0 - tick / double(kFree));
  tick -= kFree;
  if (tick < kDown) return start - Vec3(0, 0, 1.1e-3 * tick / kDown);
  tick -= kDown;
  if (tick < kSideways) {
    return start - Vec3(0, 0, 1.1e-3) + Vec3(0.6e-3 * tick / kSideways, 0.1e-3, 0);
  }
  tick -= kSideways;
  return start + Vec3(0.6e-3, 0, 3e-3 * std::min(1.0, tick / 100.0));
}

bool same(const Contact& a, const Contact& b) {
  return a.n == b.n && a.x_o == b.x_o && a.r == b.r && a.depth == b.depth &&
         a.stiffness == b.stiffness && a.damping == b.damping && a.weight == b.weight &&
         a.material == b.material;
}

// ---- The replay of the worker's removals (fast/tooth/cut_set.h ToothBricks) -------------------

// A grid of n^3 voxels, each solid with probability 3/4 (exposed voxels everywhere: at every
// brick boundary and on the grid's faces).
VoxelGrid speckled_grid(int n, std::uint64_t seed) {
  VoxelGrid grid(n, Vec3::Zero(), 1e-4);
  std::mt19937_64 rng(seed);
  for (std::uint8_t& v : grid.voxels) v = rng() % 4 == 0 ? kEmpty : kEnamel;
  return grid;
}

// How many voxels, masks, codes and surface bits of `a` differ from `b`'s.
long tooth_differs(const VoxelTooth& a, const fast::SurfaceVoxels& sa, const VoxelTooth& b,
                   const fast::SurfaceVoxels& sb) {
  const VoxelGrid& g = a.grid();
  long differ = 0;
  for (std::size_t v = 0; v < g.voxels.size(); ++v) {
    differ += a.grid().voxels[v] != b.grid().voxels[v];
    differ += a.codes.code(v) != b.codes.code(v);
  }
  for (std::size_t m = 0; m < a.octree.masks().size(); ++m) {
    differ += a.octree.masks()[m] != b.octree.masks()[m];
  }
  for (int k = 0; k < g.n; ++k) {
    for (int j = 0; j < g.n; ++j) {
      for (int i = 0; i < g.n; ++i) differ += sa.exposed(i, j, k) != sb.exposed(i, j, k);
    }
  }
  return differ;
}

// The field worker's removal copied back (FieldContactProvider::done): a tooth removes random
// batches voxel by voxel as drill_tick does (remove_voxel, reencode_local; its surface bits by
// update()) and ToothBricks::take copies the bricks that changed; a second tooth, equal before,
// applies them. After every batch the second tooth's voxels, every octree mask, every code and
// every bit equal the first's, its masks those rebuilt from its voxels and its codes those
// re-encoded from them; take and apply allocate nothing and leave the marks clear. The batches:
// random voxels, voxels at brick boundaries (a coordinate 7 or 8 mod 8) and on the grid's faces,
// and whole bricks (their node and ancestors' masks emptied), at 4^3 (a grid inside one brick,
// the root's node), 8^3 (one brick) and 32^3.
TEST(ToothBricks, CopiedBackEqualTheRemovalVoxelByVoxel) {
  for (const int n : {4, 8, 32}) {
    const VoxelTooth start(speckled_grid(n, 49 + static_cast<std::uint64_t>(n)));
    VoxelTooth worker = start, servo = start;
    fast::SurfaceVoxels s_worker(worker), s_servo(servo);
    fast::ToothBricks bricks;
    bricks.reserve(worker, 512);
    std::vector<std::uint8_t> marks(worker.codes.slot_count(), 0);
    std::mt19937_64 rng(4900 + static_cast<std::uint64_t>(n));
    std::uniform_int_distribution<int> any(0, n - 1), edge(0, 1);
    const auto boundary = [&] {  // 7 or 8 mod 8 (within the grid), or 0 / n - 1
      const int b = 8 * static_cast<int>(rng() % static_cast<unsigned>(std::max(1, n / 8)));
      const int c = b + 7 + edge(rng);
      return c < n ? c : (edge(rng) == 0 ? 0 : n - 1);
    };
    const std::size_t nn = static_cast<std::size_t>(n);
    long removed = 0, node_batches = 0;
    for (int batch = 0; batch < 60; ++batch) {
      std::vector<int> coords;  // i, j, k triples
      const int kind = batch % 4;
      if (kind == 3) {  // a whole brick
        const int b[3] = {8 * (any(rng) / 8), 8 * (any(rng) / 8), 8 * (any(rng) / 8)};
        for (int k = b[2]; k < std::min(n, b[2] + 8); ++k) {
          for (int j = b[1]; j < std::min(n, b[1] + 8); ++j) {
            for (int i = b[0]; i < std::min(n, b[0] + 8); ++i) {
              coords.insert(coords.end(), {i, j, k});
            }
          }
        }
      } else {
        for (int r = 0; r < 40; ++r) {
          int c[3] = {any(rng), any(rng), any(rng)};
          if (kind >= 1) c[rng() % 3] = boundary();
          if (kind == 2) c[rng() % 3] = boundary();
          coords.insert(coords.end(), {c[0], c[1], c[2]});
        }
      }
      std::vector<std::size_t> gone;
      for (std::size_t q = 0; q < coords.size(); q += 3) {
        const int i = coords[q], j = coords[q + 1], k = coords[q + 2];
        if (worker.octree.remove_voxel(i, j, k) == kEmpty) continue;
        reencode_local(worker.octree.grid(), i, j, k, &worker.codes);
        gone.push_back(worker.grid().index(i, j, k));
      }
      removed += static_cast<long>(gone.size());
      ASSERT_TRUE(s_worker.update(worker, gone));
      {
        testing::AllocationScope scope;
        ASSERT_TRUE(bricks.take(worker, s_worker, gone, marks));
        ASSERT_TRUE(bricks.apply(servo, s_servo));
        EXPECT_EQ(scope.count(), 0);
      }
      EXPECT_EQ(std::count(marks.begin(), marks.end(), 0), static_cast<long>(marks.size()));
      node_batches += kind == 3 && !gone.empty();
      ASSERT_EQ(tooth_differs(servo, s_servo, worker, s_worker), 0) << n << "^3, batch " << batch;
      const FullOctree rebuilt(servo.grid());
      ASSERT_EQ(rebuilt.masks(), servo.octree.masks()) << n << "^3, batch " << batch;
      ASSERT_EQ(encode_neighbors(servo.grid()).code, servo.codes.dense().code)
          << n << "^3, batch " << batch;
    }
    EXPECT_TRUE(s_servo.current());
    EXPECT_GT(removed, static_cast<long>(nn * nn * nn / 8)) << n;
    EXPECT_GT(node_batches, 0);
  }
}

// servo51: ToothBricks::apply copies of a node's voxels only the rows holding a removed voxel
// (FullOctree::load_node_rows): the rows named are the saved node's, every other row keeps its
// bytes (here one the saved tooth lost after the save, so a copy of it would show), and the masks
// are the saved ones; with the rows the removal changed named, the two octrees are equal.
TEST(ToothBricks, ApplyCopiesOnlyTheRowsTheRemovalChanged) {
  const VoxelGrid start = speckled_grid(32, 5100);
  FullOctree worker(start), servo(start);
  const int level = worker.levels() - 3, b[3] = {1, 2, 0};  // brick (1, 2, 0): voxels 8.., 16..
  std::uint64_t rows = 0;
  for (const std::array<int, 3>& c : std::initializer_list<std::array<int, 3>>{
           {8, 16, 0}, {9, 16, 0}, {15, 19, 3}, {12, 23, 7}}) {
    if (worker.remove_voxel(c[0], c[1], c[2]) == kEmpty) continue;
    rows |= std::uint64_t{1} << ((c[1] - 16) + 8 * c[2]);
  }
  ASSERT_NE(rows, 0u);
  std::vector<std::uint8_t> node(worker.node_bytes(level));
  worker.save_node(level, b[0], b[1], b[2], node.data());
  FullOctree later = worker;  // the worker's tooth loses a voxel of a row not named after the save
  int other[3] = {-1, -1, -1};
  for (int k = 0; k < 8 && other[0] < 0; ++k) {
    for (int j = 0; j < 8 && other[0] < 0; ++j) {
      if ((rows >> (j + 8 * k)) & 1) continue;
      for (int i = 0; i < 8 && other[0] < 0; ++i) {
        if (start.at(8 + i, 16 + j, k) == kEmpty) continue;
        other[0] = 8 + i, other[1] = 16 + j, other[2] = k;
      }
    }
  }
  ASSERT_GE(other[0], 0);
  later.remove_voxel(other[0], other[1], other[2]);
  std::vector<std::uint8_t> stale(later.node_bytes(level));
  later.save_node(level, b[0], b[1], b[2], stale.data());
  FullOctree partial = servo;
  partial.load_node_rows(level, b[0], b[1], b[2], stale.data(), rows);
  EXPECT_NE(partial.grid().at(other[0], other[1], other[2]), kEmpty);  // its row not copied
  for (int k = 0; k < 8; ++k) {
    for (int j = 0; j < 8; ++j) {
      const bool named = ((rows >> (j + 8 * k)) & 1) != 0;
      for (int i = 0; i < 8; ++i) {
        const std::uint8_t want =
            named ? later.grid().at(8 + i, 16 + j, k) : start.at(8 + i, 16 + j, k);
        ASSERT_EQ(partial.grid().at(8 + i, 16 + j, k), want) << i << " " << j << " " << k;
      }
    }
  }
  EXPECT_EQ(partial.masks(), later.masks());
  // The node saved right after the removal, its rows: the servo's octree is the worker's.
  servo.load_node_rows(level, b[0], b[1], b[2], node.data(), rows);
  EXPECT_EQ(servo.grid().voxels, worker.grid().voxels);
  EXPECT_EQ(servo.masks(), worker.masks());
  EXPECT_EQ(servo.masks(), FullOctree(worker.grid()).masks());
}

// The batch's bound: a removal whose changed bricks exceed the capacity is refused (fits() false,
// no brick held, the marks clear, nothing allocated) and the servo replays it voxel by voxel
// (SurfaceVoxels::remove); one that fits exactly is taken.
TEST(ToothBricks, ARemovalBeyondTheCapacityIsRefusedWithoutAllocating) {
  VoxelGrid solid = speckled_grid(32, 7);
  std::fill(solid.voxels.begin(), solid.voxels.end(), kEnamel);
  const VoxelTooth start(solid);
  VoxelTooth worker = start, servo = start;
  fast::SurfaceVoxels s_worker(worker), s_servo(servo);
  fast::ToothBricks bricks;
  bricks.reserve(worker, 2);
  EXPECT_EQ(bricks.capacity(), 2u);
  std::vector<std::uint8_t> marks(worker.codes.slot_count(), 0);
  const auto remove = [&](std::initializer_list<std::array<int, 3>> voxels) {
    std::vector<std::size_t> gone;
    for (const auto& c : voxels) {
      if (worker.octree.remove_voxel(c[0], c[1], c[2]) == kEmpty) continue;
      reencode_local(worker.octree.grid(), c[0], c[1], c[2], &worker.codes);
      gone.push_back(worker.grid().index(c[0], c[1], c[2]));
    }
    EXPECT_TRUE(s_worker.update(worker, gone));
    return gone;
  };
  // Voxels inside bricks 0 and 1 along x of the solid grid (no face neighbour in another brick).
  const std::vector<std::size_t> two = remove({{3, 3, 3}, {4, 4, 4}, {11, 3, 3}, {12, 5, 4}});
  ASSERT_FALSE(two.empty());
  {
    testing::AllocationScope scope;
    EXPECT_TRUE(bricks.take(worker, s_worker, two, marks));
    EXPECT_EQ(bricks.size(), 2u);
    EXPECT_TRUE(bricks.apply(servo, s_servo));
    EXPECT_EQ(scope.count(), 0);
  }
  EXPECT_EQ(tooth_differs(servo, s_servo, worker, s_worker), 0);
  // Three bricks (one more along z), then a voxel at a corner of four.
  const std::vector<std::size_t> three = remove({{2, 2, 2}, {10, 2, 2}, {2, 2, 20}, {7, 7, 4}});
  ASSERT_FALSE(three.empty());
  {
    testing::AllocationScope scope;
    EXPECT_FALSE(bricks.take(worker, s_worker, three, marks));
    EXPECT_FALSE(bricks.fits());
    EXPECT_EQ(bricks.size(), 0u);
    EXPECT_EQ(std::count(marks.begin(), marks.end(), 0), static_cast<long>(marks.size()));
    EXPECT_TRUE(s_servo.remove(servo, three));  // the servo's replay, voxel by voxel
    EXPECT_EQ(scope.count(), 0);
  }
  EXPECT_EQ(tooth_differs(servo, s_servo, worker, s_worker), 0);
  EXPECT_EQ(servo.octree.masks(), worker.octree.masks());
}


// latency 0: the budget path on the servo thread (both providers); L > 0: the reference's
// synchronous edit at latency L against the fast provider's worker thread, with the reference
// field and the fast provider's published bricks compared at every sample every
// kCompareEvery ticks (the servo's view, while the worker may be editing the next batches).
// `worker` (L > 0): kRuns, the worker runs as it may (the servo takes over the batches it has
// not started when they are due); kHeld, the worker never claims a batch (the servo does every
// one: all takeovers); kMixed, held for kMixedSpan ticks, then let go for kMixedSpan ticks and
// waited for after each drilling tick (it does those ticks' batches), and so on: both kinds.
enum class Worker { kRuns, kHeld, kMixed };
constexpr int kCompareEvery = 250;
constexpr int kMixedSpan = 7;
void provider_equals_the_reference(int stride, int latency = 0, Worker worker = Worker::kRuns) {
  const VoxelGrid g = sphere_grid();
  VoxelTooth tooth_r(g), tooth_f(g);
  SampledField field_r = sphere_field(g, stride);
  SampledField field_f = field_r;
  DrillParams drill;
  drill.cutting_coefficient = 10.0;  // cuts fast: hundreds of voxels on this path
  const ToolTip tip{kRho, Vec3::Zero()};
  ToothContactProvider reference(tooth_r, tip, kK, kB, &drill, ContactModel::kField,
                                 &signed_distance, &field_r);
  PipelineToothSetup setup;
  setup.tip = tip;
  setup.k_tooth = kK;
  setup.b_tooth = kB;
  setup.drilling = &drill;
  setup.contact_model = ContactModel::kField;
  setup.field = &field_f;
  setup.field_edit_latency = latency;
  if (latency > 0) reference.set_field_edit_latency(latency);
  fast::FieldContactProvider fast_provider(tooth_f, setup);
  ASSERT_EQ(fast_provider.worker() != nullptr, latency > 0);
  if (worker == Worker::kHeld) fast_provider.worker()->hold(true);
  const int m = field_r.samples_per_axis();
  // How many samples of the fast provider's published bricks differ from the reference field's.
  const auto published_differ = [&] {
    long differ = 0;
    for (int z = 0; z < m; ++z) {
      for (int y = 0; y < m; ++y) {
        for (int x = 0; x < m; ++x) {
          differ += fast_provider.bricks().at(x, y, z) != field_r.at(x, y, z);
        }
      }
    }
    return differ;
  };
  int compared = 0;
  std::vector<Contact> out_r, out_f;
  out_r.reserve(kContactCapacity);
  out_f.reserve(kContactCapacity);
  long contact_ticks = 0, removed = 0, allocations = 0, batches = 0;
  const int ticks = kFree + kDown + kSideways + kAway;
  {
    testing::AllocationScope scope;
    for (int tick = 0; tick < ticks; ++tick) {
      const bool held = worker == Worker::kMixed && (tick / kMixedSpan) % 2 == 0;
      if (worker == Worker::kMixed) fast_provider.worker()->hold(held);
      Pose pose;
      pose.x = bur(tick);
      const bool ok_r = reference.contacts(pose, out_r);
      // The stand-in's clock (FieldEditWorker::publish) is read inside contacts() and only on a
      // takeover or a wait: a tick without either adds no time, one with them no more than the
      // whole call took.
      const long stood_in = fast_provider.field_edit_servo_takeovers() +
                            fast_provider.field_edit_worker_waits();
      const long stand_in_ns = fast_provider.field_edit_stand_in_ns();
      const auto call_start = std::chrono::steady_clock::now();
      const bool ok_f = fast_provider.contacts(pose, out_f);
      const long call_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                               std::chrono::steady_clock::now() - call_start)
                               .count();
      const long tick_ns = fast_provider.field_edit_stand_in_ns() - stand_in_ns;
      if (fast_provider.field_edit_servo_takeovers() + fast_provider.field_edit_worker_waits() ==
          stood_in) {
        ASSERT_EQ(tick_ns, 0) << "tick " << tick;
      }
      ASSERT_GE(tick_ns, 0) << "tick " << tick;
      ASSERT_LE(tick_ns, call_ns) << "tick " << tick;
      ASSERT_EQ(ok_r, ok_f);
      ASSERT_EQ(out_r.size(), out_f.size()) << "tick " << tick;
      for (std::size_t i = 0; i < out_r.size(); ++i) {
        ASSERT_TRUE(same(out_r[i], out_f[i])) << "tick " << tick;
      }
      ASSERT_EQ(reference.surface_proxy().g(), fast_provider.surface_proxy().g()) << tick;
      ASSERT_EQ(reference.anchored_spring().held, fast_provider.anchored_spring().held) << tick;
      const int rr = reference.drill(out_r, kT);
      ASSERT_EQ(rr, fast_provider.drill(out_f, kT)) << "tick " << tick;
      contact_ticks += out_r.empty() ? 0 : 1;
      removed += rr;
      batches += out_r.empty() ? 0 : 1;  // a cut handed over (drill() in contact)
      if (worker == Worker::kMixed && !held) fast_provider.worker()->wait_until_done();
      if (latency > 0 && tick % kCompareEvery == kCompareEvery - 1) {
        ASSERT_EQ(published_differ(), 0) << "tick " << tick;
        ASSERT_EQ(fast_provider.bricks().lipschitz(), field_r.lipschitz()) << "tick " << tick;
        ++compared;
      }
    }
    // Away until both fields have followed every cut (L more ticks at a latency).
    Pose away;
    away.x = kTop + Vec3(0, 0, 4e-3);
    for (int k = 0; k < latency || reference.field_edits_pending() > 0; ++k) {
      reference.contacts(away, out_r);
      fast_provider.contacts(away, out_f);
    }
    allocations = scope.count();
  }
  EXPECT_EQ(fast_provider.field_edits_pending(), 0u);
  std::printf("%d ticks, %ld in contact, %ld voxels removed, %ld edits, %ld samples scanned, "
              "%ld queried, %ld raised, %ld queries certified, %ld evaluated, %ld allocations\n",
              ticks, contact_ticks, removed, reference.field_edits().voxels,
              reference.field_edits().samples_scanned, reference.field_edits().samples_queried,
              reference.field_edits().samples_raised, fast_provider.solid().certified(),
              fast_provider.solid().evaluated(), allocations);
  EXPECT_GT(contact_ticks, 500);
  EXPECT_GT(removed, 100);
  const FieldEditStats& a = reference.field_edits();
  const FieldEditStats& b = fast_provider.field_edits();
  EXPECT_EQ(a.voxels, b.voxels);
  EXPECT_EQ(a.samples_scanned, b.samples_scanned);
  EXPECT_EQ(a.samples_queried, b.samples_queried);
  EXPECT_EQ(a.samples_raised, b.samples_raised);
  EXPECT_EQ(a.samples_lost, b.samples_lost);
  EXPECT_EQ(a.rows_read, b.rows_read);
  EXPECT_EQ(a.cells_measured, b.cells_measured);
  EXPECT_EQ(a.work, b.work);
  EXPECT_GT(a.samples_raised, 0);
  EXPECT_EQ(reference.field_edit_shortfalls(), fast_provider.field_edit_shortfalls());
  EXPECT_EQ(reference.field_edit_shortfalls(), 0);
  EXPECT_EQ(reference.field_edit_late_publishes(), 0);
  EXPECT_EQ(fast_provider.field_edit_late_publishes(), 0);  // simulation: waited for
  EXPECT_EQ(reference.field_edit_servo_takeovers(), 0);
  if (latency > 0) {
    // Exactly once: each batch edited by one thread (and its edit counted once: the counts above
    // equal the reference's).
    const long takeovers = fast_provider.field_edit_servo_takeovers();
    const long by_worker = fast_provider.worker()->worker_batches();
    std::printf("%ld batches: %ld edited by the worker, %ld taken over by the servo\n", batches,
                by_worker, takeovers);
    EXPECT_EQ(takeovers + by_worker, batches);
    if (worker == Worker::kHeld) {
      EXPECT_EQ(takeovers, batches);
      EXPECT_EQ(fast_provider.field_edit_worker_waits(), 0);  // the worker never claims one
    }
    // Each takeover's edit and each wait was timed (a clock read before and after).
    if (takeovers + fast_provider.field_edit_worker_waits() > 0) {
      EXPECT_GT(fast_provider.field_edit_stand_in_ns(), 0);
    }
    if (worker == Worker::kMixed) {
      EXPECT_GT(takeovers, 0);
      EXPECT_GT(by_worker, 0);
    }
  } else {
    EXPECT_EQ(fast_provider.field_edit_servo_takeovers(), 0);
    EXPECT_EQ(fast_provider.field_edit_worker_waits(), 0);
    EXPECT_EQ(fast_provider.field_edit_stand_in_ns(), 0);  // no worker: nothing stood in for
  }
  EXPECT_EQ(reference.field_edit_stand_in_ns(), 0);  // the specification's publish: no stand-in
  EXPECT_EQ(compared, latency > 0 ? ticks / kCompareEvery : 0);
  EXPECT_EQ(fast_provider.bricks().lipschitz(), field_r.lipschitz());
  long differ = 0;
  for (int z = 0; z < m; ++z) {
    for (int y = 0; y < m; ++y) {
      for (int x = 0; x < m; ++x) {
        differ += field_f.at(x, y, z) != field_r.at(x, y, z);
        differ += fast_provider.bricks().at(x, y, z) != field_r.at(x, y, z);
      }
    }
  }
  EXPECT_EQ(differ, 0);
  EXPECT_EQ(tooth_r.grid().voxels, tooth_f.grid().voxels);
  // The servo's tooth took the worker's bricks (ToothBricks): its octree, codes and surface bits
  // are the reference's removal's.
  EXPECT_EQ(tooth_r.octree.masks(), tooth_f.octree.masks());
  EXPECT_EQ(tooth_r.codes.dense().code, tooth_f.codes.dense().code);
  long bits_wrong = 0;
  for (int k = 0; k < g.n; ++k) {
    for (int j = 0; j < g.n; ++j) {
      for (int i = 0; i < g.n; ++i) {
        bits_wrong += fast_provider.cut_set().surface().exposed(i, j, k) !=
                      (tooth_r.codes.code(g.index(i, j, k)) != 0);
      }
    }
  }
  EXPECT_EQ(bits_wrong, 0);
  EXPECT_EQ(fast_provider.replay_shortfalls(), 0);
  EXPECT_GT(fast_provider.solid().certified(), kFree);  // free space read no sample
  const fast::VoxelDistanceCache& cache = fast_provider.distance_cache();
  std::printf("edit queries: %ld answered by the kept distances, %ld asked; %ld rows read, %ld "
              "cells re-measured, %ld units of work (field_contact.h)\n",
              cache.hits(), cache.misses(), b.rows_read, b.cells_measured, b.work);
  EXPECT_GT(cache.hits(), 0);
  EXPECT_EQ(a.samples_bounded, b.samples_bounded);
  EXPECT_EQ(cache.hits() + cache.misses(), b.samples_queried - b.samples_bounded);
  EXPECT_EQ(allocations, 0);
}
TEST(FastFieldProvider, EqualsTheReferenceProviderWhileDrillingEditsTheField) {
  provider_equals_the_reference(1);
}
// The edit at a fixed latency (reference/tooth/tooth_contacts.h set_field_edit_latency): the
// fast provider's worker thread against the reference's synchronous edit at the same L, the
// published bricks equal to the reference field at every sample every 250 ticks, every tick's
// contact and g bitwise equal, no allocation on either thread.
TEST(FastFieldProvider, TheWorkerAtLatencyLEqualsTheReferenceEditAtL) {
  provider_equals_the_reference(1, ToothContactProvider::kFieldEditLatency);
}
TEST(FastFieldProvider, TheWorkerAtLatencyLEqualsTheReferenceEditAtLAtStride2) {
  provider_equals_the_reference(2, ToothContactProvider::kFieldEditLatency);
}
TEST(FastFieldProvider, TheWorkerAtLatency5EqualsTheReferenceEditAt5) {
  provider_equals_the_reference(1, 5);
}
// The servo takes over a late batch (fast/tooth/field.h FieldEditWorker::publish): the worker
// held back, the servo edits every batch at its tick t + L itself; and a mix of the servo's and
// the worker's batches. Every tick's contact, g and removed voxels, the published bricks and the
// final field bitwise the reference's, each batch edited once, no allocation on either thread.
TEST(FastFieldProvider, TheServoTakingOverEveryBatchEqualsTheReferenceEditAtL) {
  provider_equals_the_reference(1, ToothContactProvider::kFieldEditLatency, Worker::kHeld);
}
TEST(FastFieldProvider, TheServoTakingOverEveryBatchEqualsTheReferenceEditAt5) {
  provider_equals_the_reference(1, 5, Worker::kHeld);
}
TEST(FastFieldProvider, TakeoversMixedWithWorkerBatchesEqualTheReferenceEditAtL) {
  provider_equals_the_reference(1, ToothContactProvider::kFieldEditLatency, Worker::kMixed);
}
TEST(FastFieldProvider, TakeoversMixedWithWorkerBatchesEqualTheReferenceEditAt5) {
  provider_equals_the_reference(1, 5, Worker::kMixed);
}
TEST(FastFieldProvider, TakeoversMixedWithWorkerBatchesEqualTheReferenceAtStride2) {
  provider_equals_the_reference(2, ToothContactProvider::kFieldEditLatency, Worker::kMixed);
}
// How the servo hands a cut to the worker (fast/tooth/field.h FieldEditWorker): the worker watches
// for the next cut for its spin window before it parks, and submit() wakes it only when it has
// parked. With a window longer than the test the worker never parks, and no hand-over pays a wake;
// with none, every hand-over to the parked worker wakes it exactly once, and the worker does the
// batch (a lost wake would leave wait_until_done() blocked: the test would time out).
TEST(FastFieldWorker, TheServoWakesTheWorkerOnlyWhenItHasParked) {
  const VoxelGrid g = sphere_grid();
  const VoxelTooth tooth(g);
  const SampledField field0 = sphere_field(g);
  DrillParams drill;
  drill.cutting_coefficient = 10.0;
  const ToolTip tip{kRho, Vec3::Zero()};
  // Cuts far outside the tooth (nothing to remove: the hand-over alone).
  FieldDrillCut cut;
  cut.g = kCentre + Vec3(0, 0, 2 * kR);
  cut.T = kT;
  constexpr int kCuts = 40;
  for (const std::chrono::nanoseconds spin :
       {std::chrono::nanoseconds(0), std::chrono::nanoseconds(std::chrono::hours(1))}) {
    SampledField field = field0;
    fast::FieldBricks bricks(field, 0);
    fast::FieldEditWorker worker(&field, &bricks, tooth, ToothContactProvider::kFieldEditLatency,
                                 false, ToothContactProvider::kFieldEditQueue, tip, drill,
                                 make_drill_state(tooth), spin);
    for (int k = 0; k < kCuts; ++k) {
      if (spin.count() == 0) {
        while (!worker.parked()) std::this_thread::yield();  // parks as soon as it is idle
      }
      const long before = worker.wakes();
      cut.tick = k;
      ASSERT_TRUE(worker.submit(cut, ToothContactProvider::kFieldEditQueue)) << k;
      EXPECT_EQ(worker.wakes() - before, spin.count() == 0 ? 1 : 0) << k;
      worker.wait_until_done();
    }
    EXPECT_EQ(worker.worker_batches(), kCuts);  // every batch the worker's (none published)
    EXPECT_EQ(worker.wakes(), spin.count() == 0 ? kCuts : 0);
    if (spin.count() > 0) {
      EXPECT_FALSE(worker.parked());
    }
  }
}
// The same at stride 2 (a sample at every other voxel centre): the edit at stride k (reference/
// tooth/field_edit_core.h) is one code for both twins, so the twins agree bit for bit again.
TEST(FastFieldProvider, EqualsTheReferenceProviderWhileDrillingEditsTheFieldAtStride2) {
  provider_equals_the_reference(2);
}

}  // namespace
}  // namespace dentsim
