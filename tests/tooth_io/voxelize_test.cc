// Voxelisation (tooth_io/voxelize.h): the SAT triangle/box test against a clipping oracle,
// the seed fill, the distance transform against brute force, voxel volumes of analytic shapes
// (sphere, rotated box, torus whose hole must stay empty) within the discretisation bound
// |V_voxels - V_mesh| <= N_surface h^3, flood fill == winding number on every non-surface voxel
// (two independent inside tests agree exactly), materials, and the two real meshes at 256^3
// (voxel volume within 2 % of the mesh volume).
#include "tooth_io/voxelize.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <random>
#include <sstream>

#include "tests/support/stress.h"

namespace dentsim {
namespace {

constexpr double kPi = 3.14159265358979323846;

// ---- analytic meshes (closed, outward) ---------------------------------------------------------

// Torus-topology or sphere-topology parametric surface on a (u, v) lattice.
TriangleMesh torus_mesh(double big_r, double small_r, int nu, int nv) {
  TriangleMesh m;
  m.groups = {""};
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      const double u = 2 * kPi * i / nu, v = 2 * kPi * j / nv;
      m.vertices.emplace_back((big_r + small_r * std::cos(v)) * std::cos(u),
                              (big_r + small_r * std::cos(v)) * std::sin(u), small_r * std::sin(v));
    }
  }
  auto id = [&](int i, int j) { return ((i + nu) % nu) * nv + (j + nv) % nv; };
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  }
  m.triangle_group.assign(m.triangles.size(), 0);
  return m;
}

TriangleMesh sphere_mesh(const Vec3& c, double r, int slices, int stacks) {
  TriangleMesh m;
  m.groups = {""};
  m.vertices.push_back(c + Vec3(0, 0, -r));
  for (int s = 1; s < stacks; ++s) {
    const double th = kPi * s / stacks - kPi / 2;
    for (int k = 0; k < slices; ++k) {
      const double ph = 2 * kPi * k / slices;
      m.vertices.push_back(
          c + r * Vec3(std::cos(th) * std::cos(ph), std::cos(th) * std::sin(ph), std::sin(th)));
    }
  }
  m.vertices.push_back(c + Vec3(0, 0, r));
  const int top = static_cast<int>(m.vertices.size()) - 1;
  auto ring = [&](int s, int k) { return 1 + (s - 1) * slices + (k + slices) % slices; };
  for (int k = 0; k < slices; ++k) {
    m.triangles.push_back({0, ring(1, k + 1), ring(1, k)});
    m.triangles.push_back({top, ring(stacks - 1, k), ring(stacks - 1, k + 1)});
    for (int s = 1; s < stacks - 1; ++s) {
      m.triangles.push_back({ring(s, k), ring(s, k + 1), ring(s + 1, k + 1)});
      m.triangles.push_back({ring(s, k), ring(s + 1, k + 1), ring(s + 1, k)});
    }
  }
  m.triangle_group.assign(m.triangles.size(), 0);
  return m;
}

TriangleMesh box_mesh(const Vec3& half, const Mat3& rot, const Vec3& c) {
  TriangleMesh m;
  m.groups = {""};
  for (int k = 0; k < 8; ++k) {
    const Vec3 s((k & 1) ? 1 : -1, (k & 2) ? 1 : -1, (k & 4) ? 1 : -1);
    m.vertices.push_back(c + rot * half.cwiseProduct(s));
  }
  const int q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                       {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : q) {
    m.triangles.push_back({f[0], f[1], f[2]});
    m.triangles.push_back({f[0], f[2], f[3]});
  }
  m.triangle_group.assign(m.triangles.size(), 0);
  return m;
}

// Voxelises `mesh` at N and checks the bound, the bracket and flood fill == winding.
struct VolumeCheck {
  double v_mesh, v_vox, bound, rel_err;
  long surface;
};
VolumeCheck check_volume(const TriangleMesh& mesh, int n, const char* what) {
  const VoxelGrid grid = make_grid(mesh_bounds(mesh), n);
  SolidStats st;
  const auto solid = voxelize_solid(mesh, grid, {}, &st);
  const auto surface = surface_voxels(mesh, grid);
  const auto outside = seed_fill_outside(surface, n);
  const auto winding = center_winding_inside(mesh, grid);
  long disagreements = 0, solid_count = 0;
  for (std::size_t x = 0; x < solid.size(); ++x) {
    solid_count += solid[x];
    if (surface[x] == 0 && (outside[x] == 0) != (winding[x] != 0)) ++disagreements;
  }
  EXPECT_EQ(disagreements, 0) << what << ": seed fill and winding number disagree";
  EXPECT_EQ(solid_count, st.solid_voxels());
  const double hv = grid.voxel_volume();
  VolumeCheck c;
  c.v_mesh = solid_volume(mesh);
  c.v_vox = st.solid_voxels() * hv;
  c.surface = st.surface_voxels;
  c.bound = st.surface_voxels * hv;
  c.rel_err = (c.v_vox - c.v_mesh) / c.v_mesh;
  // The bracket: interior voxels lie inside, interior + surface voxels cover the solid.
  EXPECT_LE(st.interior_voxels * hv, c.v_mesh) << what;
  EXPECT_GE((st.interior_voxels + st.surface_voxels) * hv, c.v_mesh) << what;
  EXPECT_LE(std::abs(c.v_vox - c.v_mesh), c.bound) << what;
  std::printf("%-14s N=%4d  V_mesh=%.6e  V_vox=%.6e  rel.err=%+.4f%%  bound=%.2f%%  surface=%ld\n",
              what, n, c.v_mesh, c.v_vox, 100 * c.rel_err, 100 * c.bound / c.v_mesh, c.surface);
  return c;
}

// ---- triangle/box -------------------------------------------------------------------------------

// Oracle: clip the triangle against the box's six half-spaces (Sutherland-Hodgman); they overlap
// iff something is left.
bool clip_oracle(const Vec3& c, const Vec3& h, const Vec3& a, const Vec3& b, const Vec3& d) {
  std::vector<Vec3> poly = {a - c, b - c, d - c};
  for (int axis = 0; axis < 3; ++axis) {
    for (double sgn : {1.0, -1.0}) {
      std::vector<Vec3> out;
      for (std::size_t i = 0; i < poly.size(); ++i) {
        const Vec3& p = poly[i];
        const Vec3& q = poly[(i + 1) % poly.size()];
        const double fp = h[axis] - sgn * p[axis], fq = h[axis] - sgn * q[axis];  // >= 0 inside
        if (fp >= 0) out.push_back(p);
        if ((fp >= 0) != (fq >= 0)) out.push_back(p + (q - p) * (fp / (fp - fq)));
      }
      poly = out;
      if (poly.empty()) return false;
    }
  }
  return true;
}

TEST(TriangleBox, AgreesWithClippingOracle) {
  const unsigned seed = 12345;
  std::printf("seed %u\n", seed);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-2, 2), hs(0.1, 1);
  int overlaps = 0;
  const int trials = 200000;
  for (int t = 0; t < trials; ++t) {
    const Vec3 h(hs(rng), hs(rng), hs(rng));
    const Vec3 a(u(rng), u(rng), u(rng));
    const Vec3 b = a + 0.7 * Vec3(u(rng), u(rng), u(rng));
    const Vec3 c = a + 0.7 * Vec3(u(rng), u(rng), u(rng));
    const bool expected = clip_oracle(Vec3::Zero(), h, a, b, c);
    ASSERT_EQ(triangle_box_overlap(Vec3::Zero(), h, a, b, c), expected)
        << "trial " << t << " a=" << a.transpose() << " b=" << b.transpose()
        << " c=" << c.transpose() << " h=" << h.transpose();
    overlaps += expected;
  }
  // Both outcomes well represented (the test is not trivially true).
  EXPECT_GT(overlaps, trials / 10);
  EXPECT_LT(overlaps, trials * 9 / 10);
}

TEST(TriangleBox, TouchingCountsAndSeparatedDoesNot) {
  const Vec3 h(0.5, 0.5, 0.5);
  // A triangle in the plane x = 0.5 (a face of the box) overlaps; at x = 0.5 + 1e-6 it does not.
  EXPECT_TRUE(
      triangle_box_overlap(Vec3::Zero(), h, Vec3(0.5, -1, -1), Vec3(0.5, 2, -1), Vec3(0.5, -1, 2)));
  EXPECT_FALSE(triangle_box_overlap(Vec3::Zero(), h, Vec3(0.5 + 1e-6, -1, -1),
                                    Vec3(0.5 + 1e-6, 2, -1), Vec3(0.5 + 1e-6, -1, 2)));
  // A large triangle near a corner: its plane x + y + z = 1.6 misses the corner (sum 1.5).
  EXPECT_FALSE(
      triangle_box_overlap(Vec3::Zero(), h, Vec3(1.6, 0, 0), Vec3(0, 1.6, 0), Vec3(0, 0, 1.6)));
  EXPECT_TRUE(
      triangle_box_overlap(Vec3::Zero(), h, Vec3(1.4, 0, 0), Vec3(0, 1.4, 0), Vec3(0, 0, 1.4)));
}

// ---- seed fill and distance transform ---------------------------------------------------------

TEST(SeedFill, ClosedShellKeepsInsideAndAHoleLeaks) {
  const int n = 16;
  auto at = [n](int i, int j, int k) { return static_cast<std::size_t>(i + n * (j + n * k)); };
  std::vector<std::uint8_t> shell(n * n * n, 0);
  for (int k = 4; k <= 11; ++k) {
    for (int j = 4; j <= 11; ++j) {
      for (int i = 4; i <= 11; ++i) {
        const bool face = i == 4 || i == 11 || j == 4 || j == 11 || k == 4 || k == 11;
        if (face) shell[at(i, j, k)] = 1;
      }
    }
  }
  auto out = seed_fill_outside(shell, n);
  long outside = 0;
  for (auto v : out) outside += v;
  EXPECT_EQ(outside, n * n * n - 8 * 8 * 8);  // everything but the shell and its 6^3 inside
  EXPECT_EQ(out[at(7, 7, 7)], 0);
  shell[at(11, 7, 7)] = 0;  // a one-voxel hole in a face
  out = seed_fill_outside(shell, n);
  outside = 0;
  for (auto v : out) outside += v;
  EXPECT_EQ(outside, n * n * n - (8 * 8 * 8 - 6 * 6 * 6 - 1));
}

TEST(DistanceTransform, MatchesBruteForceAndClips) {
  const unsigned seed = 777;
  std::printf("seed %u\n", seed);
  std::mt19937 rng(seed);
  const int n = 16;
  VoxelGrid g(n, Vec3::Zero(), 1.0);
  std::bernoulli_distribution solid(0.93);
  for (auto& v : g.voxels) v = solid(rng) ? kDentin : kEmpty;
  const auto exact = distance_to_empty_sq(g, 255);
  const auto clipped = distance_to_empty_sq(g, 2);
  int checked = 0, above_clip = 0;
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        int best = 1 << 30;
        for (int c = 0; c < n; ++c) {
          for (int b = 0; b < n; ++b) {
            for (int a = 0; a < n; ++a) {
              if (g.solid(a, b, c)) continue;
              best = std::min(best, (a - i) * (a - i) + (b - j) * (b - j) + (c - k) * (c - k));
            }
          }
        }
        ASSERT_EQ(exact[g.index(i, j, k)], best) << i << " " << j << " " << k;
        ASSERT_EQ(clipped[g.index(i, j, k)], std::min(best, 4));
        above_clip += best > 4;
        ++checked;
      }
    }
  }
  EXPECT_GT(above_clip, 100);  // the clip is exercised
}

// ---- volumes of analytic shapes -----------------------------------------------------------------

TEST(VoxelizeShapes, SphereVolumeWithinDiscretisationBound) {
  const TriangleMesh s = sphere_mesh(Vec3(0.1, -0.2, 0.3), 1.0, 96, 48);
  double prev = 1;
  for (int n : {32, 64, 128}) {
    const VolumeCheck c = check_volume(s, n, "sphere");
    EXPECT_LT(std::abs(c.rel_err), 0.5 * c.bound / c.v_mesh);  // errors mostly cancel
    EXPECT_LT(std::abs(c.rel_err), prev);                      // and shrink with resolution
    prev = std::abs(c.rel_err);
  }
  // The tessellated sphere is within 0.2 % of the analytic one; so is the voxel volume at 128^3.
  EXPECT_NEAR(solid_volume(s) / (4.0 / 3.0 * kPi), 1.0, 2e-3);
}

TEST(VoxelizeShapes, RotatedBoxVolumeWithinDiscretisationBound) {
  const Mat3 rot =
      (Eigen::AngleAxisd(0.3, Vec3::UnitZ()) * Eigen::AngleAxisd(0.7, Vec3(1, 1, 0).normalized()))
          .toRotationMatrix();
  const TriangleMesh b = box_mesh(Vec3(1.0, 0.6, 0.35), rot, Vec3(0.01, 0.02, 0.03));
  EXPECT_NEAR(solid_volume(b), 8 * 1.0 * 0.6 * 0.35, 1e-12);
  for (int n : {32, 64, 128}) check_volume(b, n, "rotated box");
}

TEST(VoxelizeShapes, AxisAlignedBoxOnVoxelFacesIsExact) {
  // A box whose faces lie on voxel faces: every voxel is fully in or out, the count is exact.
  const TriangleMesh b = box_mesh(Vec3(1.0, 0.5, 0.25), Mat3::Identity(), Vec3::Zero());
  const int n = 64;
  const VoxelGrid g = make_grid(mesh_bounds(b), n);  // h = 2 / 60
  SolidStats st;
  voxelize_solid(b, g, {}, &st);
  EXPECT_EQ(st.solid_voxels(), 60L * 30 * 15);
}

TEST(VoxelizeShapes, TorusHoleStaysEmpty) {
  const double big_r = 1.0, small_r = 0.35;
  const TriangleMesh t = torus_mesh(big_r, small_r, 96, 48);
  for (int n : {32, 64, 128}) {
    const VolumeCheck c = check_volume(t, n, "torus");
    EXPECT_LT(std::abs(c.rel_err), 0.5 * c.bound / c.v_mesh);
    const VoxelGrid g = make_grid(mesh_bounds(t), n);
    const auto solid = voxelize_solid(t, g);
    long in_hole = 0, hole_voxels = 0;
    for (int k = 0; k < n; ++k) {
      for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
          const Vec3 p = g.center(i, j, k);
          // Voxels whose whole box lies inside the hole's cylinder r < R - r_small.
          if (std::hypot(p.x(), p.y()) + g.voxel_size < big_r - small_r) {
            ++hole_voxels;
            in_hole += solid[g.index(i, j, k)];
          }
        }
      }
    }
    EXPECT_GT(hole_voxels, 0);
    EXPECT_EQ(in_hole, 0) << "seed fill filled the torus hole at N=" << n;
  }
  // The 96 x 48 polygonal torus lies inside the analytic one (chords): 0.36 % less volume.
  EXPECT_NEAR(solid_volume(t) / (2 * kPi * kPi * big_r * small_r * small_r), 1.0, 5e-3);
}

// Random closed shapes (star-shaped bumpy spheres and bumpy tori, randomly rotated, shifted and
// sized, on random resolutions): the seed fill and the winding number agree on every non-surface
// voxel, and the volume is within the bound. Short form 12 shapes, DENTSIM_STRESS=full 400.
TEST(VoxelizeStress, RandomShapesFillEqualsWindingAndVolumeWithinBound) {
  const unsigned seed = 4242;
  const long shapes = testing::stress_count(12, 400);
  std::printf("seed %u, %ld shapes\n", seed, shapes);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  for (long s = 0; s < shapes; ++s) {
    const bool torus = s % 2 == 1;
    TriangleMesh m = torus ? torus_mesh(1.0, 0.3 + 0.2 * u(rng), 40, 20)
                           : sphere_mesh(Vec3::Zero(), 1.0, 40, 20);
    // Smooth random bumps along the radius (tube radius for the torus): keeps the surface simple.
    const Vec3 k1(3 * u(rng), 3 * u(rng), 3 * u(rng)), k2(5 * u(rng), 5 * u(rng), 5 * u(rng));
    const double a1 = 0.15 * u(rng), a2 = 0.08 * u(rng);
    for (Vec3& v : m.vertices) {
      const Vec3 axis = torus ? Vec3(v.x(), v.y(), 0).normalized() : Vec3::Zero();
      const Vec3 radial = v - axis;  // from the sphere's centre / the tube's core circle
      const double bump = 1 + a1 * std::sin(k1.dot(v)) + a2 * std::cos(k2.dot(v));
      v = axis + radial * bump;
    }
    const Mat3 rot = Eigen::Quaterniond(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5)
                         .normalized()
                         .toRotationMatrix();
    const double size = 1e-3 + 20e-3 * u(rng);
    const Vec3 shift(u(rng), u(rng), u(rng));
    for (Vec3& v : m.vertices) v = rot * v * size + shift * size;
    const int n = 16 << static_cast<int>(3 * u(rng));  // 16, 32 or 64
    SCOPED_TRACE("shape " + std::to_string(s) + (torus ? " (torus)" : " (sphere)") +
                 " N=" + std::to_string(n));
    check_volume(m, n, torus ? "random torus" : "random sphere");
  }
}

// ---- materials --------------------------------------------------------------------------------

TEST(Materials, EnamelByDepthOnTheCrownOnly) {
  // A 2 x 2 x 4 mm box standing on z, crown = upper half (CEJ at z = 0), t_cusp = 0.5 mm.
  const TriangleMesh b = box_mesh(Vec3(1e-3, 1e-3, 2e-3), Mat3::Identity(), Vec3::Zero());
  VoxelGrid g = make_grid(mesh_bounds(b), 64);
  g.voxels = voxelize_solid(b, g);
  CrownFrame crown;
  crown.axis = Vec3::UnitZ();
  crown.cej = 0;
  crown.crown_height = 2e-3;
  const double t_cusp = 0.5e-3;
  const double t_top = t_cusp * 2e-3 / (2e-3 - t_cusp);
  std::vector<std::uint8_t> pulp(g.voxels.size(), 0);
  pulp[g.index(32, 32, 20)] = 1;
  assign_materials(g, pulp, crown, t_cusp);
  const double h = g.voxel_size;
  long enamel = 0, checked = 0;
  for (int k = 0; k < g.n; ++k) {
    for (int j = 0; j < g.n; ++j) {
      for (int i = 0; i < g.n; ++i) {
        const std::uint8_t m = g.at(i, j, k);
        if (m == kEmpty) continue;
        const Vec3 p = g.center(i, j, k);
        if (i == 32 && j == 32 && k == 20) {
          EXPECT_EQ(m, kPulp);
          continue;
        }
        // Depth of the centre below the box surface (exact for a box).
        const double depth =
            std::min({1e-3 - std::abs(p.x()), 1e-3 - std::abs(p.y()), 2e-3 - std::abs(p.z())});
        const double s = p.z();
        const double t = s < 0 ? -1 : std::min(t_cusp, t_top * s / 2e-3);
        if (s < 0) {
          EXPECT_EQ(m, kDentin);
        } else if (depth < t - 0.5 * h) {
          EXPECT_EQ(m, kEnamel) << "depth " << depth << " t " << t;
          ++checked;
        } else if (depth > t + 0.5 * h) {
          EXPECT_EQ(m, kDentin) << "depth " << depth << " t " << t;
          ++checked;
        }
        enamel += m == kEnamel;
      }
    }
  }
  EXPECT_GT(enamel, 1000);
  EXPECT_GT(checked, 10000);
  // Straight down from the top face the enamel is t_cusp thick (to a voxel).
  int column = 0;
  for (int k = g.n - 1; k >= 0; --k) column += g.at(32, 32, k) == kEnamel;
  EXPECT_NEAR(column * h, t_cusp, h);
}

// Pulp marked kPulp in the grid on entry (the procedural molar's way, without an N^3 pulp array:
// issue #30) gives the same materials as the same voxels marked in `pulp`.
TEST(Materials, PulpMarkedInTheGridEqualsThePulpArray) {
  const TriangleMesh b = box_mesh(Vec3(1e-3, 1e-3, 2e-3), Mat3::Identity(), Vec3::Zero());
  VoxelGrid by_array = make_grid(mesh_bounds(b), 64);
  by_array.voxels = voxelize_solid(b, by_array);
  VoxelGrid in_grid = by_array;
  std::vector<std::uint8_t> pulp(by_array.voxels.size(), 0);
  long marked = 0;
  for (int k = 24; k < 40; ++k) {  // a pulp column through the crown's enamel and the root
    for (int j = 30; j < 34; ++j) {
      for (int i = 30; i < 34; ++i) {
        if (!by_array.solid(i, j, k)) continue;
        pulp[by_array.index(i, j, k)] = 1;
        in_grid.set(i, j, k, kPulp);
        ++marked;
      }
    }
  }
  ASSERT_GT(marked, 100);
  CrownFrame crown;
  crown.axis = Vec3::UnitZ();
  crown.crown_height = 2e-3;
  assign_materials(by_array, pulp, crown, 0.5e-3);
  assign_materials(in_grid, {}, crown, 0.5e-3);
  EXPECT_EQ(in_grid.voxels, by_array.voxels);
  EXPECT_EQ(count_materials(in_grid)[kPulp], marked);
}

// assign_materials' definition written plainly: the depth of every crown dentin voxel from the
// clipped distance transform of the whole grid (distance_to_empty_sq), the enamel where it is
// under t(s).
VoxelGrid plain_materials(VoxelGrid grid, const CrownFrame& crown, double t_cusp) {
  for (std::uint8_t& m : grid.voxels) {
    if (m != 0) m = m == kPulp ? kPulp : kDentin;
  }
  const double h = grid.voxel_size, height = crown.crown_height;
  const double t_top = t_cusp < height ? t_cusp * height / (height - t_cusp)
                                       : std::numeric_limits<double>::infinity();
  const int clip = std::min(255, static_cast<int>(std::ceil(std::min(t_cusp, grid.n * h) / h)) + 2);
  const std::vector<std::uint16_t> d2 = distance_to_empty_sq(grid, clip);
  VoxelGrid out = grid;
  for (int k = 0; k < grid.n; ++k) {
    for (int j = 0; j < grid.n; ++j) {
      for (int i = 0; i < grid.n; ++i) {
        if (grid.at(i, j, k) != kDentin) continue;
        const double s = crown.axis.dot(grid.center(i, j, k)) - crown.cej;
        if (s < 0) continue;
        const double t = std::min(t_cusp, t_top * s / height);
        if ((std::sqrt(double(d2[grid.index(i, j, k)])) - 0.5) * h < t) out.set(i, j, k, kEnamel);
      }
    }
  }
  return out;
}

// assign_materials transforms only the box of the crown's dentin and `clip` voxels around it,
// and skips the lines of the transform that are all empty or all at the clip (issue #30: the
// 512^3 tooth's setup): the materials are the plain definition's, voxel for voxel, on a box
// with a pulp column and its crown along +z, along a tilted axis with the CEJ moved, and with
// enamel thicker than the clip's reach of the solid.
TEST(Materials, CrownBoxDistancesAreTheWholeGridsDistances) {
  const TriangleMesh b = box_mesh(Vec3(1e-3, 1.2e-3, 2e-3), Mat3::Identity(), Vec3::Zero());
  VoxelGrid solid = make_grid(mesh_bounds(b), 64);
  solid.voxels = voxelize_solid(b, solid);
  for (int k = 20; k < 44; ++k) {
    for (int j = 28; j < 34; ++j) {
      for (int i = 29; i < 35; ++i) {
        if (solid.solid(i, j, k)) solid.set(i, j, k, kPulp);
      }
    }
  }
  CrownFrame up;
  up.crown_height = 1.5e-3;
  up.cej = 0.3e-3;
  CrownFrame tilted;
  tilted.axis = Vec3(0.3, -0.2, 1.0).normalized();
  tilted.cej = -0.4e-3;
  tilted.crown_height = 1.8e-3;
  for (const auto& [crown, t_cusp] :
       {std::pair{up, 0.4e-3}, std::pair{tilted, 0.3e-3}, std::pair{up, 5e-3}}) {
    VoxelGrid fast = solid;
    assign_materials(fast, {}, crown, t_cusp);
    const VoxelGrid plain = plain_materials(solid, crown, t_cusp);
    long differ = 0;
    for (std::size_t x = 0; x < plain.voxels.size(); ++x)
      differ += fast.voxels[x] != plain.voxels[x];
    EXPECT_EQ(differ, 0) << "t_cusp " << t_cusp;
    const std::vector<long> counts = count_materials(plain);
    EXPECT_GT(counts[kEnamel], 100);
    EXPECT_GT(counts[kDentin], 100);
    EXPECT_GT(counts[kPulp], 100);
  }
}

// Issue #30 (the setup on two cores): the distance transform's passes and assign_materials' scans
// run a plane a task on setup_threads() threads (DENTSIM_SETUP_THREADS): every squared distance
// and every material is the one-thread one at 2, 3 and 7 threads (a random grid solid to its
// faces, the clip 255 and 3; the box above with its crown).
TEST(Materials, ThreadedTransformAndMaterialsAreTheOneThreadOnes) {
  const char* saved = std::getenv("DENTSIM_SETUP_THREADS");
  const std::string restore = saved != nullptr ? saved : "";
  VoxelGrid random(32, Vec3::Zero(), 1e-4);
  std::mt19937_64 rng(46);
  for (auto& v : random.voxels) v = rng() % 10 < 8 ? kDentin : kEmpty;
  const TriangleMesh b = box_mesh(Vec3(1e-3, 1.2e-3, 2e-3), Mat3::Identity(), Vec3::Zero());
  VoxelGrid solid = make_grid(mesh_bounds(b), 64);
  solid.voxels = voxelize_solid(b, solid);
  CrownFrame up;
  up.crown_height = 1.5e-3;
  up.cej = 0.3e-3;
  const auto run = [&](const char* threads) {
    EXPECT_EQ(setenv("DENTSIM_SETUP_THREADS", threads, 1), 0);
    std::vector<std::vector<std::uint16_t>> d2 = {distance_to_empty_sq(random, 255),
                                                  distance_to_empty_sq(random, 3)};
    VoxelGrid materials = solid;
    assign_materials(materials, {}, up, 0.4e-3);
    return std::pair{d2, materials.voxels};
  };
  const auto one = run("1");
  for (const char* threads : {"2", "3", "7"}) {
    const auto many = run(threads);
    EXPECT_TRUE(many.first == one.first) << threads << " threads";
    EXPECT_TRUE(many.second == one.second) << threads << " threads";
  }
  if (saved != nullptr) {
    setenv("DENTSIM_SETUP_THREADS", restore.c_str(), 1);
  } else {
    unsetenv("DENTSIM_SETUP_THREADS");
  }
  // Not trivially equal: some voxels deep (the random grid's runs), some enamel.
  EXPECT_GT(*std::max_element(one.first[0].begin(), one.first[0].end()), 1);
  VoxelGrid with_enamel = solid;
  with_enamel.voxels = one.second;
  EXPECT_GT(count_materials(with_enamel)[kEnamel], 100);
}

// ---- real meshes --------------------------------------------------------------------------------

std::string shared_data(const std::string& file) {
  return std::string(DENTSIM_SOURCE_DIR) + "/../shared/data/" + file;
}

void check_real_mesh(const std::string& file, double size_m, int n) {
  const std::string path = shared_data(file);
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "../shared/data absent: " << path;
  LoadedMesh m = load_mesh(path);
  scale_mesh(m.mesh, scale_for_size(m.mesh, size_m));
  VoxelizeOptions opt;
  opt.resolution = n;
  VoxelizeReport rep;
  const VoxelGrid g = voxelize_mesh(m.mesh, opt, &rep);
  const auto counts = count_materials(g);
  const long solid = counts[kEnamel] + counts[kDentin] + counts[kPulp];
  EXPECT_EQ(solid, rep.solid.solid_voxels());
  const double v_mesh = solid_volume(m.mesh);
  const double v_vox = solid * g.voxel_volume();
  const double rel = (v_vox - v_mesh) / v_mesh;
  std::printf(
      "%s at %d^3: V_mesh %.3f mm^3, V_vox %.3f mm^3, rel.err %+.4f%%, bound %.2f%%; "
      "enamel %ld dentin %ld pulp %ld; crown axis %s\n",
      file.c_str(), n, v_mesh * 1e9, v_vox * 1e9, 100 * rel,
      100 * rep.solid.surface_voxels * g.voxel_volume() / v_mesh, counts[kEnamel], counts[kDentin],
      counts[kPulp], (std::ostringstream() << rep.crown.axis.transpose()).str().c_str());
  EXPECT_LT(std::abs(rel), 0.02);
  EXPECT_LE(std::abs(v_vox - v_mesh), rep.solid.surface_voxels * g.voxel_volume());
  EXPECT_GT(counts[kEnamel], 0);
  EXPECT_GT(counts[kDentin], 0);
}

TEST(VoxelizeRealMesh, MolarStlAt256WithinTwoPercent) {
  check_real_mesh("molar-cc0.stl", 22e-3, 256);
}

TEST(VoxelizeRealMesh, Chai3dToothAt256WithinTwoPercentAndNerveIsPulp) {
  check_real_mesh("chai3d-tooth.obj", 21e-3, 256);
  if (IsSkipped()) return;
  LoadedMesh m = load_mesh(shared_data("chai3d-tooth.obj"));
  scale_mesh(m.mesh, scale_for_size(m.mesh, 21e-3));
  VoxelizeOptions opt;
  opt.resolution = 128;
  VoxelizeReport rep;
  const VoxelGrid g = voxelize_mesh(m.mesh, opt, &rep);
  ASSERT_EQ(rep.pulp_groups, std::vector<std::string>{"Nerve"});
  std::vector<int> nerve;
  for (int t = 0; t < static_cast<int>(m.mesh.triangles.size()); ++t) {
    if (m.mesh.groups[m.mesh.triangle_group[t]] == "Nerve") nerve.push_back(t);
  }
  SolidStats ns;
  voxelize_solid(m.mesh, g, nerve, &ns);
  const double v_nerve = signed_volume(m.mesh, nerve);
  const double v_pulp = rep.pulp_voxels * g.voxel_volume();
  std::printf("chai3d nerve at 128^3: V_mesh %.3f mm^3, V_pulp %.3f mm^3 (bound %.3f)\n",
              v_nerve * 1e9, v_pulp * 1e9, ns.surface_voxels * g.voxel_volume() * 1e9);
  EXPECT_EQ(rep.pulp_voxels, ns.solid_voxels());  // the nerve lies inside the tooth
  EXPECT_LE(std::abs(v_pulp - v_nerve), ns.surface_voxels * g.voxel_volume());
}

}  // namespace
}  // namespace dentsim
