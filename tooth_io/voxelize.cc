#include "tooth_io/voxelize.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <limits>
#include <utility>

#include "reference/core/io.h"
#include "reference/core/setup_threads.h"

namespace dentsim {
namespace {

using Mask = std::vector<std::uint8_t>;

std::vector<int> all_or(const TriangleMesh& mesh, const std::vector<int>& triangles) {
  if (!triangles.empty()) return triangles;
  std::vector<int> all(mesh.triangles.size());
  for (std::size_t t = 0; t < all.size(); ++t) all[t] = static_cast<int>(t);
  return all;
}

// Index range [lo, hi] of voxels along one axis whose closed extent may meet [a, b].
std::pair<int, int> voxel_range(double a, double b, double origin, double h, int n) {
  const double slack = 1e-7;  // so a bound lying on a voxel face includes both voxels
  const int lo = static_cast<int>(std::floor((a - origin) / h - slack));
  const int hi = static_cast<int>(std::floor((b - origin) / h + slack));
  return {std::max(lo, 0), std::min(hi, n - 1)};
}

// Index range [lo, hi] of voxel centres origin + h (i + 1/2) that may lie in [a, b] (one extra
// on each side: the crossing test decides exactly).
std::pair<int, int> center_range(double a, double b, double origin, double h, int n) {
  const int lo = static_cast<int>(std::floor((a - origin) / h - 0.5)) - 1;
  const int hi = static_cast<int>(std::ceil((b - origin) / h - 0.5)) + 1;
  return {std::max(lo, 0), std::min(hi, n - 1)};
}

// One axis of the SAT: separated if the triangle's projection misses [-r, r].
bool separated(double p0, double p1, double p2, double r) {
  const double mn = std::min({p0, p1, p2});
  const double mx = std::max({p0, p1, p2});
  return mn > r || mx < -r;
}

// 1D squared distance transform (Felzenszwalb & Huttenlocher 2012, Algorithm 1):
// d[q] = min_p (q - p)^2 + f[p], for f finite.
void distance_transform_1d(const std::vector<double>& f, int n, std::vector<double>& d,
                           std::vector<int>& v, std::vector<double>& z) {
  int k = 0;
  v[0] = 0;
  z[0] = -std::numeric_limits<double>::infinity();
  z[1] = std::numeric_limits<double>::infinity();
  auto intersect = [&](int q, int p) {
    return ((f[q] + double(q) * q) - (f[p] + double(p) * p)) / (2.0 * q - 2.0 * p);
  };
  for (int q = 1; q < n; ++q) {
    double s = intersect(q, v[k]);
    while (s <= z[k]) s = intersect(q, v[--k]);  // terminates: z[0] = -infinity
    ++k;
    v[k] = q;
    z[k] = s;
    z[k + 1] = std::numeric_limits<double>::infinity();
  }
  k = 0;
  for (int q = 0; q < n; ++q) {
    while (z[k + 1] < q) ++k;
    const double dq = q - v[k];
    d[q] = dq * dq + f[v[k]];
  }
}

// Clipped squared EDT over the box [lo, hi] (inclusive) of `grid`; returns box-local values,
// index (i - lo.x) + bx * ((j - lo.y) + by * (k - lo.z)). Empty voxels outside the box are not
// seen: callers pass a box with an empty margin around the solid.
std::vector<std::uint16_t> edt_box(const VoxelGrid& grid, const std::array<int, 3>& lo,
                                   const std::array<int, 3>& hi, int clip) {
  const int bx = hi[0] - lo[0] + 1, by = hi[1] - lo[1] + 1, bz = hi[2] - lo[2] + 1;
  const double cap = double(clip) * clip;
  std::vector<std::uint16_t> out(static_cast<std::size_t>(bx) * by * bz);
  auto at = [&](int i, int j, int k) -> std::uint16_t& {
    return out[static_cast<std::size_t>(i) +
               static_cast<std::size_t>(bx) *
                   (static_cast<std::size_t>(j) + static_cast<std::size_t>(by) * k)];
  };
  // Threads (issue #30, reference/core/setup_threads.h): every line of a pass is transformed on
  // its own, a plane of lines a task, so each value is the one-thread one whatever the count.
  // Pass 1 (x): distance along the row to the nearest empty voxel, clipped.
  parallel_tasks(bz, 0, [&](int k) {
    for (int j = 0; j < by; ++j) {
      int run = clip;
      for (int i = 0; i < bx; ++i) {
        run = grid.solid(lo[0] + i, lo[1] + j, lo[2] + k) ? std::min(run + 1, clip) : 0;
        at(i, j, k) = static_cast<std::uint16_t>(run);
      }
      run = clip;
      for (int i = bx - 1; i >= 0; --i) {
        run = at(i, j, k) == 0 ? 0 : std::min(run + 1, clip);
        const int d = std::min<int>(at(i, j, k), run);
        at(i, j, k) = static_cast<std::uint16_t>(d);
      }
      for (int i = 0; i < bx; ++i) {
        const int d = at(i, j, k);
        at(i, j, k) = static_cast<std::uint16_t>(std::min<double>(double(d) * d, cap));
      }
    }
  });
  // Passes 2 (y) and 3 (z): lower envelopes of parabolas.
  const int m = std::max({bx, by, bz});
  struct Scratch {
    std::vector<double> f, d, z;
    std::vector<int> v;
  };
  // One line of `len` samples, the q-th at `cell(q)`. A line of zeros (all empty) stays zeros,
  // one all at the cap stays there (every parabola is >= cap): both are skipped.
  const auto capped = static_cast<std::uint16_t>(cap);
  auto transform_line = [&](Scratch& sc, int len, auto&& cell) {
    std::vector<double>& f = sc.f;
    std::vector<double>& d = sc.d;
    std::vector<double>& z = sc.z;
    std::vector<int>& v = sc.v;
    bool zeros = true, at_cap = true;
    for (int q = 0; q < len; ++q) {
      const std::uint16_t c = cell(q);
      f[q] = c;
      zeros = zeros && c == 0;
      at_cap = at_cap && c == capped;
    }
    if (zeros || at_cap) return;
    distance_transform_1d(f, len, d, v, z);
    for (int q = 0; q < len; ++q) cell(q) = static_cast<std::uint16_t>(std::min(d[q], cap));
  };
  const auto scratch = [m] {
    return Scratch{std::vector<double>(static_cast<std::size_t>(m)),
                   std::vector<double>(static_cast<std::size_t>(m)),
                   std::vector<double>(static_cast<std::size_t>(m) + 1),
                   std::vector<int>(static_cast<std::size_t>(m))};
  };
  parallel_tasks(bz, 0, [&](int k) {
    Scratch sc = scratch();
    for (int i = 0; i < bx; ++i) {
      transform_line(sc, by, [&](int j) -> std::uint16_t& { return at(i, j, k); });
    }
  });
  parallel_tasks(by, 0, [&](int j) {
    Scratch sc = scratch();
    for (int i = 0; i < bx; ++i) {
      transform_line(sc, bz, [&](int k) -> std::uint16_t& { return at(i, j, k); });
    }
  });
  return out;
}

bool is_pulp_group(const std::string& name) {
  std::string s = name;
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s == "nerve" || s == "pulp";
}

}  // namespace

bool triangle_box_overlap(const Vec3& center, const Vec3& half_in, const Vec3& a, const Vec3& b,
                          const Vec3& c) {
  // Boxes are closed; a relative 1e-9 guard keeps touching contacts under round-off.
  const Vec3 half = half_in * (1 + 1e-9);
  const Vec3 v0 = a - center, v1 = b - center, v2 = c - center;
  const std::array<Vec3, 3> e = {v1 - v0, v2 - v1, v0 - v2};
  // 9 axes u_i x e_j (u_i the box axes).
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 3; ++i) {
      const Vec3 axis = Vec3::Unit(i).cross(e[j]);
      const double r = half.dot(axis.cwiseAbs());
      if (separated(axis.dot(v0), axis.dot(v1), axis.dot(v2), r)) return false;
    }
  }
  // 3 box face normals: the triangle's bounding box against the box.
  for (int i = 0; i < 3; ++i) {
    if (separated(v0[i], v1[i], v2[i], half[i])) return false;
  }
  // The triangle's plane.
  const Vec3 n = e[0].cross(e[1]);
  return std::abs(n.dot(v0)) <= half.dot(n.cwiseAbs());
}

VoxelGrid make_grid(const Aabb& bounds, int resolution, int margin_voxels) {
  if (resolution < 4 || resolution > 1024 || (resolution & (resolution - 1)) != 0) {
    throw InputError("resolution " + std::to_string(resolution) +
                     ": expected a power of two from 4 to 1024 (e.g. 32, 256, 512)");
  }
  if (margin_voxels < 1 || 2 * margin_voxels >= resolution) {
    throw InputError("margin " + std::to_string(margin_voxels) + " voxels: expected 1.." +
                     std::to_string(resolution / 2 - 1));
  }
  const double extent = bounds.extent().maxCoeff();
  if (!(extent > 0) || !std::isfinite(extent)) {
    throw InputError("tooth bounds have zero or non-finite extent; expected a solid");
  }
  const double h = extent / (resolution - 2 * margin_voxels);
  const Vec3 mid = 0.5 * (bounds.min + bounds.max);
  return VoxelGrid(resolution, mid - Vec3::Constant(0.5 * h * resolution), h);
}

std::vector<std::uint8_t> surface_voxels(const TriangleMesh& mesh, const VoxelGrid& grid,
                                         const std::vector<int>& triangles) {
  const int n = grid.n;
  const double h = grid.voxel_size;
  const Vec3 half = Vec3::Constant(0.5 * h);
  Mask out(static_cast<std::size_t>(n) * n * n, 0);
  for (int t : all_or(mesh, triangles)) {
    const auto& tri = mesh.triangles[t];
    const Vec3& a = mesh.vertices[tri[0]];
    const Vec3& b = mesh.vertices[tri[1]];
    const Vec3& c = mesh.vertices[tri[2]];
    const Vec3 mn = a.cwiseMin(b).cwiseMin(c);
    const Vec3 mx = a.cwiseMax(b).cwiseMax(c);
    const auto [i0, i1] = voxel_range(mn.x(), mx.x(), grid.origin.x(), h, n);
    const auto [j0, j1] = voxel_range(mn.y(), mx.y(), grid.origin.y(), h, n);
    const auto [k0, k1] = voxel_range(mn.z(), mx.z(), grid.origin.z(), h, n);
    for (int k = k0; k <= k1; ++k) {
      for (int j = j0; j <= j1; ++j) {
        for (int i = i0; i <= i1; ++i) {
          const std::size_t idx = grid.index(i, j, k);
          if (out[idx] == 0 && triangle_box_overlap(grid.center(i, j, k), half, a, b, c)) {
            out[idx] = 1;
          }
        }
      }
    }
  }
  return out;
}

std::vector<std::uint8_t> seed_fill_outside(const std::vector<std::uint8_t>& barrier, int n) {
  Mask out(barrier.size(), 0);
  auto idx = [n](int i, int j, int k) {
    return static_cast<std::size_t>(i) +
           static_cast<std::size_t>(n) *
               (static_cast<std::size_t>(j) + static_cast<std::size_t>(n) * k);
  };
  auto fillable = [&](int i, int j, int k) {
    const std::size_t x = idx(i, j, k);
    return barrier[x] == 0 && out[x] == 0;
  };
  std::vector<std::array<int, 3>> stack;
  // Seeds: every voxel on the six faces of the grid.
  for (int a = 0; a < n; ++a) {
    for (int b = 0; b < n; ++b) {
      for (int f : {0, n - 1}) {
        stack.push_back({f, a, b});
        stack.push_back({a, f, b});
        stack.push_back({a, b, f});
      }
    }
  }
  while (!stack.empty()) {
    const auto [i, j, k] = stack.back();
    stack.pop_back();
    if (!fillable(i, j, k)) continue;
    // Fill the whole x-span through (i, j, k) ...
    int i0 = i, i1 = i;
    while (i0 > 0 && fillable(i0 - 1, j, k)) --i0;
    while (i1 < n - 1 && fillable(i1 + 1, j, k)) ++i1;
    for (int x = i0; x <= i1; ++x) out[idx(x, j, k)] = 1;
    // ... and seed one voxel per run of fillable voxels in the four neighbouring rows.
    const std::array<std::array<int, 2>, 4> rows = {
        {{j - 1, k}, {j + 1, k}, {j, k - 1}, {j, k + 1}}};
    for (const auto& [jj, kk] : rows) {
      if (jj < 0 || kk < 0 || jj >= n || kk >= n) continue;
      bool in_run = false;
      for (int x = i0; x <= i1; ++x) {
        if (fillable(x, jj, kk)) {
          if (!in_run) stack.push_back({x, jj, kk});
          in_run = true;
        } else {
          in_run = false;
        }
      }
    }
  }
  return out;
}

std::vector<std::uint8_t> center_winding_inside(const TriangleMesh& mesh, const VoxelGrid& grid,
                                                const std::vector<int>& triangles) {
  const int n = grid.n;
  const double h = grid.voxel_size;
  Mask out(static_cast<std::size_t>(n) * n * n, 0);
  // Bucket the triangles by the rows of voxel centres their z-range may cover.
  std::vector<std::vector<int>> by_k(n);
  for (int t : all_or(mesh, triangles)) {
    const auto& tri = mesh.triangles[t];
    const double z0 =
        std::min({mesh.vertices[tri[0]].z(), mesh.vertices[tri[1]].z(), mesh.vertices[tri[2]].z()});
    const double z1 =
        std::max({mesh.vertices[tri[0]].z(), mesh.vertices[tri[1]].z(), mesh.vertices[tri[2]].z()});
    const auto [k0, k1] = center_range(z0, z1, grid.origin.z(), h, n);
    for (int k = k0; k <= k1; ++k) by_k[k].push_back(t);
  }
  std::vector<std::vector<std::pair<double, int>>> rows(n);
  for (int k = 0; k < n; ++k) {
    if (by_k[k].empty()) continue;
    for (auto& r : rows) r.clear();
    const double zc = grid.center(0, 0, k).z();
    for (int t : by_k[k]) {
      const auto& tri = mesh.triangles[t];
      const Vec3& a = mesh.vertices[tri[0]];
      const Vec3& b = mesh.vertices[tri[1]];
      const Vec3& c = mesh.vertices[tri[2]];
      const auto [j0, j1] = center_range(std::min({a.y(), b.y(), c.y()}),
                                         std::max({a.y(), b.y(), c.y()}), grid.origin.y(), h, n);
      for (int j = j0; j <= j1; ++j) {
        double x;
        int s;
        if (line_crossing_x(a, b, c, grid.center(0, j, 0).y(), zc, &x, &s)) {
          rows[j].emplace_back(x, s);
        }
      }
    }
    for (int j = 0; j < n; ++j) {
      auto& r = rows[j];
      if (r.empty()) continue;
      std::sort(r.begin(), r.end());
      int w = 0;  // winding = entries minus exits left of the centre
      std::size_t p = 0;
      for (int i = 0; i < n; ++i) {
        const double xc = grid.center(i, 0, 0).x();
        while (p < r.size() && r[p].first < xc) w += r[p++].second;
        out[grid.index(i, j, k)] = w != 0 ? 1 : 0;
      }
    }
  }
  return out;
}

std::vector<std::uint8_t> voxelize_solid(const TriangleMesh& mesh, const VoxelGrid& grid,
                                         const std::vector<int>& triangles, SolidStats* stats) {
  Mask solid = surface_voxels(mesh, grid, triangles);                       // stage 1
  const Mask outside = seed_fill_outside(solid, grid.n);                    // stage 2
  const Mask center_inside = center_winding_inside(mesh, grid, triangles);  // stage 3
  SolidStats s;
  for (std::size_t x = 0; x < solid.size(); ++x) {
    const bool surface = solid[x] != 0;
    if (surface) {
      ++s.surface_voxels;
      solid[x] = center_inside[x];
      s.surface_solid_voxels += center_inside[x];
    } else if (outside[x] != 0) {
      ++s.outside_voxels;
    } else {
      ++s.interior_voxels;
      solid[x] = 1;
    }
  }
  if (stats != nullptr) *stats = s;
  return solid;
}

CrownFrame estimate_crown_frame(const std::vector<std::uint8_t>& solid, const VoxelGrid& grid,
                                double crown_fraction) {
  const int n = grid.n;
  std::array<int, 3> lo = {n, n, n}, hi = {-1, -1, -1};
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        if (solid[grid.index(i, j, k)] == 0) continue;
        const std::array<int, 3> p = {i, j, k};
        for (int d = 0; d < 3; ++d) {
          lo[d] = std::min(lo[d], p[d]);
          hi[d] = std::max(hi[d], p[d]);
        }
      }
    }
  }
  if (hi[0] < 0) throw InputError("voxelised tooth is empty; expected a solid");
  int a = 0;
  for (int d = 1; d < 3; ++d) {
    if (hi[d] - lo[d] > hi[a] - lo[a]) a = d;
  }
  const int len = hi[a] - lo[a] + 1;
  const int slab = std::max(1, static_cast<int>(std::lround(0.15 * len)));
  long low_count = 0, high_count = 0;
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        if (solid[grid.index(i, j, k)] == 0) continue;
        const int p = a == 0 ? i : (a == 1 ? j : k);
        if (p < lo[a] + slab) ++low_count;
        if (p > hi[a] - slab) ++high_count;
      }
    }
  }
  const double h = grid.voxel_size;
  const double length = len * h;
  CrownFrame crown;
  crown.crown_height = crown_fraction * length;
  if (high_count >= low_count) {
    crown.axis = Vec3::Unit(a);
    crown.cej = grid.origin[a] + (hi[a] + 1) * h - crown.crown_height;
  } else {
    crown.axis = -Vec3::Unit(a);
    crown.cej = -(grid.origin[a] + lo[a] * h) - crown.crown_height;
  }
  return crown;
}

std::vector<std::uint16_t> distance_to_empty_sq(const VoxelGrid& grid, int clip) {
  if (clip < 1 || clip > 255) throw InputError("distance clip: expected 1..255 voxels");
  return edt_box(grid, {0, 0, 0}, {grid.n - 1, grid.n - 1, grid.n - 1}, clip);
}

void assign_materials(VoxelGrid& grid, const std::vector<std::uint8_t>& pulp,
                      const CrownFrame& crown, double enamel_cusp_m) {
  const int n = grid.n;
  const double h = grid.voxel_size;
  std::array<int, 3> lo = {n, n, n}, hi = {-1, -1, -1};
  // The bounds of the dentin voxels at or above the CEJ (s >= 0 below): the only ones that can
  // turn to enamel, so the only ones whose depth is needed.
  std::array<int, 3> crown_lo = {n, n, n}, crown_hi = {-1, -1, -1};
  // A plane a task, each with its own bounds (issue #30: threads; a voxel reads and writes only
  // itself), then the planes' bounds combined: min and max, the same whatever the count.
  struct Bounds {
    std::array<int, 3> lo, hi, crown_lo, crown_hi;
  };
  std::vector<Bounds> planes(static_cast<std::size_t>(std::max(n, 0)),
                             Bounds{lo, hi, crown_lo, crown_hi});
  parallel_tasks(n, 0, [&](int k) {
    Bounds& b = planes[static_cast<std::size_t>(k)];
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const std::size_t x = grid.index(i, j, k);
        if (grid.voxels[x] == 0) continue;
        grid.voxels[x] =
            (grid.voxels[x] == kPulp || (!pulp.empty() && pulp[x] != 0)) ? kPulp : kDentin;
        const std::array<int, 3> p = {i, j, k};
        for (int d = 0; d < 3; ++d) {
          b.lo[d] = std::min(b.lo[d], p[d]);
          b.hi[d] = std::max(b.hi[d], p[d]);
        }
        // The test of the enamel loop below, on the same expression.
        if (grid.voxels[x] == kDentin && !(crown.axis.dot(grid.center(i, j, k)) - crown.cej < 0)) {
          for (int d = 0; d < 3; ++d) {
            b.crown_lo[d] = std::min(b.crown_lo[d], p[d]);
            b.crown_hi[d] = std::max(b.crown_hi[d], p[d]);
          }
        }
      }
    }
  });
  for (const Bounds& plane : planes) {
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], plane.lo[d]);
      hi[d] = std::max(hi[d], plane.hi[d]);
      crown_lo[d] = std::min(crown_lo[d], plane.crown_lo[d]);
      crown_hi[d] = std::max(crown_hi[d], plane.crown_hi[d]);
    }
  }
  if (crown_hi[0] < 0 || !(enamel_cusp_m > 0)) return;
  const double height = crown.crown_height;
  const double t_top = enamel_cusp_m < height ? enamel_cusp_m * height / (height - enamel_cusp_m)
                                              : std::numeric_limits<double>::infinity();
  for (int d = 0; d < 3; ++d) {  // an empty margin (the grid's own border counts as empty)
    lo[d] = std::max(lo[d] - 1, 0);
    hi[d] = std::min(hi[d] + 1, n - 1);
  }
  const int clip =
      std::min(255, static_cast<int>(std::ceil(std::min(enamel_cusp_m, n * h) / h)) + 2);
  // The distances over the crown's dentin and `clip` voxels around it (within the box above):
  // a clipped distance sees only the empty voxels closer than `clip`, so at those voxels it is
  // the whole box's, bit for bit (tests/tooth_io/voxelize_test.cc).
  for (int d = 0; d < 3; ++d) {
    lo[d] = std::max(lo[d], crown_lo[d] - clip);
    hi[d] = std::min(hi[d], crown_hi[d] + clip);
  }
  const auto d2 = edt_box(grid, lo, hi, clip);
  const int bx = hi[0] - lo[0] + 1, by = hi[1] - lo[1] + 1;
  // A plane of voxels a task (each voxel reads and writes only itself): any thread count.
  parallel_tasks(hi[2] - lo[2] + 1, 0, [&](int plane) {
    const int k = lo[2] + plane;
    for (int j = lo[1]; j <= hi[1]; ++j) {
      for (int i = lo[0]; i <= hi[0]; ++i) {
        const std::size_t x = grid.index(i, j, k);
        if (grid.voxels[x] != kDentin) continue;
        const double s = crown.axis.dot(grid.center(i, j, k)) - crown.cej;  // height above CEJ
        if (s < 0) continue;
        const double t = std::min(enamel_cusp_m, t_top * s / height);  // t(s)
        const std::size_t b =
            static_cast<std::size_t>(i - lo[0]) +
            static_cast<std::size_t>(bx) *
                (static_cast<std::size_t>(j - lo[1]) + static_cast<std::size_t>(by) * (k - lo[2]));
        // Depth below the surface ~ centre-to-empty-centre distance minus half a voxel.
        if ((std::sqrt(double(d2[b])) - 0.5) * h < t) grid.voxels[x] = kEnamel;
      }
    }
  });
}

VoxelGrid voxelize_mesh(const TriangleMesh& mesh, const VoxelizeOptions& options,
                        VoxelizeReport* report) {
  VoxelizeReport r;
  VoxelGrid grid = make_grid(mesh_bounds(mesh), options.resolution, options.margin_voxels);
  grid.voxels = voxelize_solid(mesh, grid, {}, &r.solid);
  std::vector<int> pulp_triangles;
  for (int t = 0; t < static_cast<int>(mesh.triangles.size()); ++t) {
    const std::string& g = mesh.groups[mesh.triangle_group[t]];
    if (!is_pulp_group(g)) continue;
    pulp_triangles.push_back(t);
    if (std::find(r.pulp_groups.begin(), r.pulp_groups.end(), g) == r.pulp_groups.end()) {
      r.pulp_groups.push_back(g);
    }
  }
  Mask pulp;
  if (!pulp_triangles.empty()) pulp = voxelize_solid(mesh, grid, pulp_triangles);
  r.crown = estimate_crown_frame(grid.voxels, grid, options.crown_fraction);
  assign_materials(grid, pulp, r.crown, options.enamel_cusp_m);
  r.pulp_voxels = count_materials(grid)[kPulp];
  if (report != nullptr) *report = r;
  return grid;
}

std::vector<long> count_materials(const VoxelGrid& grid) {
  std::vector<long> counts(kMaterialCount, 0);
  for (std::uint8_t m : grid.voxels) {
    if (m < kMaterialCount) ++counts[m];
  }
  return counts;
}

}  // namespace dentsim
