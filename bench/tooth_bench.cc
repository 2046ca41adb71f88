// Google Benchmark of the tooth query and drilling update: reference (reference/tooth/) against
// fast (fast/tooth/), both through their ContactProvider (what the servo tick calls), on the
// procedural molar at 128^3, 256^3 and 512^3 with the bur radii 0.3 / 0.5 / 1.0 mm of
// BM_ToothCollision (26 / 68 / 245 contacts at 128^3); the free-space early out; and one tick of
// query + drilling along a fixed cutting path. Results and command: docs/benchmarks.md "Tooth
// query: reference vs fast". Run: build/release/bench/dentsim_bench --benchmark_filter=Tooth
#include <benchmark/benchmark.h>

#include <algorithm>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "bench/tooth_bench.h"
#include "fast/tooth/cut_set.h"
#include "fast/tooth/field.h"
#include "fast/tooth/sdf.h"
#include "fast/tooth/tooth_contacts.h"
#include "sim/scene.h"
#include "sim/simulator.h"
#include "tooth_io/procedural_molar.h"
#include "reference/tooth/tooth_contacts.h"

namespace dentsim {
namespace {

constexpr double kK = 3000.0;  // K_tooth [N/m]
constexpr double kB = 5.0;     // B_tooth [N s/m]

// The molar at resolution n, built once per process (512^3 takes ~10 s and ~0.6 GB for both).
struct Teeth {
  VoxelTooth ref;
  fast::BrickTooth fst;
  explicit Teeth(int n) : ref(voxelize_procedural_molar(MolarParams{}, n)), fst(ref) {}
};
Teeth& teeth(int n) { return bench::built_once<Teeth>(n); }
using bench::occlusal_pose;

void run_query(benchmark::State& state, ContactProvider& provider, const Pose& pose) {
  std::vector<Contact> contacts;
  contacts.reserve(kContactCapacity);
  for (auto _ : state) {
    benchmark::DoNotOptimize(provider.contacts(pose, contacts));
    benchmark::DoNotOptimize(contacts.data());
  }
  state.counters["contacts"] = static_cast<double>(contacts.size());
}

// Args: resolution, bur radius [0.1 mm].
void BM_ToothQueryReference(benchmark::State& state) {
  Teeth& t = teeth(static_cast<int>(state.range(0)));
  ToolTip tip;
  tip.radius = static_cast<double>(state.range(1)) * 1e-4;
  ToothContactProvider provider(t.ref, tip, kK, kB);
  run_query(state, provider, occlusal_pose(t.ref.grid(), tip.radius));
}
void BM_ToothQueryFast(benchmark::State& state) {
  Teeth& t = teeth(static_cast<int>(state.range(0)));
  ToolTip tip;
  tip.radius = static_cast<double>(state.range(1)) * 1e-4;
  fast::ToothContactProvider provider(t.fst, tip, kK, kB);
  run_query(state, provider, occlusal_pose(t.ref.grid(), tip.radius));
}
BENCHMARK(BM_ToothQueryReference)->ArgsProduct({{128, 256, 512}, {3, 5, 10}});
BENCHMARK(BM_ToothQueryFast)->ArgsProduct({{128, 256, 512}, {3, 5, 10}});

// Free space: the tip 2 mm above the tooth's highest point (no candidate), 128^3, r = 0.5 mm.
// Arg: 0 reference, 1 fast.
void BM_ToothQueryFreeSpace(benchmark::State& state) {
  Teeth& t = teeth(128);
  ToolTip tip;
  tip.radius = 0.5e-3;
  Pose pose = occlusal_pose(t.ref.grid(), tip.radius);
  pose.x.z() = t.ref.grid().origin.z() + t.ref.grid().n * t.ref.grid().voxel_size + 2e-3;
  if (state.range(0) == 0) {
    ToothContactProvider provider(t.ref, tip, kK, kB);
    run_query(state, provider, pose);
  } else {
    fast::ToothContactProvider provider(t.fst, tip, kK, kB);
    run_query(state, provider, pose);
  }
  state.SetLabel(state.range(0) == 0 ? "reference" : "fast");
}
BENCHMARK(BM_ToothQueryFreeSpace)->Arg(0)->Arg(1);

// One tick of query + drilling along a fixed cutting path: the bur (r = 0.5 mm, default drill
// params) wanders over the crown in steps of up to 0.3 voxel and follows the drilled surface
// down, pressing 0.3 rho into it. A fixed iteration count makes both run the same ticks on their
// own copy of the tooth. Args: resolution, 0 reference / 1 fast.
void BM_ToothDrillTick(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  VoxelTooth ref(teeth(n).ref.grid());  // a fresh copy: drilling changes it
  fast::BrickTooth fst(ref);
  ToolTip tip;
  tip.radius = 0.5e-3;
  const DrillParams drill;
  std::unique_ptr<ContactProvider> provider;
  if (state.range(1) == 0) {
    provider = std::make_unique<ToothContactProvider>(ref, tip, kK, kB, &drill);
  } else {
    provider = std::make_unique<fast::ToothContactProvider>(fst, tip, kK, kB, &drill);
  }
  const VoxelGrid& g = state.range(1) == 0 ? ref.grid() : fst.grid();
  std::vector<Contact> contacts;
  contacts.reserve(kContactCapacity);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const double h = g.voxel_size;
  const Vec3 start = g.center(g.n / 2, g.n / 2, 0);
  Pose pose;
  pose.x = start;
  long removed = 0, members = 0;
  for (auto _ : state) {
    for (int a = 0; a < 2; ++a) {
      pose.x[a] = std::clamp(pose.x[a] + 0.3 * h * unit(rng), start[a] - 2e-3, start[a] + 2e-3);
    }
    const int i = static_cast<int>((pose.x.x() - g.origin.x()) / h);
    const int j = static_cast<int>((pose.x.y() - g.origin.y()) / h);
    int top = 0;
    for (int k = g.n - 1; k >= 0; --k) {
      if (g.solid(i, j, k)) {
        top = k + 1;
        break;
      }
    }
    pose.x.z() = g.origin.z() + h * top + 0.7 * tip.radius;
    provider->contacts(pose, contacts);
    removed += provider->drill(contacts, 1e-3);
    members += static_cast<long>(contacts.size());
  }
  state.counters["removed"] = static_cast<double>(removed);
  state.counters["contacts_per_tick"] =
      static_cast<double>(members) / static_cast<double>(state.iterations());
  state.SetLabel(state.range(1) == 0 ? "reference" : "fast");
}
BENCHMARK(BM_ToothDrillTick)->ArgsProduct({{128, 256}, {0, 1}})->Iterations(20000);

// The surface-proxy contact's voxel side (issue #30, stop 45): the contact's material and the cut
// set at the anchor g resting rho above the occlusal surface (occlusal_pose lifted by its 0.1 mm),
// 0.5 mm bur, on the procedural molar: the fast pipeline's before (proxy_material by
// fast::signed_distance and collect_cut_set on the octree, the reference's code) against
// fast::SurfaceCutSet (fast/tooth/cut_set.h, over the surface voxels). Results: docs/benchmarks.md
// "The cut set over the surface voxels". Args: resolution, 0 octree / 1 surface voxels.
struct MolarTooth {
  VoxelTooth tooth;
  explicit MolarTooth(int n) : tooth(voxelize_procedural_molar(MolarParams{}, n)) {}
};
void BM_CutSet(benchmark::State& state) {
  const VoxelTooth& tooth = bench::built_once<MolarTooth>(static_cast<int>(state.range(0))).tooth;
  const double rho = 0.5e-3;
  const Vec3 g = occlusal_pose(tooth.grid(), rho).x + Vec3(0, 0, 1e-4);
  Contact contact;
  contact.x_o = g - rho * contact.n;
  std::vector<Contact> shares;
  std::vector<std::size_t> voxels, candidates;
  shares.reserve(kContactCapacity);
  voxels.reserve(kContactCapacity);
  candidates.reserve(1u << 16);
  fast::SurfaceCutSet cut(tooth, rho, &fast::signed_distance);
  fast::SurfaceCutSet::Nearest nearest;
  std::uint8_t material = 0;
  for (auto _ : state) {
    shares.clear();
    voxels.clear();
    if (state.range(1) == 0) {
      material = proxy_material(tooth, g, rho, &fast::signed_distance);
      collect_cut_set(tooth, contact, g, rho, &candidates, &shares, &voxels);
    } else {
      cut.collect(g, contact, &shares, &voxels, &nearest);
      material = tooth.grid().voxels[nearest.voxel];
    }
    benchmark::DoNotOptimize(material);
    benchmark::DoNotOptimize(shares.data());
  }
  state.counters["members"] = static_cast<double>(shares.size());
  state.SetLabel(state.range(1) == 0 ? "octree" : "surface voxels");
}
BENCHMARK(BM_CutSet)->ArgsProduct({{128, 256, 512}, {0, 1}});

// The anchor of the material's and the local query's benchmarks: g0 moved 0.5 um a call along a
// 2 mm line (x and y) and back (a tip at 0.5 mm/s at 1 kHz).
struct LineWalk {
  static constexpr int kSteps = 4000;  // 2 mm at 0.5 um
  Vec3 g0;
  int step = 0;
  Vec3 next() {
    const int s = step < kSteps ? step : 2 * kSteps - step;  // there and back
    step = step + 1 == 2 * kSteps ? 0 : step + 1;
    return g0 + Vec3(0.5e-6 * (s - kSteps / 2), 0.2e-6 * (s - kSteps / 2), 0.0);
  }
};

// The contact's material alone (issue #30, stop 47: the field model's servo asks for it without a
// cut set, its cut being the worker's): the solid voxel nearest to the anchor within 2 rho, on the
// procedural molar at `resolution`, 0.5 mm bur, the anchor g moving 0.5 um a call along a
// 2 mm-long line through the occlusal anchor of BM_CutSet and back (a tip at 0.5 mm/s at 1 kHz).
// Args: resolution, 0 octree (proxy_material by fast::signed_distance) / 1 surface voxels
// (SurfaceCutSet::collect without a cut set). Results: docs/benchmarks.md "The field model's
// contact material without the band scan".
void BM_ContactMaterial(benchmark::State& state) {
  const VoxelTooth& tooth = bench::built_once<MolarTooth>(static_cast<int>(state.range(0))).tooth;
  const double rho = 0.5e-3;
  const Vec3 g0 = occlusal_pose(tooth.grid(), rho).x + Vec3(0, 0, 1e-4);
  Contact contact;
  fast::SurfaceCutSet cut(tooth, rho, &fast::signed_distance);
  fast::SurfaceCutSet::Nearest nearest;
  LineWalk line{g0};
  long found = 0;
  for (auto _ : state) {
    const Vec3 g = line.next();
    std::uint8_t material = kEmpty;
    if (state.range(1) == 0) {
      material = proxy_material(tooth, g, rho, &fast::signed_distance);
    } else if (cut.collect(g, contact, nullptr, nullptr, &nearest) && nearest.found) {
      material = tooth.grid().voxels[nearest.voxel];
    }
    found += material != kEmpty;
    benchmark::DoNotOptimize(material);
  }
  state.counters["found"] = static_cast<double>(found) / static_cast<double>(state.iterations());
  state.SetLabel(state.range(1) == 0 ? "octree" : "surface voxels");
}
BENCHMARK(BM_ContactMaterial)->ArgsProduct({{128, 256, 512}, {0, 1}});

// The sdf model's local distance query (fast::LocalVoxelDistance::outside, the nearest-first walk of
// fast/tooth/nearest_voxel_walk.h) along BM_ContactMaterial's line (the anchor 0.1 mm above the
// occlusal pose moving 0.5 um a call, there and back), reach 1 mm widened as the provider widens
// it (FreeSpaceCertificate::widened). Args: resolution, 0 as the provider asks (the last answer's
// voxel and the balls kept) / 1 forgotten before each call (the walk alone, unseeded). Results:
// docs/benchmarks.md "One nearest-first walker".
void BM_LocalVoxelDistance(benchmark::State& state) {
  const VoxelTooth& tooth = bench::built_once<MolarTooth>(static_cast<int>(state.range(0))).tooth;
  const double rho = 0.5e-3;
  const double reach = fast::FreeSpaceCertificate::widened(2.0 * rho, tooth.grid().voxel_size);
  const Vec3 g0 = occlusal_pose(tooth.grid(), rho).x + Vec3(0, 0, 1e-4);
  const fast::SurfaceVoxels surface(tooth);
  const fast::LocalVoxelDistance local(tooth, surface);
  LineWalk line{g0};
  long found = 0;
  for (auto _ : state) {
    const Vec3 g = line.next();
    int cell[3];
    if (sdf_detail::voxel_of(tooth.grid(), g, cell) &&
        tooth.grid().solid(cell[0], cell[1], cell[2])) {
      continue;  // outside() is for points outside the solid
    }
    if (state.range(1) == 1) local.forget();
    SignedDistance sd;
    double best2 = 0.0;
    found += local.outside(g, reach, &sd, &best2) && sd.found;
    benchmark::DoNotOptimize(sd);
  }
  state.counters["found"] = static_cast<double>(found) / static_cast<double>(state.iterations());
  state.counters["balls"] =
      static_cast<double>(local.reused()) / static_cast<double>(std::max(1L, local.queries()));
  state.SetLabel(state.range(1) == 0 ? "kept" : "forgotten");
}
BENCHMARK(BM_LocalVoxelDistance)->ArgsProduct({{128, 256, 512}, {0, 1}});

// The field model's query (issue #30): value and gradient at a point, i.e. the surface proxy's
// distance(x, rho) and, where found, normal(x), on the drill scene's tooth (procedural molar at
// 128^3, 0.5 mm bur) and field: dentsim::FieldSolid (reference) against fast::FieldSolid (fast/
// tooth/field.h). Points: `scatter`, 4096 seeded points within 0.6 mm of the occlusal anchor
// (each query in another cell: no kept query, no certificate); `path`, 4096 points 0.55 um apart
// (a tip at 0.55 mm/s at 1 kHz) from 1 mm above the anchor down through the band into the
// surface, where the kept brick and query and the free-space certificate act. Results:
// docs/benchmarks.md "The field model".
struct FieldScene {
  std::unique_ptr<SceneRig> rig;
  std::vector<Vec3> scatter, path;
  explicit FieldScene(int) {
    Scene scene = load_scene("drill");
    scene.tooth.contact_model = "field";
    SceneRigOptions options;
    options.pipeline = "reference";
    rig = build_scene_rig(scene, options);
    std::mt19937_64 rng(30);
    std::uniform_real_distribution<double> u(-0.6e-3, 0.6e-3);
    const Vec3 a = rig->anchor;
    for (int i = 0; i < 4096; ++i) scatter.push_back(a + Vec3(u(rng), u(rng), u(rng)));
    Vec3 x = a + Vec3(-0.4e-3, 0.1e-3, 1.0e-3);
    for (int i = 0; i < 4096; ++i, x += Vec3(0.2e-6, 0.05e-6, -0.5e-6)) path.push_back(x);
  }
};

template <class Solid>
void run_field_query(benchmark::State& state, const Solid& solid, const std::vector<Vec3>& points,
                     double rho) {
  std::size_t i = 0;
  long found = 0;
  for (auto _ : state) {
    const Vec3& x = points[i];
    i = i + 1 == points.size() ? 0 : i + 1;
    const SignedDistance sd = solid.distance(x, rho);
    benchmark::DoNotOptimize(sd);
    if (sd.found) {
      ++found;
      benchmark::DoNotOptimize(solid.normal(x, sd));
    }
  }
  state.counters["found"] = static_cast<double>(found) / static_cast<double>(state.iterations());
}

// Args: 0 reference, 1 fast; 0 scatter, 1 path.
void BM_FieldQuery(benchmark::State& state) {
  FieldScene& f = bench::built_once<FieldScene>(128);
  const std::vector<Vec3>& points = state.range(1) == 0 ? f.scatter : f.path;
  const double rho = f.rig->tip.radius;
  if (state.range(0) == 0) {
    const dentsim::FieldSolid solid(*f.rig->tooth, *f.rig->field);
    run_field_query(state, solid, points, rho);
  } else {
    const fast::FieldBricks bricks(*f.rig->field, 0);
    const fast::FieldSolid solid(*f.rig->tooth, bricks);
    run_field_query(state, solid, points, rho);
  }
  state.SetLabel(std::string(state.range(0) == 0 ? "reference" : "fast") +
                 (state.range(1) == 0 ? ", scatter" : ", path"));
}
BENCHMARK(BM_FieldQuery)->ArgsProduct({{0, 1}, {0, 1}});

}  // namespace
}  // namespace dentsim
