// The sampled signed-distance field of the tooth (reference/tooth/sampled_field.h). Beyond the
// thesis; derivation in docs/derivations/field_contact.md.
#include "reference/tooth/sampled_field.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <bit>
#include <stdexcept>
#include <string>
#include <tuple>

namespace dentsim {

FieldBand field_band_for_tip(double rho, double voxel_size, int stride) {
  FieldBand band;
  const double spacing = stride * voxel_size;
  band.outside_m = 1.25 * rho + 2.0 * spacing;
  band.inside_m = 2.0 * spacing;
  band.stride = stride;
  return band;
}

double field_max_spacing(double rho) {
  const double wall = (1.0 - 1e-9) * 2.0 * (rho - 0.25 * rho) / std::sqrt(3.0);
  const double ripple = rho * kFieldRippleAim / kFieldRipplePerSpacing;
  return std::min(wall, ripple);
}

int field_stride_for(double rho, double voxel_size, double spacing_m) {
  const double target = spacing_m > 0.0 ? spacing_m * (1.0 + 1e-9) : field_max_spacing(rho);
  const double k = std::floor(target / voxel_size);
  return k >= 1.0 ? static_cast<int>(std::min(k, 64.0)) : 1;
}

// Closest point on a triangle by its Voronoi regions (vertex, edge, face), then the distance.
double point_triangle_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return ap.norm();  // vertex a
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return bp.norm();  // vertex b
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {  // edge ab
    const double v = d1 / (d1 - d3);
    return (p - (a + v * ab)).norm();
  }
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return cp.norm();  // vertex c
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {  // edge ac
    const double w = d2 / (d2 - d6);
    return (p - (a + w * ac)).norm();
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {  // edge bc
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return (p - (b + w * (c - b))).norm();
  }
  const double denom = 1.0 / (va + vb + vc);  // face
  const double v = vb * denom, w = vc * denom;
  return (p - (a + ab * v + ac * w)).norm();
}

float SampledField::at(int sx, int sy, int sz) const {
  const std::int32_t id = index_[slot(sx / kFieldBrick, sy / kFieldBrick, sz / kFieldBrick)];
  if (id >= 0) {
    const int lx = sx % kFieldBrick, ly = sy % kFieldBrick, lz = sz % kFieldBrick;
    return bricks_[static_cast<std::size_t>(id) * kBrickSamples +
                   static_cast<std::size_t>(lx + kFieldBrick * (ly + kFieldBrick * lz))];
  }
  return id == kAllOutside ? static_cast<float>(c_out_) : static_cast<float>(-c_in_);
}

bool SampledField::all_outside(const int lo[3], const int hi[3]) const {
  for (int bz = lo[2] / kFieldBrick; bz <= hi[2] / kFieldBrick; ++bz) {
    for (int by = lo[1] / kFieldBrick; by <= hi[1] / kFieldBrick; ++by) {
      for (int bx = lo[0] / kFieldBrick; bx <= hi[0] / kFieldBrick; ++bx) {
        if (index_[slot(bx, by, bz)] != kAllOutside) return false;
      }
    }
  }
  return true;
}

void SampledField::reserve_spare_bricks(std::size_t spare) {
  bricks_.reserve(bricks_.size() + spare * static_cast<std::size_t>(kBrickSamples));
  row_bounds_.reserve(row_bounds_.size() + spare * static_cast<std::size_t>(kBrickRows));
}

void SampledField::measure_row_bounds(std::int32_t id) {
  const float out_f = static_cast<float>(c_out_);
  const std::size_t first = static_cast<std::size_t>(id) * kBrickRows;
  if (row_bounds_.size() < first + kBrickRows) row_bounds_.resize(first + kBrickRows);
  for (int r = 0; r < kBrickRows; ++r) {
    float b = -1.0f;
    for (int x = 0; x < kFieldBrick; ++x) {
      const float v = bricks_[static_cast<std::size_t>(id) * kBrickSamples +
                              static_cast<std::size_t>(x + kFieldBrick * r)];
      if (v < out_f) b = std::max(b, std::abs(v));
    }
    row_bounds_[first + static_cast<std::size_t>(r)] = b;
  }
}

bool SampledField::raise(int sx, int sy, int sz, double value) {
  const float v = static_cast<float>(std::clamp(value, -c_in_, c_out_));
  const std::size_t sl = slot(sx / kFieldBrick, sy / kFieldBrick, sz / kFieldBrick);
  std::int32_t id = index_[sl];
  if (id < 0) {
    const float fill = id == kAllOutside ? static_cast<float>(c_out_) : static_cast<float>(-c_in_);
    if (!(v > fill)) return true;  // nothing to raise
    if (bricks_.size() + kBrickSamples > bricks_.capacity() ||
        row_bounds_.size() + kBrickRows > row_bounds_.capacity()) {
      return false;  // no spare brick
    }
    id = static_cast<std::int32_t>(bricks_.size() / kBrickSamples);
    bricks_.insert(bricks_.end(), static_cast<std::size_t>(kBrickSamples), fill);  // in capacity
    // Every sample is `fill` = -c_in (an all-outside slot is never raised: v <= c_out).
    row_bounds_.insert(row_bounds_.end(), static_cast<std::size_t>(kBrickRows), std::abs(fill));
    index_[sl] = id;
  }
  const int lx = sx % kFieldBrick, ly = sy % kFieldBrick, lz = sz % kFieldBrick;
  float& stored = bricks_[static_cast<std::size_t>(id) * kBrickSamples +
                          static_cast<std::size_t>(lx + kFieldBrick * (ly + kFieldBrick * lz))];
  stored = std::max(stored, v);
  if (stored < static_cast<float>(c_out_)) {  // the row bound covers the new value (header)
    float& bound = row_bounds_[static_cast<std::size_t>(id) * kBrickRows +
                               static_cast<std::size_t>(ly + kFieldBrick * lz)];
    bound = std::max(bound, std::abs(stored));
  }
  return true;
}

double SampledField::cell_lipschitz(int x, int y, int z) const {
  double c[8];
  for (int d = 0; d < 8; ++d) c[d] = at(x + (d & 1), y + ((d >> 1) & 1), z + (d >> 2));
  double mx = 0.0, my = 0.0, mz = 0.0;
  for (int e = 0; e < 4; ++e) {
    const int ix = 2 * e;                   // corners with x = 0: 0, 2, 4, 6
    const int iy = (e & 1) + 4 * (e >> 1);  // y = 0: 0, 1, 4, 5
    const int iz = e;                       // z = 0: 0, 1, 2, 3
    mx = std::max(mx, std::abs(c[ix + 1] - c[ix]));
    my = std::max(my, std::abs(c[iy + 2] - c[iy]));
    mz = std::max(mz, std::abs(c[iz + 4] - c[iz]));
  }
  return std::sqrt(mx * mx + my * my + mz * mz) / h_;
}

void SampledField::include_cells(const int lo[3], const int hi[3]) {
  int a[3], b[3];
  for (int k = 0; k < 3; ++k) {
    a[k] = std::max(0, lo[k] - 1);
    b[k] = std::min(m_ - 2, hi[k]);
  }
  double l = lipschitz_;
  for (int z = a[2]; z <= b[2]; ++z) {
    for (int y = a[1]; y <= b[1]; ++y) {
      for (int x = a[0]; x <= b[0]; ++x) l = std::max(l, cell_lipschitz(x, y, z));
    }
  }
  lipschitz_ = l;
}

namespace {

// The cell holding x: lower corner s (in [0, m - 2]) and the local coordinates t in [0, 1]^3.
void locate(const Vec3& origin, double h, int m, const Vec3& x, int s[3], double t[3]) {
  for (int a = 0; a < 3; ++a) {
    const double u = std::clamp((x[a] - origin[a]) / h, 0.0, static_cast<double>(m - 1));
    const int i = std::min(static_cast<int>(u), m - 2);
    s[a] = i;
    t[a] = u - i;
  }
}

}  // namespace

FieldSample SampledField::sample(const Vec3& x) const {
  FieldSample out;
  if (m_ < 2) return out;
  int s[3];
  double t[3];
  locate(origin_, h_, m_, x, s, t);
  double c[2][2][2];  // c[dx][dy][dz]
  for (int dz = 0; dz < 2; ++dz) {
    for (int dy = 0; dy < 2; ++dy) {
      for (int dx = 0; dx < 2; ++dx) c[dx][dy][dz] = at(s[0] + dx, s[1] + dy, s[2] + dz);
    }
  }
  const double tx = t[0], ty = t[1], tz = t[2];
  // Along x on the four x-edges, then y, then z.
  double ex[2][2], dx_edge[2][2];
  for (int dz = 0; dz < 2; ++dz) {
    for (int dy = 0; dy < 2; ++dy) {
      ex[dy][dz] = c[0][dy][dz] + tx * (c[1][dy][dz] - c[0][dy][dz]);
      dx_edge[dy][dz] = c[1][dy][dz] - c[0][dy][dz];
    }
  }
  const double ey0 = ex[0][0] + ty * (ex[1][0] - ex[0][0]);
  const double ey1 = ex[0][1] + ty * (ex[1][1] - ex[0][1]);
  out.value = ey0 + tz * (ey1 - ey0);
  // d/dx: bilinear (y, z) interpolation of the x-edge differences; likewise for y and z.
  const double gx0 = dx_edge[0][0] + ty * (dx_edge[1][0] - dx_edge[0][0]);
  const double gx1 = dx_edge[0][1] + ty * (dx_edge[1][1] - dx_edge[0][1]);
  const double gx = gx0 + tz * (gx1 - gx0);
  const double gy = (ex[1][0] - ex[0][0]) + tz * ((ex[1][1] - ex[0][1]) - (ex[1][0] - ex[0][0]));
  const double gz = ey1 - ey0;
  out.gradient = Vec3(gx, gy, gz) / h_;
  return out;
}

bool SampledField::deep_inside(const Vec3& x) const {
  if (m_ < 2) return false;
  int s[3];
  double t[3];
  locate(origin_, h_, m_, x, s, t);
  const float floor_value = static_cast<float>(-c_in_);
  for (int d = 0; d < 8; ++d) {
    if (at(s[0] + (d & 1), s[1] + ((d >> 1) & 1), s[2] + ((d >> 2) & 1)) != floor_value) {
      return false;
    }
  }
  return true;
}

SampledField build_sampled_field(const VoxelGrid& grid, const TriangleMesh& surface,
                                 const FieldBand& band, int threads) {
  if (threads <= 0) threads = setup_threads();
  SampledField f;
  // Stride (header comment): h below is the lattice's spacing H = k h_voxel; every length is in
  // it except where a voxel is named. At k = 1 every expression is the one-sample-per-voxel one.
  const int stride = std::max(1, band.stride);
  const double h_voxel = grid.voxel_size;
  const double h = stride * h_voxel;
  f.h_ = h;
  f.voxel_h_ = h_voxel;
  f.stride_ = stride;
  f.c_out_ = std::max(band.outside_m, 2.0 * h);
  f.c_in_ = band.inside_m > 0.0 ? std::max(band.inside_m, 2.0 * h) : 2.0 * h;
  f.pad_ = static_cast<int>(std::ceil(f.c_out_ / h)) + 2;
  // Samples on the grid: the voxel centres k s', s' in [0, (n - 1) / k].
  const int n = (grid.n - 1) / stride + 1;
  f.m_ = ((n + 2 * f.pad_ + kFieldBrick - 1) / kFieldBrick) * kFieldBrick;
  f.nb_ = f.m_ / kFieldBrick;
  f.origin_ = grid.origin + (0.5 - static_cast<double>(stride) * f.pad_) * h_voxel * Vec3::Ones();
  const int m = f.m_, pad = f.pad_;
  const std::size_t slots = static_cast<std::size_t>(f.nb_) * f.nb_ * f.nb_;
  constexpr int kB = SampledField::kBrickSamples;

  // Build state: per allocated brick, the nearest distance so far and its triangle (-1: none).
  std::vector<std::int32_t> id(slots, -1);
  std::vector<double> dist;
  std::vector<std::int32_t> tri;
  const auto sample_ref = [&](int sx, int sy, int sz, bool allocate) -> std::int64_t {
    const std::size_t sl = f.slot(sx / kFieldBrick, sy / kFieldBrick, sz / kFieldBrick);
    if (id[sl] < 0) {
      if (!allocate) return -1;
      id[sl] = static_cast<std::int32_t>(dist.size() / kB);
      dist.resize(dist.size() + kB, std::numeric_limits<double>::infinity());
      tri.resize(tri.size() + kB, -1);
    }
    const int lx = sx % kFieldBrick, ly = sy % kFieldBrick, lz = sz % kFieldBrick;
    return static_cast<std::int64_t>(id[sl]) * kB + lx + kFieldBrick * (ly + kFieldBrick * lz);
  };
  const auto distance_to = [&](int t, int sx, int sy, int sz) {
    const auto& v = surface.triangles[static_cast<std::size_t>(t)];
    return point_triangle_distance(f.sample_position(sx, sy, sz), surface.vertices[v[0]],
                                   surface.vertices[v[1]], surface.vertices[v[2]]);
  };
  struct S {
    int x, y, z;
  };
  std::vector<S> frontier, next;

  // Layer 0: exact distances within 2 h of each triangle (its box grown by 2 h): every sample
  // within 2 h > sqrt(3) h of the surface is exact (the no-tunnelling bound relies on it).
  // A sample that already has a distance skips the exact one when a lower bound of it (the
  // distance to the triangle's plane, or to its bounding box) exceeds the distance it has by
  // more than `slack`: the exact distance could not be smaller, so it would change nothing (the
  // update takes a strictly smaller one). `slack` (10^-6 h) dwarfs the bounds' rounding (~10^-16
  // of the coordinates), so the stored values are the same, bit for bit, as without the test
  // (tests/tooth/sampled_field_test.cc BuildSkipsOnlyDistancesThatCannotWin).
  const double slack = 1e-6 * h;
  // Triangle t's sample box [lo, hi] (empty when some lo > hi) and its own bounding box.
  const auto triangle_box = [&](std::size_t t, int lo[3], int hi[3], Vec3& box_lo, Vec3& box_hi) {
    const auto& v = surface.triangles[t];
    const Vec3& ta = surface.vertices[v[0]];
    const Vec3& tb = surface.vertices[v[1]];
    const Vec3& tc = surface.vertices[v[2]];
    for (int a = 0; a < 3; ++a) {
      box_lo[a] = std::min({ta[a], tb[a], tc[a]});
      box_hi[a] = std::max({ta[a], tb[a], tc[a]});
      const double mn = box_lo[a] - 2.0 * h;
      const double mx = box_hi[a] + 2.0 * h;
      lo[a] = std::max(0, static_cast<int>(std::ceil((mn - f.origin_[a]) / h)));
      hi[a] = std::min(m - 1, static_cast<int>(std::floor((mx - f.origin_[a]) / h)));
    }
    return lo[0] <= hi[0] && lo[1] <= hi[1] && lo[2] <= hi[2];
  };
  // Threads (issue #30): the bricks layer 0 reaches are allocated first (a brick holds a sample of
  // a triangle's box iff its brick range does), then each z-layer of bricks is one task, which
  // runs the triangles reaching it in index order over its own samples only. So every sample sees
  // the same triangles in the same order as in one pass over the triangles, with the same state
  // (its own dist and tri), and ends with the same values. The frontier, which the band's growth
  // reads in order (ties go to the first), is the one pass's: the tasks' lists (each in the one
  // pass's order: triangle, then z, y, x) merged by (triangle, z, y, x).
  // A task scans the index range of the triangles reaching its layer (no list of them is kept:
  // memory, issue #30); triangulate_voxel_signs makes its triangles slab by slab along z, so the
  // range of a layer holds few others.
  const int nb = f.nb_;
  std::vector<std::size_t> layer_begin(static_cast<std::size_t>(nb), surface.triangles.size()),
      layer_end(static_cast<std::size_t>(nb), 0);
  {
    std::vector<std::uint8_t> reached(slots, 0);
    for (std::size_t t = 0; t < surface.triangles.size(); ++t) {
      int lo[3], hi[3];
      Vec3 box_lo, box_hi;
      if (!triangle_box(t, lo, hi, box_lo, box_hi)) continue;
      for (int bz = lo[2] / kFieldBrick; bz <= hi[2] / kFieldBrick; ++bz) {
        layer_begin[static_cast<std::size_t>(bz)] =
            std::min(layer_begin[static_cast<std::size_t>(bz)], t);
        layer_end[static_cast<std::size_t>(bz)] = t + 1;
        for (int by = lo[1] / kFieldBrick; by <= hi[1] / kFieldBrick; ++by) {
          for (int bx = lo[0] / kFieldBrick; bx <= hi[0] / kFieldBrick; ++bx) {
            reached[f.slot(bx, by, bz)] = 1;
          }
        }
      }
    }
    for (std::size_t sl = 0; sl < slots; ++sl) {
      if (reached[sl] == 0) continue;
      id[sl] = static_cast<std::int32_t>(dist.size() / kB);
      dist.resize(dist.size() + kB, std::numeric_limits<double>::infinity());
      tri.resize(tri.size() + kB, -1);
    }
  }
  struct FirstVisit {
    std::int32_t t, z, y, x;
  };
  std::vector<std::vector<FirstVisit>> firsts(static_cast<std::size_t>(nb));
  parallel_tasks(nb, threads, [&](int bz) {
    std::vector<FirstVisit>& mine = firsts[static_cast<std::size_t>(bz)];
    for (std::size_t t = layer_begin[static_cast<std::size_t>(bz)];
         t < layer_end[static_cast<std::size_t>(bz)]; ++t) {
      int lo[3], hi[3];
      Vec3 box_lo, box_hi;
      if (!triangle_box(t, lo, hi, box_lo, box_hi) || lo[2] / kFieldBrick > bz ||
          hi[2] / kFieldBrick < bz) {
        continue;
      }
      lo[2] = std::max(lo[2], bz * kFieldBrick);
      hi[2] = std::min(hi[2], bz * kFieldBrick + kFieldBrick - 1);
      const auto& v = surface.triangles[t];
      const Vec3& ta = surface.vertices[v[0]];
      const Vec3& tb = surface.vertices[v[1]];
      const Vec3& tc = surface.vertices[v[2]];
      // The plane's unit normal (none for a degenerate triangle: the bound is then 0).
      const Vec3 cross = (tb - ta).cross(tc - ta);
      const double cross_norm = cross.norm();
      const bool has_plane = cross_norm > 0.0 && std::isfinite(cross_norm);
      const Vec3 unit = has_plane ? Vec3(cross / cross_norm) : Vec3::Zero();
      const double offset = unit.dot(ta);
      for (int sz = lo[2]; sz <= hi[2]; ++sz) {
        for (int sy = lo[1]; sy <= hi[1]; ++sy) {
          for (int sx = lo[0]; sx <= hi[0]; ++sx) {
            const std::int64_t r = sample_ref(sx, sy, sz, false);  // allocated above
            if (tri[r] >= 0) {
              const double beat = dist[r] + slack;
              const Vec3 p = f.sample_position(sx, sy, sz);
              if (std::abs(unit.dot(p) - offset) > beat) continue;
              double box2 = 0.0;
              for (int a = 0; a < 3; ++a) {
                const double g = std::max({box_lo[a] - p[a], 0.0, p[a] - box_hi[a]});
                box2 += g * g;
              }
              if (box2 > beat * beat) continue;
            }
            const double d = distance_to(static_cast<int>(t), sx, sy, sz);
            if (tri[r] < 0) mine.push_back({static_cast<std::int32_t>(t), sz, sy, sx});
            if (d < dist[r]) {
              dist[r] = d;
              tri[r] = static_cast<std::int32_t>(t);
            }
          }
        }
      }
    }
  });
  {
    // The merge: repeatedly the least head among the layers' lists (each sorted already).
    const auto before = [](const FirstVisit& p, const FirstVisit& q) {
      return std::tie(p.t, p.z, p.y, p.x) < std::tie(q.t, q.z, q.y, q.x);
    };
    std::size_t total = 0;
    for (const auto& v : firsts) total += v.size();
    frontier.reserve(total);
    std::vector<std::size_t> head(static_cast<std::size_t>(nb), 0);
    for (std::size_t done = 0; done < total; ++done) {
      std::size_t best = firsts.size();
      for (std::size_t q = 0; q < firsts.size(); ++q) {
        if (head[q] == firsts[q].size()) continue;
        if (best == firsts.size() || before(firsts[q][head[q]], firsts[best][head[best]])) best = q;
      }
      const FirstVisit& e = firsts[best][head[best]++];
      frontier.push_back({e.x, e.y, e.z});
    }
  }
  std::vector<std::vector<FirstVisit>>().swap(firsts);
  // Grow the band: face neighbours take the nearest of their neighbours' triangles.
  // The sign of sample s: the voxel k (s - P) of the grid (outside the grid: outside).
  const auto sign = [&](int sx, int sy, int sz) {
    return grid.solid(stride * (sx - pad), stride * (sy - pad), stride * (sz - pad)) ? -1.0 : 1.0;
  };
  const double stop_out = f.c_out_ + 2.0 * h, stop_in = f.c_in_ + 2.0 * h;
  constexpr int kNeighbour[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0},
                                    {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  while (!frontier.empty()) {
    next.clear();
    for (const S& s : frontier) {
      const std::int32_t t = tri[sample_ref(s.x, s.y, s.z, false)];
      for (const auto& o : kNeighbour) {
        const int x = s.x + o[0], y = s.y + o[1], z = s.z + o[2];
        if (x < 0 || y < 0 || z < 0 || x >= m || y >= m || z >= m) continue;
        const double d = distance_to(t, x, y, z);
        if (d >= (sign(x, y, z) < 0.0 ? stop_in : stop_out)) continue;
        const std::int64_t r = sample_ref(x, y, z, true);
        if (tri[r] < 0) next.push_back({x, y, z});
        if (d < dist[r]) {
          dist[r] = d;
          tri[r] = t;
        }
      }
    }
    frontier.swap(next);
  }
  // Descent: beyond 2 h a sample's triangle came from a neighbour and may be a few triangles off
  // the nearest; walk the mesh (the triangles around each vertex of the current one) while a
  // nearer one is found (on a smooth surface the distance falls monotonically towards the foot).
  std::vector<int> star_begin(surface.vertices.size() + 1, 0), star;
  for (const auto& t : surface.triangles) {
    for (const int v : t) ++star_begin[static_cast<std::size_t>(v) + 1];
  }
  for (std::size_t v = 0; v < surface.vertices.size(); ++v) star_begin[v + 1] += star_begin[v];
  star.resize(static_cast<std::size_t>(star_begin.back()));
  {
    std::vector<int> fill(star_begin.begin(), star_begin.end() - 1);
    for (std::size_t t = 0; t < surface.triangles.size(); ++t) {
      for (const int v : surface.triangles[t]) star[fill[v]++] = static_cast<int>(t);
    }
  }
  // Each sample's walk reads and writes only its own dist and tri: a z-layer of bricks a task.
  parallel_tasks(nb, threads, [&](int bz) {
    std::array<int, 96> seen{};  // a walk step's triangles so far (a full list only forgets)
    for (int by = 0; by < f.nb_; ++by) {
      for (int bx = 0; bx < f.nb_; ++bx) {
        if (id[f.slot(bx, by, bz)] < 0) continue;
        for (int l = 0; l < kB; ++l) {
          const int x = bx * kFieldBrick + l % kFieldBrick;
          const int y = by * kFieldBrick + (l / kFieldBrick) % kFieldBrick;
          const int z = bz * kFieldBrick + l / (kFieldBrick * kFieldBrick);
          const std::int64_t r = sample_ref(x, y, z, false);
          if (tri[r] < 0 || dist[r] < 2.0 * h) continue;  // exact already (layer 0)
          for (int walk = 0; walk < 64; ++walk) {
            const std::int32_t at_t = tri[r];
            // The stars' triangles, each once: at_t itself gives dist[r] (the pair was set
            // together) and a repeat its first value again, neither strictly smaller, so
            // skipping them changes nothing.
            std::size_t seen_count = 0;
            for (const int v : surface.triangles[static_cast<std::size_t>(at_t)]) {
              for (int k = star_begin[v]; k < star_begin[v + 1]; ++k) {
                const int cand = star[k];
                if (cand == at_t) continue;
                bool repeat = false;
                for (std::size_t q = 0; q < seen_count && !repeat; ++q) repeat = seen[q] == cand;
                if (repeat) continue;
                if (seen_count < seen.size()) seen[seen_count++] = cand;
                const double d = distance_to(cand, x, y, z);
                if (d < dist[r]) {
                  dist[r] = d;
                  tri[r] = cand;
                }
              }
            }
            if (tri[r] == at_t) break;
          }
        }
      }
    }
  });

  const float out_f = static_cast<float>(f.c_out_), in_f = static_cast<float>(-f.c_in_);
  f.index_.assign(slots, SampledField::kAllOutside);
  std::array<float, kB> values{};
  for (int bz = 0; bz < f.nb_; ++bz) {
    for (int by = 0; by < f.nb_; ++by) {
      for (int bx = 0; bx < f.nb_; ++bx) {
        const std::size_t sl = f.slot(bx, by, bz);
        const int x0 = bx * kFieldBrick, y0 = by * kFieldBrick, z0 = bz * kFieldBrick;
        if (id[sl] < 0) {
          f.index_[sl] =
              sign(x0, y0, z0) < 0.0 ? SampledField::kAllInside : SampledField::kAllOutside;
          continue;
        }
        bool all_out = true, all_in = true;
        for (int l = 0; l < kB; ++l) {
          const int lx = l % kFieldBrick, ly = (l / kFieldBrick) % kFieldBrick,
                    lz = l / (kFieldBrick * kFieldBrick);
          const double sg = sign(x0 + lx, y0 + ly, z0 + lz);
          const std::size_t r = static_cast<std::size_t>(id[sl]) * kB + static_cast<std::size_t>(l);
          const double d = tri[r] >= 0 ? dist[r] : std::numeric_limits<double>::infinity();
          values[l] = static_cast<float>(std::clamp(sg * d, -f.c_in_, f.c_out_));
          all_out = all_out && values[l] == out_f;
          all_in = all_in && values[l] == in_f;
        }
        if (all_out || all_in) {
          f.index_[sl] = all_out ? SampledField::kAllOutside : SampledField::kAllInside;
          continue;
        }
        f.index_[sl] = static_cast<std::int32_t>(f.bricks_.size() / kB);
        f.bricks_.insert(f.bricks_.end(), values.begin(), values.end());
        f.measure_row_bounds(f.index_[sl]);
      }
    }
  }

  // Lipschitz constant: the cell bound over every cell touching a stored brick (other cells have
  // 8 equal corners).
  double l = 0.0;
  for (int bz = 0; bz < f.nb_; ++bz) {
    for (int by = 0; by < f.nb_; ++by) {
      for (int bx = 0; bx < f.nb_; ++bx) {
        if (f.index_[f.slot(bx, by, bz)] < 0) continue;
        const int lo[3] = {std::max(0, bx * kFieldBrick - 1), std::max(0, by * kFieldBrick - 1),
                           std::max(0, bz * kFieldBrick - 1)};
        const int hi[3] = {std::min(m - 2, bx * kFieldBrick + kFieldBrick - 1),
                           std::min(m - 2, by * kFieldBrick + kFieldBrick - 1),
                           std::min(m - 2, bz * kFieldBrick + kFieldBrick - 1)};
        for (int z = lo[2]; z <= hi[2]; ++z) {
          for (int y = lo[1]; y <= hi[1]; ++y) {
            for (int x = lo[0]; x <= hi[0]; ++x) l = std::max(l, f.cell_lipschitz(x, y, z));
          }
        }
      }
    }
  }
  f.lipschitz_ = std::max(l, 1e-6);
  return f;
}

TriangleMesh triangulate_voxel_signs(
    const VoxelGrid& grid, const std::function<Vec3(const Vec3& p_in, const Vec3& p_out)>& place) {
  std::vector<VoxelEdge> edges;
  TriangleMesh mesh = triangulate_voxel_edges(grid, &edges);
  for (std::size_t v = 0; v < edges.size(); ++v) {
    const VoxelEdge& e = edges[v];
    mesh.vertices[v] = place(grid.center(e.in[0], e.in[1], e.in[2]),
                             grid.center(e.out(0), e.out(1), e.out(2)));
  }
  return mesh;
}

TriangleMesh triangulate_voxel_edges(const VoxelGrid& grid, std::vector<VoxelEdge>* edges) {
  TriangleMesh mesh;
  mesh.groups.push_back("");
  const int n = grid.n;
  edges->clear();
  if (n > 32766) {
    throw std::invalid_argument("triangulate_voxel_edges: " + std::to_string(n) +
                                " voxels a side (at most 32766)");
  }
  // Kuhn's six tetrahedra of a cell along its diagonal 0 -> 7 (corner c = x + 2 y + 4 z): for each
  // order of the axes (a, b, c), the vertices 0, e_a, e_a + e_b, 7. Every tetrahedron edge joins
  // corners c0 < c1 with c1 - c0 a sum of distinct unit steps, so it is keyed by its lower
  // sample (in [-1, n]^3: the cells run from -1 to n - 1, so that a solid voxel on the grid's
  // boundary layer meets the empty centres beyond it) and that step (1..7).
  constexpr int kAxisBit[3] = {1, 2, 4};
  constexpr int kOrders[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  if (n <= 0) return mesh;
  // Samples per axis with the layer beyond the grid on each side, and 64-bit words a row of them
  // takes as bits (bit i + 1 is sample i; one spare bit so that a cell's upper corner is in range).
  const int span = n + 2;
  const int words = (span + 1 + 63) / 64;
  // The edges' vertices, by the lower sample's z layer (the cells of slab k reach layers k and
  // k + 1): two tables of span^2 x 8 slots (vertex id or -1), the upper one becoming the lower one
  // as k advances; only the slots written are cleared (issue #30: no hash map of every edge).
  std::vector<std::int32_t> layer_vertex[2];
  std::vector<std::size_t> layer_written[2];
  for (auto& t : layer_vertex) t.assign(static_cast<std::size_t>(span) * span * 8, -1);
  int lower = 0;  // layer_vertex[lower] holds sample layer k (+1 shift: ck = k + 1)
  // The edge from corner c_in to corner c_out of cell (i, j, k) (VoxelEdge: the step per axis is
  // the difference of the corners' bits, + 1).
  const auto make_edge = [](int i, int j, int k, int c_in, int c_out) {
    VoxelEdge e;
    e.in[0] = static_cast<std::int16_t>(i + (c_in & 1));
    e.in[1] = static_cast<std::int16_t>(j + ((c_in >> 1) & 1));
    e.in[2] = static_cast<std::int16_t>(k + ((c_in >> 2) & 1));
    int step = 0;
    for (int a = 0; a < 3; ++a) step |= (((c_out >> a) & 1) - ((c_in >> a) & 1) + 1) << (2 * a);
    e.step = static_cast<std::uint8_t>(step);
    return e;
  };
  const auto vertex_on = [&](int i, int j, int k, int c0, int c1, bool in0) {
    // c0 < c1; the slot names the lower corner's sample and the step.
    const int up = (c0 >> 2) & 1;  // the lower corner's layer: k or k + 1
    const std::size_t ci = static_cast<std::size_t>(i + (c0 & 1) + 1),
                      cj = static_cast<std::size_t>(j + ((c0 >> 1) & 1) + 1);
    const int table = up == 0 ? lower : 1 - lower;
    const std::size_t slot = (ci + static_cast<std::size_t>(span) * cj) * 8 +
                             static_cast<std::size_t>(c1 - c0);
    std::int32_t& v = layer_vertex[table][slot];
    if (v >= 0) return static_cast<int>(v);
    v = static_cast<std::int32_t>(edges->size());
    layer_written[table].push_back(slot);
    edges->push_back(make_edge(i, j, k, in0 ? c0 : c1, in0 ? c1 : c0));
    return static_cast<int>(v);
  };
  // The solid flags of sample layer z (in [-1, n]) as bit rows: row j + 1 for sample row j.
  const auto fill_bits = [&](int z, std::vector<std::uint64_t>& bits) {
    bits.assign(static_cast<std::size_t>(span) * words, 0);
    if (z < 0 || z >= n) return;
    for (int j = 0; j < n; ++j) {
      std::uint64_t* row = &bits[static_cast<std::size_t>(j + 1) * words];
      const std::uint8_t* v = &grid.voxels[grid.index(0, j, z)];
      for (int i = 0; i < n; ++i) {
        if (v[i] != 0) row[(i + 1) >> 6] |= std::uint64_t{1} << ((i + 1) & 63);
      }
    }
  };
  std::vector<std::uint64_t> bits_lo, bits_hi, any(static_cast<std::size_t>(words)),
      all(static_cast<std::size_t>(words));
  fill_bits(-1, bits_hi);
  for (int k = -1; k < n; ++k) {
    bits_lo.swap(bits_hi);
    fill_bits(k + 1, bits_hi);
    for (int j = -1; j < n; ++j) {
      // Cell c = i + 1 (i in [-1, n - 1]) has the bits c and c + 1 of its four sample rows; it
      // has a surface iff some corner is solid and not all are.
      const std::uint64_t* r[4] = {&bits_lo[static_cast<std::size_t>(j + 1) * words],
                                   &bits_lo[static_cast<std::size_t>(j + 2) * words],
                                   &bits_hi[static_cast<std::size_t>(j + 1) * words],
                                   &bits_hi[static_cast<std::size_t>(j + 2) * words]};
      bool some = false;
      for (int w = 0; w < words; ++w) {
        any[w] = r[0][w] | r[1][w] | r[2][w] | r[3][w];
        all[w] = r[0][w] & r[1][w] & r[2][w] & r[3][w];
        some = some || any[w] != 0;
      }
      if (!some) continue;
      for (int w = 0; w < words; ++w) {
        const std::uint64_t any_next = (any[w] >> 1) | (w + 1 < words ? any[w + 1] << 63 : 0);
        const std::uint64_t all_next = (all[w] >> 1) | (w + 1 < words ? all[w + 1] << 63 : 0);
        std::uint64_t mixed = (any[w] | any_next) & ~(all[w] & all_next);
        while (mixed != 0) {
          const int c = 64 * w + std::countr_zero(mixed);
          mixed &= mixed - 1;
          if (c > n) break;  // cells run to i = n - 1
          const int i = c - 1;
          bool s[8];
          for (int q = 0; q < 8; ++q) {
            s[q] = grid.solid(i + (q & 1), j + ((q >> 1) & 1), k + ((q >> 2) & 1));
          }
          for (const auto& order : kOrders) {
            const int tv[4] = {0, kAxisBit[order[0]], kAxisBit[order[0]] + kAxisBit[order[1]], 7};
            int in[4], out[4], ni = 0, no = 0;
            for (const int q : tv) (s[q] ? in[ni++] : out[no++]) = q;
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
              const int cc = cross(in[1], out[1]), d = cross(in[1], out[0]);
              mesh.triangles.push_back({a, b, cc});
              mesh.triangles.push_back({a, cc, d});
            }
            mesh.triangle_group.push_back(0);
            if (ni == 2) mesh.triangle_group.push_back(0);
          }
        }
      }
    }
    // Layer k is done: its table takes layer k + 2.
    for (const std::size_t slot : layer_written[lower]) layer_vertex[lower][slot] = -1;
    layer_written[lower].clear();
    lower = 1 - lower;
  }
  // The tables go before the vertices come (the setup's peak memory at 512^3, issue #30).
  for (int t = 0; t < 2; ++t) {
    std::vector<std::int32_t>().swap(layer_vertex[t]);
    std::vector<std::size_t>().swap(layer_written[t]);
  }
  std::vector<std::uint64_t>().swap(bits_lo);
  std::vector<std::uint64_t>().swap(bits_hi);
  mesh.vertices.assign(edges->size(), Vec3::Zero());
  return mesh;
}

}  // namespace dentsim
