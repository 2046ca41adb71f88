// The field of a scan (tooth_io/tooth_field.h: build_volume_field, scan_surface; issue #30):
// synthetic partial-volume scans of a ball and of a box (each sample = the fraction of its own box
// inside the shape times the material's intensity, on a coarse lattice), their voxel tooth and
// field. The field's zero level lies within the derived bound of the true surface along many rays
// (against the voxel staircase's up to h / 2), its sign is the grid's at every voxel centre and
// the truth's away from the surface, islands the grid drops have no surface, its Lipschitz
// constant is within docs/derivations/field_contact.md §2's sqrt(3), and bad input is an
// InputError naming the scan.
//
// The bound (docs/derivations/field_contact.md §1 "scan"), with D the scan spacing and h the
// grid's voxel size:
//  - the iso-surface of the trilinear intensity at half the material's intensity: on a face
//    normal to a scan axis, the samples across it are a ramp one D wide (0, u, 1 times the
//    intensity, u in (0, 1)), and linear interpolation between u and its neighbour crosses 1/2 at
//    D (u - 1/2) / u from the sample where the face is at D (u - 1/2): an error of
//    D (u - 1/2)(1 - u) / u, largest at u = 1/sqrt 2: (3/2 - sqrt 2) D = 0.0858 D;
//  - on the ball (radius R), to first order in D / R: the half level of the box-averaged ball
//    lies inside the sphere by E|U_t|^2 / (2 R) <= D^2 / (8 R) (U uniform in the sample's box,
//    U_t its part along the tangent plane), and the trilinear interpolation of the distance to
//    the centre overshoots it by at most (D^2 / 8) trace(Hessian |x|) = D^2 / (4 R);
//  - the triangles' chord and the field's interpolation of the distance to them: 3 h^2 / (4 (R -
//    c_in)) (the implicit sphere's bound, tests/tooth/sampled_field_test.cc); zero on a flat face.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "reference/core/io.h"
#include "reference/tooth/sampled_field.h"
#include "tests/support/input_error.h"
#include "tooth_io/tooth_field.h"
#include "tooth_io/volume.h"

namespace dentsim {
namespace {

using ::testing::HasSubstr;
using testing::input_error_of;

constexpr double kIntensity = 1000.0;  // the material; background 0
const double kFlatBound = 1.5 - std::sqrt(2.0);  // x D: the ramp's interpolation (header)

// Thresholds with the solid/background level at half the material's intensity (the partial-
// volume midpoint), no enamel in the scan.
VolumeToothOptions half_level_options(int resolution) {
  VolumeToothOptions o;
  o.resolution = resolution;
  o.automatic_thresholds = false;
  o.thresholds = parse_material_thresholds("dentin=500:1500,enamel=1600:3000", "test");
  return o;
}

// An axis-aligned lattice of spacing d over [lo, hi] (shifted by a fraction of d, so that no
// surface sits on a sample), each sample fraction(sample centre) * kIntensity.
template <class Fraction>
ScanVolume render(const Vec3& lo, const Vec3& hi, double d, Fraction fraction) {
  ScanVolume v;
  v.spacing = Vec3::Constant(d);
  v.origin = lo + d * Vec3(0.371, 0.219, 0.143);
  for (int a = 0; a < 3; ++a) v.dims[a] = static_cast<int>(std::ceil((hi[a] - lo[a]) / d)) + 1;
  v.values.resize(static_cast<std::size_t>(v.dims[0]) * v.dims[1] * v.dims[2]);
  for (int k = 0; k < v.dims[2]; ++k) {
    for (int j = 0; j < v.dims[1]; ++j) {
      for (int i = 0; i < v.dims[0]; ++i) {
        v.values[v.index(i, j, k)] =
            static_cast<float>(kIntensity * fraction(v.position(Vec3(i, j, k))));
      }
    }
  }
  v.format = "memory";
  v.source = "synthetic.nii";
  return v;
}

// Fraction of the cube of side d centred at p inside the ball (c, r): exact 0 or 1 when the cube
// is wholly out or in; else 64 x 64 columns along the axis nearest the ball's normal at p (away
// from the ball's silhouette), each column's chord exact.
double ball_fraction(const Vec3& p, double d, const Vec3& c, double r) {
  const Vec3 q = p - c;
  const Vec3 nearest = (q.cwiseAbs() - Vec3::Constant(0.5 * d)).cwiseMax(0.0);
  const Vec3 farthest = q.cwiseAbs() + Vec3::Constant(0.5 * d);
  if (nearest.norm() >= r) return 0.0;
  if (farthest.norm() <= r) return 1.0;
  int a = 0;
  q.cwiseAbs().maxCoeff(&a);
  const int b = (a + 1) % 3, e = (a + 2) % 3;
  constexpr int m = 64;
  double sum = 0.0;
  for (int ib = 0; ib < m; ++ib) {
    for (int ie = 0; ie < m; ++ie) {
      const double ub = q[b] + d * ((ib + 0.5) / m - 0.5), ue = q[e] + d * ((ie + 0.5) / m - 0.5);
      const double rho2 = ub * ub + ue * ue;
      if (rho2 >= r * r) continue;
      const double s = std::sqrt(r * r - rho2);
      sum += std::max(0.0, std::min(s, q[a] + 0.5 * d) - std::max(-s, q[a] - 0.5 * d));
    }
  }
  return sum / (static_cast<double>(m) * m * d);
}

// The zero of phi along x(t) = o + t u, t in [t0, t1] (phi(x(t0)) < 0 < phi(x(t1))), by bisection.
double zero_along(const SampledField& f, const Vec3& o, const Vec3& u, double t0, double t1) {
  EXPECT_LT(f.value(o + t0 * u), 0.0);
  EXPECT_GT(f.value(o + t1 * u), 0.0);
  for (int it = 0; it < 60; ++it) {
    const double t = 0.5 * (t0 + t1);
    (f.value(o + t * u) < 0.0 ? t0 : t1) = t;
  }
  return 0.5 * (t0 + t1);
}

// The voxel staircase along the same ray: the largest t in [t0, t1] (steps of h / 256) whose point
// lies in a solid voxel.
double staircase_along(const VoxelGrid& g, const Vec3& o, const Vec3& u, double t0, double t1) {
  const double step = g.voxel_size / 256.0;
  for (double t = t1; t >= t0; t -= step) {
    const Vec3 x = (o + t * u - g.origin) / g.voxel_size;
    if (g.solid(static_cast<int>(std::floor(x[0])), static_cast<int>(std::floor(x[1])),
                static_cast<int>(std::floor(x[2])))) {
      return t;
    }
  }
  return t0;
}

struct Errors {
  double field_max = 0, field_rms = 0, voxel_max = 0, voxel_rms = 0;
  int rays = 0;
  void add(double field, double voxel) {
    field_max = std::max(field_max, std::abs(field));
    voxel_max = std::max(voxel_max, std::abs(voxel));
    field_rms += field * field;
    voxel_rms += voxel * voxel;
    ++rays;
  }
  void finish() {
    field_rms = std::sqrt(field_rms / rays);
    voxel_rms = std::sqrt(voxel_rms / rays);
  }
};

// Every voxel centre: the field's sign is the grid's; where the true signed distance `truth` is
// beyond `margin`, both are the truth's. Returns the voxels checked against the truth.
template <class Truth>
long check_signs(const SampledField& f, const VoxelGrid& g, Truth truth, double margin) {
  long against_truth = 0, wrong_field = 0, wrong_grid = 0;
  for (int k = 0; k < g.n; ++k) {
    for (int j = 0; j < g.n; ++j) {
      for (int i = 0; i < g.n; ++i) {
        const Vec3 p = g.center(i, j, k);
        wrong_field += (f.value(p) < 0.0) != g.solid(i, j, k);
        const double t = truth(p);
        if (std::abs(t) <= margin) continue;
        ++against_truth;
        wrong_grid += (t < 0.0) != g.solid(i, j, k);
      }
    }
  }
  EXPECT_EQ(wrong_field, 0);
  EXPECT_EQ(wrong_grid, 0);
  return against_truth;
}

// A ball of radius 2 mm scanned at D (0.2 mm on a 32^3 grid, 0.1 mm on 64^3), with a speckle of
// 2 x 2 x 2 bright samples 0.6 mm off it (an island the grid drops).
void check_ball(double d, int resolution) {
  const Vec3 c(1.03e-3, -0.47e-3, 0.29e-3);
  const double r = 2e-3;
  ScanVolume v = render(c - Vec3::Constant(3e-3), c + Vec3::Constant(3e-3), d,
                        [&](const Vec3& p) { return ball_fraction(p, d, c, r); });
  const Vec3 speckle = c + Vec3::Constant(1.5e-3);
  const Vec3 s0 = ((speckle - v.origin) / d).array().floor().matrix();
  for (int o = 0; o < 8; ++o) {
    v.values[v.index(static_cast<int>(s0[0]) + (o & 1), static_cast<int>(s0[1]) + ((o >> 1) & 1),
                     static_cast<int>(s0[2]) + (o >> 2))] = static_cast<float>(kIntensity);
  }
  const VolumeToothOptions opt = half_level_options(resolution);
  VolumeToothReport rep;
  VoxelGrid grid = build_volume_tooth(v, opt, &rep);
  EXPECT_GT(rep.island_voxels, 0);  // the speckle's voxels, dropped
  const double h = grid.voxel_size;
  // The field as the simulator builds it: on the grid moved by an offset.
  const Vec3 offset(0.013, -0.002, 0.021);
  grid.origin += offset;
  ScanSurfaceStats stats;
  const SampledField f =
      build_volume_field(v, opt, grid, offset, field_band_for_tip(0.4e-3, h), &stats);
  const Vec3 centre = c + offset;
  EXPECT_GT(stats.edges, 1000);
  EXPECT_EQ(stats.midpoint, 0);  // every vertex on the iso-surface itself

  const double iso_bound = kFlatBound * d + 3.0 * d * d / (8.0 * r);
  const double bound = iso_bound + 3.0 * h * h / (4.0 * (r - f.inside_clamp())) + 1e-9;
  ASSERT_LT(bound, 0.5 * h);  // below the staircase's
  std::mt19937_64 rng(77);
  std::normal_distribution<double> g(0.0, 1.0);
  Errors e;
  for (int ray = 0; ray < 2000; ++ray) {
    const Vec3 u = Vec3(g(rng), g(rng), g(rng)).normalized();
    const double field = zero_along(f, centre, u, r - 2.0 * h, r + 2.0 * h) - r;
    const double voxel = staircase_along(grid, centre, u, r - 2.0 * h, r + 2.0 * h) - r;
    e.add(field, voxel);
    ASSERT_LE(std::abs(field), bound) << "ray " << u.transpose();
  }
  e.finish();
  std::printf("ball r = 2 mm, scan %.2f mm, %d^3 (h = %.4f mm): zero level - sphere: field max "
              "%.4f rms %.4f mm (bound %.4f), voxels max %.4f rms %.4f mm; %ld surface edges\n",
              d * 1e3, resolution, h * 1e3, e.field_max * 1e3, e.field_rms * 1e3, bound * 1e3,
              e.voxel_max * 1e3, e.voxel_rms * 1e3, stats.edges);

  const long checked = check_signs(
      f, grid, [&](const Vec3& p) { return (p - centre).norm() - r; }, iso_bound);
  EXPECT_GT(checked, grid.n * grid.n * grid.n / 2);
  // The island has no surface: phi there is the distance to the ball (clamped).
  EXPECT_GT(f.value(speckle + offset), 0.5e-3);
  EXPECT_GE(f.lipschitz(), 1.0 - 1e-6);
  EXPECT_LE(f.lipschitz(), std::sqrt(3.0) + 1e-6);
  std::printf("  Lipschitz %.4f\n", f.lipschitz());
}

TEST(VolumeField, BallZeroLevelWithinTheBoundAtTwoScanSpacings) {
  check_ball(0.2e-3, 32);
  check_ball(0.1e-3, 64);
}

// A box 3.2 x 2.5 x 2.5 mm (faces off the samples) scanned at 0.2 mm, 32^3: on each face, two
// scan spacings and two voxels from its edges, the field's zero is within (3/2 - sqrt 2) D of the
// face (the iso-surface is that plane there, and the triangles and the field reproduce a plane).
TEST(VolumeField, BoxFacesWithinTheRampBound) {
  const double d = 0.2e-3;
  const Vec3 lo(-1.7e-3, -1.3e-3, -1.1e-3), hi(1.5e-3, 1.2e-3, 1.4e-3);
  const auto overlap = [](double a0, double a1, double b0, double b1) {
    return std::max(0.0, std::min(a1, b1) - std::max(a0, b0));
  };
  const ScanVolume v =
      render(lo - Vec3::Constant(1e-3), hi + Vec3::Constant(1e-3), d, [&](const Vec3& p) {
        double frac = 1.0;
        for (int a = 0; a < 3; ++a) frac *= overlap(p[a] - 0.5 * d, p[a] + 0.5 * d, lo[a], hi[a]) / d;
        return frac;
      });
  const VolumeToothOptions opt = half_level_options(32);
  const VoxelGrid grid = build_volume_tooth(v, opt);
  const double h = grid.voxel_size;
  ScanSurfaceStats stats;
  const SampledField f =
      build_volume_field(v, opt, grid, Vec3::Zero(), field_band_for_tip(0.4e-3, h), &stats);
  EXPECT_EQ(stats.midpoint, 0);
  const double bound = kFlatBound * d + 1e-9;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Errors e;
  const double keep_off = 2.0 * d + 2.0 * h;  // from the face's edges
  for (int face = 0; face < 6; ++face) {
    const int a = face / 2, b = (a + 1) % 3, c = (a + 2) % 3;
    Vec3 u = Vec3::Zero();
    u[a] = face % 2 == 0 ? -1.0 : 1.0;
    const double plane = face % 2 == 0 ? lo[a] : hi[a];
    for (int ray = 0; ray < 300; ++ray) {
      Vec3 o = Vec3::Zero();
      o[a] = plane;
      o[b] = lo[b] + keep_off + unit(rng) * (hi[b] - lo[b] - 2.0 * keep_off);
      o[c] = lo[c] + keep_off + unit(rng) * (hi[c] - lo[c] - 2.0 * keep_off);
      const double field = zero_along(f, o, u, -2.0 * h, 2.0 * h);
      const double voxel = staircase_along(grid, o, u, -2.0 * h, 2.0 * h);
      e.add(field, voxel);
      ASSERT_LE(std::abs(field), bound) << "face " << face << " at " << o.transpose();
    }
  }
  e.finish();
  std::printf("box, scan 0.20 mm, 32^3 (h = %.4f mm): zero level - face: field max %.4f rms %.4f "
              "mm (bound %.4f), voxels max %.4f rms %.4f mm\n",
              h * 1e3, e.field_max * 1e3, e.field_rms * 1e3, bound * 1e3, e.voxel_max * 1e3,
              e.voxel_rms * 1e3);
  // Signs: the truth's wherever a centre is 1.5 D from the box's surface (beyond the ramp and
  // its interpolation, so the edges' and corners' rounding too).
  const auto truth = [&](const Vec3& p) {
    const Vec3 out = (lo - p).cwiseMax(p - hi);
    return out.maxCoeff() <= 0.0 ? out.maxCoeff() : out.cwiseMax(0.0).norm();
  };
  EXPECT_GT(check_signs(f, grid, truth, 1.5 * d), grid.n * grid.n * grid.n / 3);
  EXPECT_GE(f.lipschitz(), 1.0 - 1e-6);
  EXPECT_LE(f.lipschitz(), std::sqrt(3.0) + 1e-6);
}

// Bad input: an InputError naming the scan (or the volume's degenerate shape), never a crash.
TEST(VolumeField, BadInputNamesTheScan) {
  const double d = 0.2e-3;
  const Vec3 c = Vec3::Zero();
  const ScanVolume ball = render(Vec3::Constant(-2e-3), Vec3::Constant(2e-3), d,
                                 [&](const Vec3& p) { return ball_fraction(p, d, c, 1.2e-3); });
  const VolumeToothOptions opt = half_level_options(32);
  const VoxelGrid grid = build_volume_tooth(ball, opt);
  const FieldBand band = field_band_for_tip(0.4e-3, grid.voxel_size);
  const auto field_error = [&](const ScanVolume& v, const VolumeToothOptions& o,
                               const VoxelGrid& g) {
    return input_error_of([&] { build_volume_field(v, o, g, Vec3::Zero(), band); });
  };
  // Empty solid: every sample background.
  ScanVolume empty = ball;
  std::fill(empty.values.begin(), empty.values.end(), 0.0f);
  EXPECT_THAT(field_error(empty, opt, grid),
              HasSubstr("synthetic.nii: no sample lies in the enamel or dentin range"));
  VolumeToothOptions automatic = opt;
  automatic.automatic_thresholds = true;
  EXPECT_THAT(field_error(empty, automatic, grid), HasSubstr("synthetic.nii: volume is uniform"));
  // Thresholds above the scan's intensities; at or below its lowest (every sample solid).
  VolumeToothOptions above = opt;
  above.thresholds = parse_material_thresholds("dentin=5000:6000,enamel=7000:8000", "test");
  EXPECT_THAT(field_error(ball, above, grid), HasSubstr("synthetic.nii: no sample lies"));
  VolumeToothOptions below = opt;
  below.thresholds = parse_material_thresholds("dentin=-10:1500,enamel=1600:3000", "test");
  EXPECT_THAT(field_error(ball, below, build_volume_tooth(ball, below)),
              HasSubstr("synthetic.nii: no sample is background"));
  // A range only the brightest sample reaches: solid samples, but no solid voxel centre (the
  // trilinear intensity is below the sample's between the samples).
  ScanVolume spike = ball;
  std::fill(spike.values.begin(), spike.values.end(), 0.0f);
  spike.values[spike.index(10, 10, 10)] = 1000.0f;
  VolumeToothOptions exact = opt;
  exact.thresholds = parse_material_thresholds("dentin=1000:1000,enamel=1600:3000", "test");
  EXPECT_THAT(field_error(spike, exact, build_volume_tooth(spike, exact)),
              HasSubstr("synthetic.nii: no voxel of the resampled tooth is solid"));
  // Degenerate volumes.
  ScanVolume flat = ball;
  flat.dims[2] = 1;
  flat.values.resize(static_cast<std::size_t>(flat.dims[0]) * flat.dims[1]);
  EXPECT_THAT(field_error(flat, opt, grid), HasSubstr("synthetic.nii: size 1 along axis 2"));
  ScanVolume short_of_samples = ball;
  short_of_samples.values.pop_back();
  EXPECT_THAT(field_error(short_of_samples, opt, grid), HasSubstr("synthetic.nii: "));
  EXPECT_THAT(field_error(short_of_samples, opt, grid), HasSubstr("samples for a"));
  ScanVolume no_spacing = ball;
  no_spacing.spacing[1] = 0.0;
  EXPECT_THAT(field_error(no_spacing, opt, grid), HasSubstr("synthetic.nii: spacing 0"));
  // A grid that is not this scan's.
  EXPECT_THAT(field_error(ball, half_level_options(64), grid),
              HasSubstr("synthetic.nii: the voxel tooth given is not the one this scan gives"));
}

}  // namespace
}  // namespace dentsim
