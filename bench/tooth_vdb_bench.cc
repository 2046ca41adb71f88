// The tooth's sphere query against OpenVDB and OctoMap (benchmark-only dependencies, Debian
// libopenvdb-dev / liboctomap-dev; built only when CMake finds them). The same query on the same
// voxelised molar: the surface voxels (nonzero neighbour code: the only ones that can give a
// contact) that the tip sphere intersects, by the reference's exact predicate
// sphere_intersects_voxel; each structure stores exactly the surface voxels and finds candidates
// its own idiomatic way:
// - fast (fast/tooth/brick_tooth.h): brick octree + 64-bit surface masks, BM_ToothSphereFast;
// - OpenVDB 10: a BoolGrid of active surface voxels; the 8^3 leaf nodes under the sphere's box
//   are probed and their active voxels tested, BM_ToothSphereOpenVdb;
// - OctoMap 1.9: an OcTree with one occupied leaf per surface voxel (voxel i <-> key 32768 + i,
//   resolution h; inserted lazily, no pruning), leaf iteration over the box, BM_ToothSphereOctoMap.
// The result sets are checked equal before timing. Args: resolution, bur radius [0.1 mm].
// Results and command: docs/benchmarks.md "Tooth query: reference vs fast".
#include <benchmark/benchmark.h>
#include <octomap/OcTree.h>
#include <openvdb/openvdb.h>

#include <algorithm>
#include <memory>
#include <vector>

#include "bench/tooth_bench.h"
#include "fast/tooth/collision.h"
#include "tooth_io/procedural_molar.h"

namespace dentsim {
namespace {

struct Structures {
  VoxelTooth ref;
  fast::BrickTooth fst;
  openvdb::BoolGrid::Ptr vdb;
  std::unique_ptr<octomap::OcTree> octo;
  explicit Structures(int n) : ref(voxelize_procedural_molar(MolarParams{}, n)), fst(ref) {
    openvdb::initialize();
    vdb = openvdb::BoolGrid::create(false);
    auto acc = vdb->getAccessor();
    octo = std::make_unique<octomap::OcTree>(ref.grid().voxel_size);
    for (int k = 0; k < n; ++k) {
      for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
          if (ref.codes.code(ref.grid().index(i, j, k)) == 0) continue;
          acc.setValueOn(openvdb::Coord(i, j, k), true);
          octo->updateNode(octomap::OcTreeKey(static_cast<std::uint16_t>(32768 + i),
                                              static_cast<std::uint16_t>(32768 + j),
                                              static_cast<std::uint16_t>(32768 + k)),
                           true, true);
        }
      }
    }
    octo->updateInnerOccupancy();
  }
};
Structures& structures(int n) { return bench::built_once<Structures>(n); }

void query_vdb(const Structures& s, const Vec3& c, double rho, std::vector<std::size_t>* out) {
  int lo[3], hi[3];
  if (!fast::sphere_voxel_box(s.fst, c, rho, lo, hi)) return;
  const VoxelGrid& g = s.ref.grid();
  auto acc = s.vdb->getConstAccessor();
  using Leaf = openvdb::BoolGrid::TreeType::LeafNodeType;
  constexpr int kLeaf = static_cast<int>(Leaf::DIM);
  for (int z = lo[2] & ~(kLeaf - 1); z <= hi[2]; z += kLeaf) {
    for (int y = lo[1] & ~(kLeaf - 1); y <= hi[1]; y += kLeaf) {
      for (int x = lo[0] & ~(kLeaf - 1); x <= hi[0]; x += kLeaf) {
        const Leaf* leaf = acc.probeConstLeaf(openvdb::Coord(x, y, z));
        if (leaf == nullptr) continue;
        for (auto it = leaf->cbeginValueOn(); it; ++it) {
          const openvdb::Coord p = it.getCoord();
          if (p.x() < lo[0] || p.x() > hi[0] || p.y() < lo[1] || p.y() > hi[1] ||
              p.z() < lo[2] || p.z() > hi[2]) {
            continue;
          }
          if (sphere_intersects_voxel(g, p.x(), p.y(), p.z(), c, rho)) {
            out->push_back(g.index(p.x(), p.y(), p.z()));
          }
        }
      }
    }
  }
}

void query_octomap(const Structures& s, const Vec3& c, double rho, std::vector<std::size_t>* out) {
  int lo[3], hi[3];
  if (!fast::sphere_voxel_box(s.fst, c, rho, lo, hi)) return;
  const VoxelGrid& g = s.ref.grid();
  const auto key = [](int i, int j, int k) {
    return octomap::OcTreeKey(static_cast<std::uint16_t>(32768 + i),
                              static_cast<std::uint16_t>(32768 + j),
                              static_cast<std::uint16_t>(32768 + k));
  };
  for (auto it = s.octo->begin_leafs_bbx(key(lo[0], lo[1], lo[2]), key(hi[0], hi[1], hi[2]));
       it != s.octo->end_leafs_bbx(); ++it) {
    if (!s.octo->isNodeOccupied(*it)) continue;
    const octomap::OcTreeKey k = it.getKey();
    const int i = k[0] - 32768, j = k[1] - 32768, l = k[2] - 32768;
    if (sphere_intersects_voxel(g, i, j, l, c, rho)) out->push_back(g.index(i, j, l));
  }
}

// Which structure: 0 fast, 1 OpenVDB, 2 OctoMap.
void run(benchmark::State& state, int which) {
  Structures& s = structures(static_cast<int>(state.range(0)));
  const double rho = static_cast<double>(state.range(1)) * 1e-4;
  const Vec3 c = bench::occlusal_pose(s.ref.grid(), rho).x;
  const auto query = [&](std::vector<std::size_t>* out) {
    out->clear();
    if (which == 0) fast::sphere_surface_voxels(s.fst, c, rho, out);
    if (which == 1) query_vdb(s, c, rho, out);
    if (which == 2) query_octomap(s, c, rho, out);
  };
  std::vector<std::size_t> expected, got;
  fast::sphere_surface_voxels(s.fst, c, rho, &expected);
  query(&got);
  std::sort(expected.begin(), expected.end());
  std::sort(got.begin(), got.end());
  if (got != expected) {
    state.SkipWithError("result set differs from the fast tooth's");
    return;
  }
  got.reserve(16384);
  for (auto _ : state) {
    query(&got);
    benchmark::DoNotOptimize(got.data());
  }
  state.counters["voxels"] = static_cast<double>(got.size());
}

void BM_ToothSphereFast(benchmark::State& state) { run(state, 0); }
void BM_ToothSphereOpenVdb(benchmark::State& state) { run(state, 1); }
void BM_ToothSphereOctoMap(benchmark::State& state) { run(state, 2); }
BENCHMARK(BM_ToothSphereFast)->ArgsProduct({{128, 256}, {3, 5, 10}});
BENCHMARK(BM_ToothSphereOpenVdb)->ArgsProduct({{128, 256}, {3, 5, 10}});
BENCHMARK(BM_ToothSphereOctoMap)->ArgsProduct({{128, 256}, {3, 5, 10}});

}  // namespace
}  // namespace dentsim
