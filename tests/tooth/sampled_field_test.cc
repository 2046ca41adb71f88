// The sampled signed-distance field (reference/tooth/sampled_field.h): its value is the exact
// distance to the source surface (a box mesh, a triangulated sphere, the plane of a box face) up
// to stated bounds, its gradient is the derivative of the interpolant, its Lipschitz constant
// bounds it, and its memory (bricks) grows with the surface's area, not the grid's volume.
#include "reference/tooth/sampled_field.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <unordered_map>
#include <vector>

#include "tooth_io/procedural_molar.h"
#include "tooth_io/voxelize.h"
#include "tests/tooth/field_shapes.h"

namespace dentsim {
namespace {

constexpr std::uint64_t kSeed = 30;

using test::box_mesh;

// Exact signed distance of the box [lo, hi].
double box_sdf(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  const Vec3 c = 0.5 * (lo + hi), e = 0.5 * (hi - lo);
  const Vec3 q = (p - c).cwiseAbs() - e;
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

VoxelGrid grid_from(int n, double side, const std::function<bool(const Vec3&)>& inside) {
  return test::solid_grid(n, side, inside);
}

TEST(SampledField, PointTriangleDistanceMatchesDenseSampling) {
  std::mt19937_64 rng(kSeed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3 a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng)), c(u(rng), u(rng), u(rng));
    const Vec3 p = 2.0 * Vec3(u(rng), u(rng), u(rng));
    double best = 1e9;
    const int k = 300;
    for (int i = 0; i <= k; ++i) {
      for (int j = 0; i + j <= k; ++j) {
        const Vec3 q = a + (b - a) * (double(i) / k) + (c - a) * (double(j) / k);
        best = std::min(best, (p - q).norm());
      }
    }
    const double d = point_triangle_distance(p, a, b, c);
    EXPECT_LE(d, best + 1e-12);
    EXPECT_GE(d, best - 4.0 * ((b - a).norm() + (c - a).norm()) / k);
  }
}

// A box from a mesh: at every stored sample the field is the exact signed distance clamped to
// the band (float rounding: 1e-9 m); near the middle of a face it is the plane's distance at any
// point (trilinear interpolation reproduces a linear function).
TEST(SampledField, BoxMeshSamplesAreTheExactDistanceAndFacesArePlanes) {
  const Vec3 lo(1.13e-3, 1.37e-3, 0.91e-3), hi(4.71e-3, 4.02e-3, 3.88e-3);
  const TriangleMesh mesh = box_mesh(lo, hi);
  VoxelGrid grid(32, Vec3::Zero(), 6.4e-3 / 32);
  const std::vector<std::uint8_t> in = center_winding_inside(mesh, grid);
  for (std::size_t v = 0; v < in.size(); ++v) grid.voxels[v] = in[v] ? kEnamel : kEmpty;
  FieldBand band;
  band.outside_m = 0.7e-3;
  const SampledField f = build_sampled_field(grid, mesh, band);
  const double h = grid.voxel_size;
  EXPECT_EQ(f.outside_clamp(), 0.7e-3);
  EXPECT_EQ(f.inside_clamp(), 2.0 * h);
  int checked = 0;
  for (int z = 0; z < f.samples_per_axis(); ++z) {
    for (int y = 0; y < f.samples_per_axis(); ++y) {
      for (int x = 0; x < f.samples_per_axis(); ++x) {
        const double exact = std::clamp(box_sdf(f.sample_position(x, y, z), lo, hi),
                                        -f.inside_clamp(), f.outside_clamp());
        ASSERT_NEAR(f.at(x, y, z), exact, 1e-9) << x << " " << y << " " << z;
        checked += std::abs(exact) < f.outside_clamp() ? 1 : 0;
      }
    }
  }
  EXPECT_GT(checked, 5000);
  // The top face z = hi.z, away from its edges by more than the band: a plane.
  std::mt19937_64 rng(kSeed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 500; ++trial) {
    const Vec3 p(lo.x() + 0.8e-3 + u(rng) * (hi.x() - lo.x() - 1.6e-3),
                 lo.y() + 0.8e-3 + u(rng) * (hi.y() - lo.y() - 1.6e-3),
                 hi.z() - 1.5 * h + u(rng) * (1.5 * h + 0.6e-3));
    const FieldSample s = f.sample(p);
    EXPECT_NEAR(s.value, p.z() - hi.z(), 1e-9);
    EXPECT_NEAR((s.gradient - Vec3::UnitZ()).norm(), 0.0, 1e-5);
  }
  // The Lipschitz constant: at least the slope of a face, at most sqrt(3).
  EXPECT_GE(f.lipschitz(), 1.0 - 1e-6);
  EXPECT_LE(f.lipschitz(), std::sqrt(3.0) + 1e-6);
}

// A sphere triangulated from its implicit function: the field is within the chord and
// interpolation bound 3 h^2 / (4 (R - c_in)) of |x - c| - R in the band, and its gradient is the
// derivative of the interpolant (central differences inside a cell).
TEST(SampledField, SphereFromItsImplicitFunctionIsItsDistanceAndGradient) {
  const double side = 8e-3, r = 2.5e-3;
  const Vec3 centre(4.03e-3, 3.97e-3, 4.11e-3);
  const auto inside = [&](const Vec3& p) { return (p - centre).norm() < r; };
  const VoxelGrid grid = grid_from(64, side, inside);
  const TriangleMesh surface = triangulate_implicit(grid, inside);
  for (const Vec3& v : surface.vertices) ASSERT_NEAR((v - centre).norm(), r, 1e-12);
  FieldBand band;
  band.outside_m = 0.7e-3;
  const SampledField f = build_sampled_field(grid, surface, band);
  const double h = grid.voxel_size;
  const double bound = 3.0 * h * h / (4.0 * (r - f.inside_clamp()));
  std::mt19937_64 rng(kSeed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double worst = 0.0;
  for (int trial = 0; trial < 2000; ++trial) {
    Vec3 dir(u(rng), u(rng), u(rng));
    if (dir.norm() < 1e-3) continue;
    dir.normalize();
    // Depths whose cell has no clamped corner (corners are within sqrt(3) h of the point).
    const double lo = -(f.inside_clamp() - 1.75 * h), hi = f.outside_clamp() - 1.75 * h;
    const double d = lo + 0.5 * (u(rng) + 1.0) * (hi - lo);
    const Vec3 p = centre + (r + d) * dir;
    const FieldSample s = f.sample(p);
    worst = std::max(worst, std::abs(s.value - d));
    ASSERT_NEAR(s.value, d, bound) << "at depth " << d;
    // Central differences of the interpolant within the cell holding p.
    const double e = 1e-4 * h;
    Vec3 fd;
    for (int a = 0; a < 3; ++a) {
      Vec3 dp = Vec3::Zero();
      dp[a] = e;
      fd[a] = (f.value(p + dp) - f.value(p - dp)) / (2.0 * e);
    }
    // Points within e of a cell face see two cells: skip them (the gradient jumps there).
    bool near_face = false;
    for (int a = 0; a < 3; ++a) {
      const double w = (p[a] - f.sample_position(0, 0, 0)[a]) / h;
      const double frac = w - std::floor(w);
      near_face = near_face || frac < 1e-3 || frac > 1.0 - 1e-3;
    }
    if (!near_face) {
      ASSERT_NEAR((fd - s.gradient).norm(), 0.0, 1e-5);
    }
    // The gradient points along the radius (the sphere's normal) within the chord bound.
    EXPECT_GT(s.gradient.normalized().dot(dir), std::cos(0.1));
  }
  std::printf("sphere R = %.1f mm, h = %.3f mm: max |phi - d| = %.3g m (bound %.3g m), L = %.4f\n",
              1e3 * r, 1e3 * h, worst, bound, f.lipschitz());
  EXPECT_LE(f.lipschitz(), std::sqrt(3.0) + 1e-6);
  EXPECT_LT(f.lipschitz(), 1.2);
}

// Bricks (memory) grow with the surface's area: a sphere of twice the radius at the same voxel
// size takes about four times the bricks (the band's thickness is fixed), not eight.
TEST(SampledField, BrickCountScalesWithTheSurfaceArea) {
  const double h = 0.2e-3;
  std::size_t bricks[2];
  for (int s = 0; s < 2; ++s) {
    const double r = (s == 0 ? 2.0e-3 : 4.0e-3);
    const int n = s == 0 ? 32 : 64;
    const Vec3 centre = Vec3::Constant(0.5 * n * h + 0.013e-3);
    const auto inside = [&](const Vec3& p) { return (p - centre).norm() < r; };
    const VoxelGrid grid = grid_from(n, n * h, inside);
    FieldBand band;
    band.outside_m = 0.8e-3;
    const SampledField f = build_sampled_field(grid, triangulate_implicit(grid, inside), band);
    bricks[s] = f.brick_count();
    // Well below a dense lattice of samples.
    const std::size_t m = static_cast<std::size_t>(f.samples_per_axis());
    EXPECT_LT(f.brick_count() * SampledField::kBrickSamples, m * m * m / 2);
  }
  const double ratio = static_cast<double>(bricks[1]) / bricks[0];
  std::printf("bricks: R = 2 mm %zu, R = 4 mm %zu, ratio %.2f (area 4, volume 8)\n", bricks[0],
              bricks[1], ratio);
  EXPECT_GT(ratio, 3.0);
  EXPECT_LT(ratio, 5.0);
}


// triangulate_voxel_signs as it was written first (issue #30 made it scan only the cells with a
// surface, from bit rows, and keep the edges' vertices in two layer tables): every cell of
// [-1, n - 1]^3 visited, its 8 signs read, the edges' vertices in one hash map. The fast one must
// give the same mesh: the same vertices (bit for bit) in the same order, the same triangles.
TriangleMesh plain_triangulation(const VoxelGrid& grid,
                                 const std::function<Vec3(const Vec3&, const Vec3&)>& place) {
  TriangleMesh mesh;
  mesh.groups.push_back("");
  const int n = grid.n;
  constexpr int kAxisBit[3] = {1, 2, 4};
  constexpr int kOrders[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  const std::uint64_t span = static_cast<std::uint64_t>(n) + 2;
  std::unordered_map<std::uint64_t, int> edge_vertex;
  const auto corner = [&](int i, int j, int k, int c) {
    return grid.center(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
  };
  const auto vertex_on = [&](int i, int j, int k, int c0, int c1, bool in0) {
    const std::uint64_t ci = static_cast<std::uint64_t>(i + (c0 & 1) + 1),
                        cj = static_cast<std::uint64_t>(j + ((c0 >> 1) & 1) + 1),
                        ck = static_cast<std::uint64_t>(k + ((c0 >> 2) & 1) + 1);
    const std::uint64_t key =
        ((ci + span * (cj + span * ck)) << 3) | static_cast<unsigned>(c1 - c0);
    const auto it = edge_vertex.find(key);
    if (it != edge_vertex.end()) return it->second;
    const int v = static_cast<int>(mesh.vertices.size());
    mesh.vertices.push_back(
        place(corner(i, j, k, in0 ? c0 : c1), corner(i, j, k, in0 ? c1 : c0)));
    edge_vertex.emplace(key, v);
    return v;
  };
  for (int k = -1; k < n; ++k) {
    for (int j = -1; j < n; ++j) {
      for (int i = -1; i < n; ++i) {
        bool s[8];
        int count = 0;
        for (int c = 0; c < 8; ++c) {
          s[c] = grid.solid(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
          count += s[c] ? 1 : 0;
        }
        if (count == 0 || count == 8) continue;
        for (const auto& order : kOrders) {
          const int tv[4] = {0, kAxisBit[order[0]], kAxisBit[order[0]] + kAxisBit[order[1]], 7};
          int in[4], out[4], ni = 0, no = 0;
          for (const int c : tv) (s[c] ? in[ni++] : out[no++]) = c;
          if (ni == 0 || no == 0) continue;
          const auto cross = [&](int a, int b) {
            return a < b ? vertex_on(i, j, k, a, b, s[a]) : vertex_on(i, j, k, b, a, s[b]);
          };
          if (ni == 1 || no == 1) {
            const int lone = ni == 1 ? in[0] : out[0];
            const int* others = ni == 1 ? out : in;
            mesh.triangles.push_back(
                {cross(lone, others[0]), cross(lone, others[1]), cross(lone, others[2])});
          } else {
            const int a = cross(in[0], out[0]), b = cross(in[0], out[1]);
            const int c = cross(in[1], out[1]), d = cross(in[1], out[0]);
            mesh.triangles.push_back({a, b, c});
            mesh.triangles.push_back({a, c, d});
          }
          mesh.triangle_group.push_back(0);
          if (ni == 2) mesh.triangle_group.push_back(0);
        }
      }
    }
  }
  return mesh;
}

void expect_same_mesh(const TriangleMesh& a, const TriangleMesh& b, const std::string& what) {
  ASSERT_EQ(a.vertices.size(), b.vertices.size()) << what;
  ASSERT_EQ(a.triangles.size(), b.triangles.size()) << what;
  ASSERT_EQ(a.triangle_group.size(), b.triangle_group.size()) << what;
  for (std::size_t v = 0; v < a.vertices.size(); ++v) {
    for (int c = 0; c < 3; ++c) ASSERT_EQ(a.vertices[v][c], b.vertices[v][c]) << what << " " << v;
  }
  for (std::size_t t = 0; t < a.triangles.size(); ++t) {
    ASSERT_EQ(a.triangles[t], b.triangles[t]) << what << " " << t;
  }
}

// The procedural molar (the drill scene's surface, bisected onto molar_solid), and random grids
// of sizes 1..9, 63 and 65 (rows within one and across two 64-bit words) at several densities,
// solids on the grid's boundary layer included (the surface closes beyond it).
TEST(SampledField, TriangulationScansOnlyTheSurfaceCellsAndMeshesAsEveryCell) {
  const MolarParams params;
  const VoxelGrid molar = voxelize_procedural_molar(params, 32);
  const auto on_molar = [&](const Vec3& in, const Vec3& out) {
    Vec3 p_in = in, p_out = out;
    for (int it = 0; it < 40; ++it) {
      const Vec3 mid = 0.5 * (p_in + p_out);
      (molar_solid(params, mid) ? p_in : p_out) = mid;
    }
    return Vec3(0.5 * (p_in + p_out));
  };
  const TriangleMesh fast_molar =
      triangulate_implicit(molar, [&](const Vec3& p) { return molar_solid(params, p); });
  EXPECT_GT(fast_molar.triangles.size(), 5000u);
  expect_same_mesh(fast_molar, plain_triangulation(molar, on_molar), "molar 32^3");
  std::mt19937_64 rng(kSeed);
  // A vertex a quarter of the edge from its empty end (any point of the edge would do).
  const auto place = [](const Vec3& in, const Vec3& out) { return Vec3(0.25 * in + 0.75 * out); };
  long triangles = 0;
  for (const int n : {1, 2, 3, 4, 5, 7, 9, 63, 65}) {
    for (const double density : {0.05, 0.5, 0.95}) {
      VoxelGrid g(n, Vec3(0.1, -0.2, 0.3), 0.5e-3);
      std::bernoulli_distribution solid(density);
      for (std::uint8_t& v : g.voxels) v = solid(rng) ? kDentin : 0;
      const TriangleMesh fast = triangulate_voxel_signs(g, place);
      triangles += static_cast<long>(fast.triangles.size());
      expect_same_mesh(fast, plain_triangulation(g, place),
                       "n " + std::to_string(n) + " density " + std::to_string(density));
    }
  }
  EXPECT_GT(triangles, 100000);
}

// The build's definition (sampled_field.h "Build"), written plainly on dense arrays: every exact
// distance of layer 0 computed, the band grown layer by layer, and each walk step evaluating
// every triangle of the three stars, repeats and the current one included; the samples the band
// did not reach are the clamps of their sign.
// `grid` and `surface` one tooth; the field at `stride` compared sample by sample with the
// definition written plainly (below). Returns the samples the band reached.
long expect_build_is_the_plain_definition(const VoxelGrid& grid, const TriangleMesh& surface,
                                          int stride, const std::string& what) {
  const FieldBand band = field_band_for_tip(0.5e-3, grid.voxel_size, stride);
  const SampledField f = build_sampled_field(grid, surface, band);
  EXPECT_EQ(f.stride(), stride);
  const double h = f.spacing();  // H = k h: every length of the definition is in it
  const int m = f.samples_per_axis(), pad = f.padding();
  const double c_out = f.outside_clamp(), c_in = f.inside_clamp();
  const auto at = [m](int x, int y, int z) {
    const std::size_t sm = static_cast<std::size_t>(m);
    return static_cast<std::size_t>(x) +
           sm * (static_cast<std::size_t>(y) + sm * static_cast<std::size_t>(z));
  };
  const std::size_t count = static_cast<std::size_t>(m) * m * m;
  std::vector<double> dist(count, std::numeric_limits<double>::infinity());
  std::vector<int> tri(count, -1);
  const auto d_to = [&](int t, int x, int y, int z) {
    const auto& corners = surface.triangles[static_cast<std::size_t>(t)];
    const Vec3 p = f.sample_position(x, y, z);
    return point_triangle_distance(p, surface.vertices[corners[0]], surface.vertices[corners[1]],
                                   surface.vertices[corners[2]]);
  };
  struct Sample {
    int x, y, z;
  };
  std::vector<Sample> frontier, next;
  for (std::size_t t = 0; t < surface.triangles.size(); ++t) {
    const auto& v = surface.triangles[t];
    int lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      const double mn = std::min({surface.vertices[v[0]][a], surface.vertices[v[1]][a],
                                  surface.vertices[v[2]][a]}) - 2.0 * h;
      const double mx = std::max({surface.vertices[v[0]][a], surface.vertices[v[1]][a],
                                  surface.vertices[v[2]][a]}) + 2.0 * h;
      const double o = f.sample_position(0, 0, 0)[a];
      lo[a] = std::max(0, static_cast<int>(std::ceil((mn - o) / h)));
      hi[a] = std::min(m - 1, static_cast<int>(std::floor((mx - o) / h)));
    }
    for (int z = lo[2]; z <= hi[2]; ++z) {
      for (int y = lo[1]; y <= hi[1]; ++y) {
        for (int x = lo[0]; x <= hi[0]; ++x) {
          const double d = d_to(static_cast<int>(t), x, y, z);
          const std::size_t r = at(x, y, z);
          if (tri[r] < 0) frontier.push_back({x, y, z});
          if (d < dist[r]) {
            dist[r] = d;
            tri[r] = static_cast<int>(t);
          }
        }
      }
    }
  }
  const auto sign = [&](int x, int y, int z) {
    return grid.solid(stride * (x - pad), stride * (y - pad), stride * (z - pad)) ? -1.0 : 1.0;
  };
  const int step[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  while (!frontier.empty()) {
    next.clear();
    for (const Sample& s : frontier) {
      const int t = tri[at(s.x, s.y, s.z)];
      for (const auto& o : step) {
        const int x = s.x + o[0], y = s.y + o[1], z = s.z + o[2];
        if (x < 0 || y < 0 || z < 0 || x >= m || y >= m || z >= m) continue;
        const double d = d_to(t, x, y, z);
        if (d >= (sign(x, y, z) < 0.0 ? c_in : c_out) + 2.0 * h) continue;
        const std::size_t r = at(x, y, z);
        if (tri[r] < 0) next.push_back({x, y, z});
        if (d < dist[r]) {
          dist[r] = d;
          tri[r] = t;
        }
      }
    }
    frontier.swap(next);
  }
  std::vector<std::vector<int>> star(surface.vertices.size());
  for (std::size_t t = 0; t < surface.triangles.size(); ++t) {
    for (const int v : surface.triangles[t]) {
      star[static_cast<std::size_t>(v)].push_back(static_cast<int>(t));
    }
  }
  long band_samples = 0, walked = 0;
  for (int z = 0; z < m; ++z) {
    for (int y = 0; y < m; ++y) {
      for (int x = 0; x < m; ++x) {
        const std::size_t r = at(x, y, z);
        const double sg = sign(x, y, z);
        if (tri[r] >= 0 && dist[r] >= 2.0 * h) {
          ++walked;
          for (int walk = 0; walk < 64; ++walk) {
            const int at_t = tri[r];
            for (const int v : surface.triangles[static_cast<std::size_t>(at_t)]) {
              for (const int t : star[static_cast<std::size_t>(v)]) {
                const double d = d_to(t, x, y, z);
                if (d < dist[r]) {
                  dist[r] = d;
                  tri[r] = t;
                }
              }
            }
            if (tri[r] == at_t) break;
          }
        }
        if (tri[r] < 0) {  // beyond the band: a clamp (its brick's side)
          const float a = std::abs(f.at(x, y, z));
          EXPECT_TRUE(a == static_cast<float>(c_in) || a == static_cast<float>(c_out))
              << what << ": " << x << " " << y << " " << z;
          if (a != static_cast<float>(c_in) && a != static_cast<float>(c_out)) return -1;
          continue;
        }
        ++band_samples;
        const float expected = static_cast<float>(std::clamp(sg * dist[r], -c_in, c_out));
        EXPECT_EQ(f.at(x, y, z), expected) << what << ": " << x << " " << y << " " << z;
        if (f.at(x, y, z) != expected) return -1;
      }
    }
  }
  EXPECT_GT(walked, band_samples / 10) << what;
  return band_samples;
}

// The build (sampled_field.h "Build") skips layer 0's distances whose lower bound cannot win and
// the walks' repeats, and its inputs come from the faster triangulation and inside test (issue
// #30: the field at 512^3); its stored values must be the definition's, bit for bit, at strides
// 1, 2 and 3, for the procedural molar (its surface bisected onto molar_solid itself, not the
// build's faster MolarSolidTest) and for a mesh tooth (the molar's coarse triangles, voxelised by
// the mesh voxeliser at a finer grid: triangles much larger than a voxel, as a scan's or an STL's).
TEST(SampledField, BuildIsThePlainDefinitionAtStrides1To3OnTheMolarAndAMesh) {
  const MolarParams params;
  const VoxelGrid molar = voxelize_procedural_molar(params, 64);
  const TriangleMesh molar_surface =
      triangulate_voxel_signs(molar, [&](const Vec3& in, const Vec3& out) {
        Vec3 p_in = in, p_out = out;
        for (int it = 0; it < 40; ++it) {
          const Vec3 mid = 0.5 * (p_in + p_out);
          (molar_solid(params, mid) ? p_in : p_out) = mid;
        }
        return Vec3(0.5 * (p_in + p_out));
      });
  TriangleMesh mesh = triangulate_implicit(voxelize_procedural_molar(params, 16),
                                           [&](const Vec3& p) { return molar_solid(params, p); });
  VoxelizeOptions options;
  options.resolution = 64;
  const VoxelGrid mesh_grid = voxelize_mesh(mesh, options);
  for (const int stride : {1, 2, 3}) {
    const long molar_band = expect_build_is_the_plain_definition(
        molar, molar_surface, stride, "molar, stride " + std::to_string(stride));
    const long mesh_band = expect_build_is_the_plain_definition(
        mesh_grid, mesh, stride, "mesh, stride " + std::to_string(stride));
    EXPECT_GT(molar_band, 40000 / (stride * stride)) << stride;
    EXPECT_GT(mesh_band, 40000 / (stride * stride)) << stride;
  }
}

// Every sample, row bound, the Lipschitz constant and the brick count of two fields.
void expect_same_field(const SampledField& a, const SampledField& b, const std::string& what) {
  ASSERT_EQ(a.samples_per_axis(), b.samples_per_axis()) << what;
  EXPECT_EQ(a.brick_count(), b.brick_count()) << what;
  EXPECT_EQ(a.lipschitz(), b.lipschitz()) << what;
  const int m = a.samples_per_axis();
  long differ = 0;
  for (int z = 0; z < m; ++z) {
    for (int y = 0; y < m; ++y) {
      for (int x = 0; x < m; ++x) {
        differ += a.at(x, y, z) != b.at(x, y, z) ? 1 : 0;
        if (x % kFieldBrick == 0) {
          differ += a.row_bound(x / kFieldBrick, y, z) != b.row_bound(x / kFieldBrick, y, z);
        }
      }
    }
  }
  EXPECT_EQ(differ, 0) << what;
}

// Issue #30 (the setup on two cores): the surface's vertices and the field's samples are made on
// several threads, each on a disjoint part (sampled_field.h); the results must be the one-thread
// ones bit for bit whatever the thread count: the molar's triangulation, and the fields of the
// molar (strides 1 and 2) and of a mesh tooth (coarse triangles on a finer grid), at 1, 2, 3 and
// 7 threads (7 more than the z-layers of bricks of the coarser fields: idle threads).
TEST(SampledField, ThreadedBuildIsTheOneThreadBuildAt1To7Threads) {
  const MolarParams params;
  const VoxelGrid molar = voxelize_procedural_molar(params, 64);
  const MolarSolidTest inside(params);
  const TriangleMesh one = triangulate_implicit(molar, inside, 1);
  EXPECT_GT(one.triangles.size(), 20000u);
  TriangleMesh mesh = triangulate_implicit(voxelize_procedural_molar(params, 16), inside, 1);
  VoxelizeOptions options;
  options.resolution = 64;
  const VoxelGrid mesh_grid = voxelize_mesh(mesh, options);
  std::vector<SampledField> single;
  for (const int stride : {1, 2}) {
    single.push_back(build_sampled_field(
        molar, one, field_band_for_tip(0.5e-3, molar.voxel_size, stride), 1));
    single.push_back(build_sampled_field(
        mesh_grid, mesh, field_band_for_tip(0.5e-3, mesh_grid.voxel_size, stride), 1));
  }
  EXPECT_GT(single[0].brick_count(), 100u);
  for (const int threads : {1, 2, 3, 7}) {
    const std::string at = " at " + std::to_string(threads) + " threads";
    expect_same_mesh(triangulate_implicit(molar, inside, threads), one, "molar 64^3" + at);
    for (const int stride : {1, 2}) {
      const std::size_t q = 2 * static_cast<std::size_t>(stride - 1);
      expect_same_field(
          build_sampled_field(molar, one,
                              field_band_for_tip(0.5e-3, molar.voxel_size, stride), threads),
          single[q], "molar, stride " + std::to_string(stride) + at);
      expect_same_field(
          build_sampled_field(mesh_grid, mesh,
                              field_band_for_tip(0.5e-3, mesh_grid.voxel_size, stride), threads),
          single[q + 1], "mesh, stride " + std::to_string(stride) + at);
    }
  }
}

}  // namespace
}  // namespace dentsim
