#include "tooth_io/procedural_molar.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "reference/core/setup_threads.h"

namespace dentsim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kMm = 1e-3;
constexpr double kSuperellipse = 2.5;  // cross-section exponent: a rounded rectangle

// Cusps of a lower first molar: position (x, y) [mm] and tip height above the CEJ as a fraction of
// the crown height (the mesiolingual cusp is the tallest, 1.0). Mesial -x, buccal -y. Positions
// are for the default 11.0 x 10.5 mm crown and scale with it.
struct Cusp {
  double x, y, height;
};
constexpr std::array<Cusp, 5> kCusps = {{
    {-2.6, -2.0, 7.0 / 7.5},  // mesiobuccal
    {0.8, -2.2, 6.8 / 7.5},   // distobuccal
    {3.3, -1.1, 6.4 / 7.5},   // distal
    {-2.4, 2.0, 1.0},         // mesiolingual
    {1.8, 2.1, 7.3 / 7.5},    // distolingual
}};
constexpr double kCuspCurvature = 0.15;  // paraboloid drop [mm / mm^2] away from a tip
constexpr double kGrooveDepth = 1.0;     // central groove depth [mm]
constexpr double kGrooveWidth = 0.4;     // its Gaussian width [mm]
constexpr double kContourHeight = 2.5;   // height of contour above the CEJ [mm]
constexpr double kOcclusalTable = 0.88;  // occlusal half width / maximal half width

// Lengths in millimetres of the unscaled model.
struct Mm {
  double md, bl, cmd, cbl, crown, mesial, distal, trunk;
};
Mm mm_of(const MolarParams& p) {
  return {p.crown_mesiodistal_m / kMm,   p.crown_buccolingual_m / kMm, p.cervix_mesiodistal_m / kMm,
          p.cervix_buccolingual_m / kMm, p.crown_height_m / kMm,       p.mesial_root_length_m / kMm,
          p.distal_root_length_m / kMm,  p.root_trunk_m / kMm};
}

bool in_superellipse(double x, double y, double a, double b) {
  if (a <= 0 || b <= 0) return false;
  return std::pow(std::abs(x) / a, kSuperellipse) + std::pow(std::abs(y) / b, kSuperellipse) <= 1;
}

// Crown and trunk half widths (x, y) at height z [mm].
std::array<double, 2> body_half_widths(const Mm& m, double z) {
  const double max_x = m.md / 2, max_y = m.bl / 2, cerv_x = m.cmd / 2, cerv_y = m.cbl / 2;
  if (z < 0) {  // root trunk: narrows slightly towards the furcation
    const double u = std::min(1.0, -z / m.trunk);
    return {cerv_x * (1 - 0.07 * u), cerv_y * (1 - 0.07 * u)};
  }
  const double zc = kContourHeight * m.crown / 7.5;
  if (z <= zc) {
    const double w = std::sin(0.5 * kPi * z / zc);
    return {cerv_x + (max_x - cerv_x) * w, cerv_y + (max_y - cerv_y) * w};
  }
  const double u = std::min(1.0, (z - zc) / (m.crown - zc));
  const double f = 1 - (1 - kOcclusalTable) * u * u;
  return {max_x * f, max_y * f};
}

// Occlusal surface height at (x, y) [mm]: upper envelope of the cusps minus the central groove.
double occlusal_height(const Mm& m, double x, double y) {
  const double sx = m.md / 11.0, sy = m.bl / 10.5;
  double top = -1e9;
  for (const Cusp& c : kCusps) {
    const double dx = x - c.x * sx, dy = y - c.y * sy;
    top = std::max(top, c.height * m.crown - kCuspCurvature * (dx * dx + dy * dy));
  }
  return top - kGrooveDepth * std::exp(-(y * y) / (kGrooveWidth * kGrooveWidth));
}

// Root centreline x [mm] and scaled half widths at depth u = -z / L in [0, 1].
struct RootShape {
  double x0, bend, wx, wy, length;
};
std::array<RootShape, 2> roots(const Mm& m) {
  const double sx = m.md / 11.0, sy = m.bl / 10.5;
  return {{{-2.4 * sx, 0.8 * sx, 2.0 * sx, 4.2 * sy, m.mesial},   // mesial: curves distally
           {2.6 * sx, 0.4 * sx, 1.9 * sx, 3.8 * sy, m.distal}}};  // distal: straighter
}

double root_taper(double u) { return (1 - 0.6 * u) * std::sqrt(std::max(0.0, 1 - std::pow(u, 6))); }

bool in_root(const RootShape& r, double x, double y, double z) {
  if (z > 0 || -z >= r.length) return false;
  const double u = -z / r.length;
  const double s = root_taper(u);
  const double dx = x - (r.x0 + r.bend * u * u);
  return s > 0 && (dx * dx) / (r.wx * r.wx * s * s) + (y * y) / (r.wy * r.wy * s * s) <= 1;
}

}  // namespace

bool molar_solid(const MolarParams& params, const Vec3& p) {
  const Mm m = mm_of(params);
  const double x = p.x() / (kMm * params.scale), y = p.y() / (kMm * params.scale),
               z = p.z() / (kMm * params.scale);
  if (z >= -m.trunk && z <= m.crown) {
    const auto [a, b] = body_half_widths(m, z);
    if (in_superellipse(x, y, a, b) && z <= occlusal_height(m, x, y)) return true;
  }
  for (const RootShape& r : roots(m)) {
    if (in_root(r, x, y, z)) return true;
  }
  return false;
}

MolarSolidTest::MolarSolidTest(const MolarParams& params) : params_(params) {
  unit_ = kMm * params.scale;
  const Mm m = mm_of(params);
  const double l[8] = {m.md, m.bl, m.cmd, m.cbl, m.crown, m.mesial, m.distal, m.trunk};
  std::copy(l, l + 8, lengths_);
  const std::array<RootShape, 2> r = roots(m);
  for (int i = 0; i < 2; ++i) {
    const double v[5] = {r[i].x0, r[i].bend, r[i].wx, r[i].wy, r[i].length};
    std::copy(v, v + 5, roots_[i]);
  }
}

// The margins. The products' values differ from std::pow's by a relative error below 10^-15
// (t^2.5 as t t sqrt(t): three correctly rounded operations, against pow's < 1 ulp; u^6 as
// ((u u) (u u)) (u u): five products, absolute error below 10^-15 for u in [0, 1]).
//  - Cross-section: S = |x/a|^2.5 + |y/b|^2.5 <= 1. The products' sum is within 10^-15 S of
//    pow's (plus the sum's own rounding, the same in both), so it decides when it is below
//    1 - 10^-12 or above 1 + 10^-12, margins 1000 times that error at S ~ 1.
//  - Root: Q = dx^2 / (wx^2 s^2) + y^2 / (wy^2 s^2) <= 1 with s = (1 - 0.6 u) sqrt(1 - u^6). With
//    w = 1 - u^6 >= 10^-6, w's relative error is below 10^-15 / 10^-6 = 10^-9, so s^2's and Q's
//    below ~3 x 10^-9 (plus rounding): Q decides when below 1 - 10^-7 or above 1 + 10^-7; a
//    smaller w (the apex's last 10^-6 of the root's length) goes to pow.
bool MolarSolidTest::operator()(const Vec3& p) const {
  const Mm m{lengths_[0], lengths_[1], lengths_[2], lengths_[3],
             lengths_[4], lengths_[5], lengths_[6], lengths_[7]};
  const double x = p.x() / unit_, y = p.y() / unit_, z = p.z() / unit_;
  if (z >= -m.trunk && z <= m.crown) {
    const auto [a, b] = body_half_widths(m, z);
    bool in = false;
    if (a > 0 && b > 0) {
      const double tx = std::abs(x) / a, ty = std::abs(y) / b;
      const double s = tx * tx * std::sqrt(tx) + ty * ty * std::sqrt(ty);
      in = s < 1.0 - 1e-12 ? true : s > 1.0 + 1e-12 ? false : in_superellipse(x, y, a, b);
    }
    if (in && z <= occlusal_height(m, x, y)) return true;
  }
  for (const auto& rv : roots_) {
    const RootShape r{rv[0], rv[1], rv[2], rv[3], rv[4]};
    if (z > 0 || -z >= r.length) continue;
    const double u = -z / r.length;
    const double u2 = u * u;
    const double w = 1.0 - (u2 * u2) * u2;
    if (w < 1e-6) {
      if (in_root(r, x, y, z)) return true;
      continue;
    }
    const double s = (1 - 0.6 * u) * std::sqrt(w);
    const double dx = x - (r.x0 + r.bend * u * u);
    const double q = (dx * dx) / (r.wx * r.wx * s * s) + (y * y) / (r.wy * r.wy * s * s);
    if (q < 1.0 - 1e-7) return true;
    if (q <= 1.0 + 1e-7 && in_root(r, x, y, z)) return true;
  }
  return false;
}

bool molar_pulp(const MolarParams& params, const Vec3& p) {
  const Mm m = mm_of(params);
  const double x = p.x() / (kMm * params.scale), y = p.y() / (kMm * params.scale),
               z = p.z() / (kMm * params.scale);
  const double sx = m.md / 11.0, sy = m.bl / 10.5, sz = m.crown / 7.5;
  // Chamber: floor 1.5 mm below the CEJ, roof 2.0 mm above it, horns under the four main cusps.
  const double floor = -1.5 * sz, roof = 2.0 * sz;
  if (z >= floor && z <= roof + 1.2 * sz && in_superellipse(x, y, 2.6 * sx, 2.2 * sy)) {
    double top = roof;
    for (int c : {0, 1, 3, 4}) {
      const double dx = x - 0.6 * kCusps[c].x * sx, dy = y - 0.6 * kCusps[c].y * sy;
      top = std::max(top, roof + 1.2 * sz - 0.8 * (dx * dx + dy * dy));
    }
    if (z <= top) return true;
  }
  // One canal per root along its centreline, ending short of the apex.
  for (const RootShape& r : roots(m)) {
    if (z > 0 || -z >= 0.95 * r.length) continue;
    const double u = -z / r.length;
    const double rad = 0.5 * sx * (1 - 0.7 * u);
    const double dx = x - (r.x0 + r.bend * u * u);
    if (dx * dx + y * y <= rad * rad) return true;
  }
  return false;
}

Aabb molar_bounds(const MolarParams& params) {
  const Mm m = mm_of(params);
  double x_min = -m.md / 2, x_max = m.md / 2;
  for (const RootShape& r : roots(m)) {  // root outlines at the sampled depths
    for (int i = 0; i <= 1000; ++i) {
      const double u = i / 1000.0;
      const double c = r.x0 + r.bend * u * u, w = r.wx * root_taper(u);
      x_min = std::min(x_min, c - w);
      x_max = std::max(x_max, c + w);
    }
  }
  Aabb b;
  const double k = kMm * params.scale;
  b.min = Vec3(x_min, -m.bl / 2, -std::max(m.mesial, m.distal)) * k;
  b.max = Vec3(x_max, m.bl / 2, m.crown) * k;
  return b;
}

bool molar_caries(const MolarParams& params, const Vec3& p) {
  if (!params.caries_lesion) return false;
  const Mm m = mm_of(params);
  const double k = kMm * params.scale;
  const double cx = params.caries_x_m / kMm;  // unscaled model millimetres
  const Vec3 radii = params.caries_radii_m / kMm;
  const Vec3 centre(cx, 0.0, occlusal_height(m, cx, 0.0) - radii.z());
  const Vec3 q = p / k - centre;
  const double s = (q.x() * q.x()) / (radii.x() * radii.x()) +
                   (q.y() * q.y()) / (radii.y() * radii.y()) +
                   (q.z() * q.z()) / (radii.z() * radii.z());
  return s <= 1.0;
}

CrownFrame molar_crown_frame(const MolarParams& params) {
  CrownFrame c;
  c.axis = Vec3::UnitZ();
  c.cej = 0.0;
  c.crown_height = params.crown_height_m * params.scale;
  return c;
}

namespace {

// molar_solid and molar_pulp over the voxel centres of a box of the grid, slice k by slice k,
// with every factor that depends on fewer than three coordinates computed once: x, y, z of the
// centres per index; per slice the body's half widths, the roots' centrelines and tapers, the
// canals; per slice and column (i) the body's superellipse term in x, per slice and row (j) the
// one in y; per (i, j) the occlusal height and the pulp's roof, and the pulp's superellipse terms.
// Each is the expression of molar_solid / molar_pulp on the same operands, so the answers are the
// definitions' bit for bit (no reassociation: the compiler contracts nothing without -ffast-math,
// and the build targets no FMA).
class MolarSlices {
 public:
  MolarSlices(const MolarParams& params, const VoxelGrid& grid, const std::array<int, 3>& lo,
              const std::array<int, 3>& hi)
      : m_(mm_of(params)),
        roots_(roots(m_)),
        lo_(lo),
        hi_(hi),
        nx_(hi[0] - lo[0] + 1),
        ny_(hi[1] - lo[1] + 1) {
    const double unit = kMm * params.scale;
    for (int d = 0; d < 3; ++d) {
      coord_[d].resize(hi[d] - lo[d] + 1);
      for (int i = lo[d]; i <= hi[d]; ++i) {
        // The component d of grid.center(...): origin[d] + h (i + 1/2), then scaled as the
        // definitions do.
        const Vec3 c = grid.center(i, i, i);
        coord_[d][i - lo[d]] = c[d] / unit;
      }
    }
    sx_ = m_.md / 11.0;
    sy_ = m_.bl / 10.5;
    sz_ = m_.crown / 7.5;
    body_px_.resize(nx_);
    body_py_.resize(ny_);
    occlusal_.resize(static_cast<std::size_t>(nx_) * ny_);
    pulp_top_.resize(occlusal_.size());
    pulp_px_.resize(nx_);
    pulp_py_.resize(ny_);
    const double pa = 2.6 * sx_, pb = 2.2 * sy_;
    for (int i = 0; i < nx_; ++i)
      pulp_px_[i] = std::pow(std::abs(coord_[0][i]) / pa, kSuperellipse);
    for (int j = 0; j < ny_; ++j)
      pulp_py_[j] = std::pow(std::abs(coord_[1][j]) / pb, kSuperellipse);
    const double roof = 2.0 * sz_;
    for (int j = 0; j < ny_; ++j) {
      for (int i = 0; i < nx_; ++i) {
        const double x = coord_[0][i], y = coord_[1][j];
        occlusal_[i + static_cast<std::size_t>(nx_) * j] = occlusal_height(m_, x, y);
        double top = roof;
        for (int c : {0, 1, 3, 4}) {
          const double dx = x - 0.6 * kCusps[c].x * sx_, dy = y - 0.6 * kCusps[c].y * sy_;
          top = std::max(top, roof + 1.2 * sz_ - 0.8 * (dx * dx + dy * dy));
        }
        pulp_top_[i + static_cast<std::size_t>(nx_) * j] = top;
      }
    }
  }

  // Computes the factors of slice k (lo[2] <= k <= hi[2]).
  void start_slice(int k) {
    const double z = coord_[2][k - lo_[2]];
    z_ = z;
    body_ = false;
    if (z >= -m_.trunk && z <= m_.crown) {
      const auto [a, b] = body_half_widths(m_, z);
      // in_superellipse's early exit.
      body_ = a > 0 && b > 0;
      if (body_) {
        for (int i = 0; i < nx_; ++i)
          body_px_[i] = std::pow(std::abs(coord_[0][i]) / a, kSuperellipse);
        for (int j = 0; j < ny_; ++j)
          body_py_[j] = std::pow(std::abs(coord_[1][j]) / b, kSuperellipse);
      }
    }
    for (std::size_t r = 0; r < roots_.size(); ++r) {
      const RootShape& root = roots_[r];
      RootSlice& s = root_[r];
      s.in = false;
      if (!(z > 0 || -z >= root.length)) {
        const double u = -z / root.length;
        const double t = root_taper(u);
        s.in = t > 0;
        s.centre = root.x0 + root.bend * u * u;
        s.den_x = root.wx * root.wx * t * t;
        s.den_y = root.wy * root.wy * t * t;
      }
      CanalSlice& c = canal_[r];
      c.in = !(z > 0 || -z >= 0.95 * root.length);
      if (c.in) {
        const double u = -z / root.length;
        const double rad = 0.5 * sx_ * (1 - 0.7 * u);
        c.centre = root.x0 + root.bend * u * u;
        c.rad2 = rad * rad;
      }
    }
    const double floor = -1.5 * sz_, roof = 2.0 * sz_;
    // in_superellipse's early exit on the chamber's half widths.
    chamber_ = z >= floor && z <= roof + 1.2 * sz_ && 2.6 * sx_ > 0 && 2.2 * sy_ > 0;
  }

  // molar_solid at the centre (i, j, k) of the current slice.
  bool solid(int i, int j) const {
    return inside(i, j, body_, body_px_, body_py_, occlusal_, root_,
                  [](const RootSlice& s, double dx, double y) {
                    return (dx * dx) / s.den_x + (y * y) / s.den_y <= 1;
                  });
  }

  // molar_pulp at the centre (i, j, k) of the current slice.
  bool pulp(int i, int j) const {
    return inside(
        i, j, chamber_, pulp_px_, pulp_py_, pulp_top_, canal_,
        [](const CanalSlice& c, double dx, double y) { return dx * dx + y * y <= c.rad2; });
  }

 private:
  struct RootSlice {
    bool in = false;
    double centre = 0, den_x = 1, den_y = 1;
  };
  struct CanalSlice {
    bool in = false;
    double centre = 0, rad2 = 0;
  };
  // The body (chamber): inside its superellipse section, under its top; else inside one of the
  // parts (roots, canals) that cross the slice, `in_part` given x minus the part's centreline.
  template <class Part, class InPart>
  bool inside(int i, int j, bool section, const std::vector<double>& px,
              const std::vector<double>& py, const std::vector<double>& top,
              const std::array<Part, 2>& parts, InPart in_part) const {
    const int a = i - lo_[0], b = j - lo_[1];
    if (section && px[a] + py[b] <= 1 && z_ <= top[a + static_cast<std::size_t>(nx_) * b]) {
      return true;
    }
    const double x = coord_[0][a], y = coord_[1][b];
    for (const Part& p : parts) {
      if (p.in && in_part(p, x - p.centre, y)) return true;
    }
    return false;
  }

  Mm m_;
  std::array<RootShape, 2> roots_;
  std::array<int, 3> lo_, hi_;
  int nx_, ny_;
  double sx_ = 1, sy_ = 1, sz_ = 1;
  std::array<std::vector<double>, 3> coord_;
  std::vector<double> body_px_, body_py_, occlusal_, pulp_top_, pulp_px_, pulp_py_;
  double z_ = 0;
  bool body_ = false, chamber_ = false;
  std::array<RootSlice, 2> root_;
  std::array<CanalSlice, 2> canal_;
};

}  // namespace

VoxelGrid voxelize_procedural_molar(const MolarParams& params, int resolution,
                                    VoxelizeReport* report) {
  VoxelGrid grid = make_grid(molar_bounds(params), resolution);
  VoxelizeReport r;
  // Only the voxels whose centres may lie within the model's bounds are sampled.
  const Aabb b = molar_bounds(params);
  std::array<int, 3> lo{}, hi{};
  for (int d = 0; d < 3; ++d) {
    lo[d] = std::max(
        0, static_cast<int>(std::floor((b.min[d] - grid.origin[d]) / grid.voxel_size)) - 1);
    hi[d] = std::min(
        grid.n - 1, static_cast<int>(std::ceil((b.max[d] - grid.origin[d]) / grid.voxel_size)) + 1);
  }
  // molar_solid and molar_pulp at every centre, their factors that depend on one or two of the
  // coordinates computed once (MolarSlices): the same operations on the same operands, so the
  // same bits (tests/tooth/procedural_molar_test.cc compares with the per-voxel definition).
  // Threads (issue #30, reference/core/setup_threads.h): each task a contiguous run of slices
  // with its own MolarSlices, writing only its slices' voxels; the counts are summed after.
  const int slice_count = hi[2] - lo[2] + 1;
  const int tasks = std::max(1, std::min(setup_threads(), slice_count));
  std::vector<long> pulp_count(static_cast<std::size_t>(tasks), 0),
      solid_count(static_cast<std::size_t>(tasks), 0);
  parallel_tasks(tasks, tasks, [&](int task) {
    const int k0 = lo[2] + static_cast<int>(static_cast<long>(slice_count) * task / tasks);
    const int k1 = lo[2] + static_cast<int>(static_cast<long>(slice_count) * (task + 1) / tasks);
    MolarSlices slices(params, grid, lo, hi);
    for (int k = k0; k < k1; ++k) {
      slices.start_slice(k);
      for (int j = lo[1]; j <= hi[1]; ++j) {
        for (int i = lo[0]; i <= hi[0]; ++i) {
          if (!slices.solid(i, j)) continue;
          // Solid (any non-zero id); pulp marked kPulp, which assign_materials keeps.
          const bool pulp = slices.pulp(i, j);
          grid.voxels[grid.index(i, j, k)] = pulp ? kPulp : kDentin;
          pulp_count[static_cast<std::size_t>(task)] += pulp ? 1 : 0;
          ++solid_count[static_cast<std::size_t>(task)];
        }
      }
    }
  });
  long pulp_voxels = 0;
  for (int t = 0; t < tasks; ++t) {
    pulp_voxels += pulp_count[static_cast<std::size_t>(t)];
    r.solid.interior_voxels += solid_count[static_cast<std::size_t>(t)];
  }
  r.crown = molar_crown_frame(params);
  assign_materials(grid, {}, r.crown, params.enamel_cusp_m * params.scale);
  if (params.caries_lesion) {
    // molar_caries with its centre (the groove's height there) computed once: the same operands.
    const Mm m = mm_of(params);
    const double unit = kMm * params.scale;
    const double cx = params.caries_x_m / kMm;
    const Vec3 radii = params.caries_radii_m / kMm;
    const Vec3 centre(cx, 0.0, occlusal_height(m, cx, 0.0) - radii.z());
    for (int k = lo[2]; k <= hi[2]; ++k) {
      for (int j = lo[1]; j <= hi[1]; ++j) {
        for (int i = lo[0]; i <= hi[0]; ++i) {
          const std::size_t x = grid.index(i, j, k);
          if (grid.voxels[x] == kEnamel || grid.voxels[x] == kDentin) {
            const Vec3 q = grid.center(i, j, k) / unit - centre;
            const double s = (q.x() * q.x()) / (radii.x() * radii.x()) +
                             (q.y() * q.y()) / (radii.y() * radii.y()) +
                             (q.z() * q.z()) / (radii.z() * radii.z());
            if (s <= 1.0) grid.voxels[x] = kCaries;
          }
        }
      }
    }
  }
  // The pulp marked above: assign_materials keeps it, the lesion takes only enamel and dentin.
  r.pulp_voxels = pulp_voxels;
  if (report != nullptr) *report = r;
  return grid;
}

}  // namespace dentsim
