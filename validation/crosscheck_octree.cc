#include "validation/crosscheck_octree.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>

#include "reference/core/io.h"
#include "reference/tooth/octree.h"

namespace dentsim {
namespace {

struct Sphere {
  Vec3 c_vox;  // centre in voxel units from the grid origin
  double rho_vox;
};

// A random unit vector with all components > 0 scaled by the signs s (each +-1 or 0: zero
// components stay zero).
Vec3 outward_direction(std::mt19937_64& rng, const Vec3& s) {
  std::uniform_real_distribution<double> u(0.05, 1.0);
  Vec3 d(u(rng) * s.x(), u(rng) * s.y(), u(rng) * s.z());
  return d / d.norm();
}

Sphere make_sphere(SpherePlacement kind, int n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<int> cell(0, n - 1);
  std::uniform_int_distribution<int> sign01(0, 1);
  auto radius = [&] { return 0.05 + 3.0 * unit(rng); };
  switch (kind) {
    case SpherePlacement::kUniform:
    case SpherePlacement::kCount:
      return {Vec3(unit(rng), unit(rng), unit(rng)) * (n + 4.0) - Vec3::Constant(2.0), radius()};
    case SpherePlacement::kTouchFace: {
      // A point on a random face of a random voxel, centre rho along the face normal.
      const int axis = std::uniform_int_distribution<int>(0, 2)(rng);
      const int side = sign01(rng);
      Vec3 p(cell(rng) + unit(rng), cell(rng) + unit(rng), cell(rng) + unit(rng));
      p[axis] = std::floor(p[axis]) + side;
      const double rho = radius();
      Vec3 c = p;
      c[axis] += (side == 1 ? rho : -rho);
      return {c, rho};
    }
    case SpherePlacement::kTouchEdge: {
      const int axis = std::uniform_int_distribution<int>(0, 2)(rng);  // the edge's direction
      Vec3 p(cell(rng) + sign01(rng), cell(rng) + sign01(rng), cell(rng) + sign01(rng));
      p[axis] = cell(rng) + unit(rng);
      Vec3 s(sign01(rng) ? 1.0 : -1.0, sign01(rng) ? 1.0 : -1.0, sign01(rng) ? 1.0 : -1.0);
      s[axis] = 0.0;
      const double rho = radius();
      return {p + rho * outward_direction(rng, s), rho};
    }
    case SpherePlacement::kTouchCorner: {
      const Vec3 p(cell(rng) + sign01(rng), cell(rng) + sign01(rng), cell(rng) + sign01(rng));
      const Vec3 s(sign01(rng) ? 1.0 : -1.0, sign01(rng) ? 1.0 : -1.0, sign01(rng) ? 1.0 : -1.0);
      const double rho = radius();
      return {p + rho * outward_direction(rng, s), rho};
    }
    case SpherePlacement::kCellBoundary: {
      // Coordinates snapped to the node boundaries of a random level (0 or more axes snapped).
      int levels = 0;
      while ((1 << levels) < n) ++levels;
      const int level = std::uniform_int_distribution<int>(0, levels)(rng);
      const int size = n >> level;  // node edge in voxels
      Vec3 c(unit(rng) * n, unit(rng) * n, unit(rng) * n);
      for (int a = 0; a < 3; ++a) {
        if (sign01(rng)) c[a] = size * std::round(c[a] / size);
      }
      return {c, radius()};
    }
    case SpherePlacement::kGridPointIntegerRadius: {
      const Vec3 c(std::uniform_int_distribution<int>(0, n)(rng),
                   std::uniform_int_distribution<int>(0, n)(rng),
                   std::uniform_int_distribution<int>(0, n)(rng));
      return {c, static_cast<double>(std::uniform_int_distribution<int>(1, 4)(rng))};
    }
    case SpherePlacement::kUlpNudge: {
      // A face-touching sphere with rho moved by one ulp either way.
      Sphere s = make_sphere(SpherePlacement::kTouchFace, n, rng);
      s.rho_vox = std::nextafter(s.rho_vox, sign01(rng) ? 1e9 : 0.0);
      return s;
    }
    case SpherePlacement::kLarge:
      return {Vec3(unit(rng), unit(rng), unit(rng)) * n, (0.3 + 0.7 * unit(rng)) * n};
  }
  return {Vec3::Zero(), 1.0};
}

}  // namespace

const char* sphere_placement_name(SpherePlacement p) {
  switch (p) {
    case SpherePlacement::kUniform:
      return "uniform";
    case SpherePlacement::kTouchFace:
      return "touch_face";
    case SpherePlacement::kTouchEdge:
      return "touch_edge";
    case SpherePlacement::kTouchCorner:
      return "touch_corner";
    case SpherePlacement::kCellBoundary:
      return "cell_boundary";
    case SpherePlacement::kGridPointIntegerRadius:
      return "grid_point_integer_radius";
    case SpherePlacement::kUlpNudge:
      return "ulp_nudge";
    case SpherePlacement::kLarge:
      return "large";
    case SpherePlacement::kCount:
      break;
  }
  return "?";
}

VoxelGrid make_crosscheck_grid(int n, std::uint64_t seed) {
  // A non-dyadic origin and voxel size, so that box bounds are not exact binary fractions.
  VoxelGrid grid(n, Vec3(-1.3e-3, 0.7e-3, 2.1e-3), 12e-3 / n * 1.01);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double r_out = 0.42 * n;
  const Vec3 mid = Vec3::Constant(0.5 * n);
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const double r = (Vec3(i + 0.5, j + 0.5, k + 0.5) - mid).norm();
        std::uint8_t m = kEmpty;
        if (r < 0.35 * r_out) {
          m = kPulp;
        } else if (r < 0.8 * r_out) {
          m = kDentin;
        } else if (r < r_out) {
          m = kEnamel;
        }
        if (m != kEmpty && unit(rng) < 0.15) m = kEmpty;
        grid.set(i, j, k, m);
      }
    }
  }
  return grid;
}

void brute_force_sphere(const VoxelGrid& grid, const Vec3& c, double rho,
                        std::vector<std::size_t>* out) {
  const int n = grid.n;
  for (std::size_t v = 0; v < grid.voxels.size(); ++v) {
    if (grid.voxels[v] == kEmpty) continue;
    const int i = static_cast<int>(v % n);
    const int j = static_cast<int>((v / n) % n);
    const int k = static_cast<int>(v / (static_cast<std::size_t>(n) * n));
    if (sphere_intersects_voxel(grid, i, j, k, c, rho)) out->push_back(v);
  }
}

OctreeCrosscheckResult crosscheck_octree(const OctreeCrosscheckOptions& options) {
  if (options.spheres < 1) {
    throw InputError("crosscheck octree: --spheres = " + std::to_string(options.spheres) +
                     ", expected >= 1");
  }
  if (options.remove_every < 0) {
    throw InputError("crosscheck octree: --remove-every = " + std::to_string(options.remove_every) +
                     ", expected >= 0");
  }
  if (options.n < 2 || options.n > 128 || (options.n & (options.n - 1)) != 0) {
    throw InputError("crosscheck octree: --n = " + std::to_string(options.n) +
                     ", expected a power of two in [2, 128]");
  }
  FullOctree tree(make_crosscheck_grid(options.n, options.seed));
  std::mt19937_64 rng(options.seed ^ 0x9e3779b97f4a7c15ULL);
  std::uniform_int_distribution<int> pick_kind(0, static_cast<int>(SpherePlacement::kCount) - 1);
  std::uniform_int_distribution<std::size_t> pick_voxel(0, tree.grid().voxels.size() - 1);
  const double h = tree.grid().voxel_size;

  long initial_solid = 0;
  for (const std::uint8_t m : tree.grid().voxels) initial_solid += m != kEmpty;

  OctreeCrosscheckResult result;
  std::vector<std::size_t> from_tree, from_brute;
  from_tree.reserve(tree.grid().voxels.size());
  from_brute.reserve(tree.grid().voxels.size());
  for (long q = 0; q < options.spheres; ++q) {
    if (options.remove_every > 0 && q > 0 && q % options.remove_every == 0 &&
        result.removals < initial_solid / 2) {
      // A random solid voxel (up to 100 draws), until half of the solid is gone, so that the
      // later queries still meet a populated octree.
      const int n = options.n;
      for (int draw = 0; draw < 100; ++draw) {
        const std::size_t v = pick_voxel(rng);
        if (tree.grid().voxels[v] == kEmpty) continue;
        tree.remove_voxel(static_cast<int>(v % n), static_cast<int>((v / n) % n),
                          static_cast<int>(v / (static_cast<std::size_t>(n) * n)));
        ++result.removals;
        break;
      }
    }
    const auto kind = static_cast<SpherePlacement>(pick_kind(rng));
    const Sphere s = make_sphere(kind, options.n, rng);
    const Vec3 c = tree.grid().origin + h * s.c_vox;
    const double rho = h * s.rho_vox;
    from_tree.clear();
    from_brute.clear();
    tree.query_sphere(c, rho, &from_tree);
    brute_force_sphere(tree.grid(), c, rho, &from_brute);
    std::sort(from_tree.begin(), from_tree.end());
    ++result.queries;
    ++result.by_placement[static_cast<int>(kind)];
    if (!from_brute.empty()) ++result.nonempty_queries;
    result.voxels_matched += static_cast<long>(from_brute.size());
    if (from_tree != from_brute) {
      ++result.mismatches;
      if (result.first_mismatch.empty()) {
        std::ostringstream msg;
        msg.precision(17);
        msg << "query " << q << " (" << sphere_placement_name(kind) << ") centre [" << c.transpose()
            << "] rho " << rho << ": octree " << from_tree.size() << " voxels, brute force "
            << from_brute.size();
        result.first_mismatch = msg.str();
      }
    }
  }
  return result;
}

nlohmann::json octree_memory_table_json() {
  nlohmann::json rows = nlohmann::json::array();
  for (int n = 32; n <= 512; n *= 2) {
    int levels = 0;
    while ((1 << levels) < n) ++levels;
    const std::size_t masks = FullOctree::internal_node_count(levels);
    const std::size_t total = FullOctree::memory_bytes_for(n);
    const std::size_t nn = static_cast<std::size_t>(n);
    rows.push_back({{"n", n},
                    {"levels", levels},
                    {"internal_nodes", masks},
                    {"mask_bytes", masks},
                    {"leaf_bytes", nn * nn * nn},
                    {"octree_bytes", total},
                    {"neighbor_code_bytes", nn * nn * nn},
                    {"drill_work_bytes", nn * nn * nn * sizeof(double)}});
  }
  return rows;
}

nlohmann::json crosscheck_octree_json(const OctreeCrosscheckOptions& options,
                                      const OctreeCrosscheckResult& r) {
  nlohmann::json by_placement = nlohmann::json::object();
  for (int p = 0; p < static_cast<int>(SpherePlacement::kCount); ++p) {
    by_placement[sphere_placement_name(static_cast<SpherePlacement>(p))] = r.by_placement[p];
  }
  return {{"n", options.n},
          {"seed", options.seed},
          {"remove_every", options.remove_every},
          {"queries", r.queries},
          {"mismatches", r.mismatches},
          {"nonempty_queries", r.nonempty_queries},
          {"voxels_matched", r.voxels_matched},
          {"removals", r.removals},
          {"by_placement", by_placement},
          {"first_mismatch", r.first_mismatch},
          {"memory_per_resolution", octree_memory_table_json()}};
}

}  // namespace dentsim
