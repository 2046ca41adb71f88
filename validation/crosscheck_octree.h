// Cross-check of the full octree's sphere query against brute force over the flat voxel array
// (docs/design.md "Voxel tooth"; docs/conventions.md "Tests": the oracle is not the code under
// test). The comparison is exact: the sorted set of flat voxel indices the
// octree returns must equal the set the brute force finds by testing every voxel of the array with
// the same definition (sphere_intersects_voxel: distance from the centre to the closed voxel box
// < rho). Between queries, random voxels are removed through FullOctree::remove_voxel, so the
// levels updated incrementally up to the root are what is checked.
//
// Sphere placements (in voxel units h, then mapped to the world): uniform random; touching a
// voxel face, an edge or a corner exactly (distance = rho); centred on an octree cell boundary of a
// random level (node faces, edges, corners); centred on a grid point with rho an integer number of
// voxels (many voxels at distance exactly rho); nudged by one ulp in and out of touching; large
// spheres covering most of the grid.
#pragma once

#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "reference/core/types.h"
#include "reference/tooth/voxel_grid.h"

namespace dentsim {

enum class SpherePlacement : int {
  kUniform = 0,
  kTouchFace,
  kTouchEdge,
  kTouchCorner,
  kCellBoundary,
  kGridPointIntegerRadius,
  kUlpNudge,
  kLarge,
  kCount,
};
const char* sphere_placement_name(SpherePlacement p);

struct OctreeCrosscheckOptions {
  int n = 16;              // grid resolution (power of two)
  long spheres = 100000;   // number of queries
  std::uint64_t seed = 1;  // std::mt19937_64 seed
  // Remove one random solid voxel every this many queries (0: never) until half of the solid is
  // gone, so that later queries still meet a populated octree.
  long remove_every = 50;
};

struct OctreeCrosscheckResult {
  long queries = 0;
  long mismatches = 0;        // queries whose octree set differs from the brute-force set
  long nonempty_queries = 0;  // queries whose brute-force set is not empty
  long voxels_matched = 0;    // total size of the brute-force sets
  long removals = 0;          // voxels removed between queries
  std::array<long, static_cast<int>(SpherePlacement::kCount)> by_placement{};
  std::string first_mismatch;  // description of the first mismatch, empty if none
};

// The test object: a ball of radius 0.42 N (enamel shell, dentin, pulp core) with random voxels
// removed (probability 0.15), so that octree nodes at every level are full, partial and empty.
VoxelGrid make_crosscheck_grid(int n, std::uint64_t seed);

// Brute force: every voxel of the flat array in index order; appends the solid ones intersecting
// the sphere.
void brute_force_sphere(const VoxelGrid& grid, const Vec3& c, double rho,
                        std::vector<std::size_t>* out);

OctreeCrosscheckResult crosscheck_octree(const OctreeCrosscheckOptions& options);

// The memory of the full octree per resolution n = 32, 64, ..., 512 (docs/tooth_octree.md): per
// row n, levels, internal_nodes, mask_bytes, leaf_bytes, octree_bytes, neighbor_code_bytes and
// drill_work_bytes (one double per voxel) [bytes].
nlohmann::json octree_memory_table_json();

// `dentsim crosscheck octree --json`: the options, the counts, the placements, the first mismatch
// and the memory table.
nlohmann::json crosscheck_octree_json(const OctreeCrosscheckOptions& options,
                                      const OctreeCrosscheckResult& result);

}  // namespace dentsim
