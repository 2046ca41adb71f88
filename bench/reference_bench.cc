// Google Benchmark of the reference pipeline: one servo tick per method, in free space and in
// contact with a flat wall, and the voxel tooth's collision query. Results and the command that
// made them: docs/benchmarks.md. Run: build/release/bench/dentsim_bench
#include <benchmark/benchmark.h>

#include "reference/half_space_wall.h"
#include "reference/rigid_body_device.h"
#include "reference/tick.h"
#include "reference/tools.h"
#include "reference/tooth/collision.h"
#include "tooth_io/procedural_molar.h"

namespace dentsim {
namespace {

PipelineConfig config_for(Method m) {
  PipelineConfig c;
  c.method = m;
  c.proxy.mass = 0.02;
  c.proxy.inertia = Mat3::Identity() * 2e-6;
  c.tool = tool_preset("handpiece");
  c.observer_gain = VecX::Constant(6, 30.0);
  return c;
}

// One tick of the reference pipeline; arg 0: method, arg 1: 1 = in contact with a flat wall.
void BM_ReferenceTick(benchmark::State& state) {
  const Method m = static_cast<Method>(state.range(0));
  const bool contact = state.range(1) != 0;
  const RigidBodyDevice device;
  ReferencePipeline p(device, config_for(m));
  HalfSpaceWall wall(Vec3(0, 0, contact ? 0.0009 : -1.0), Vec3::UnitZ(), 0.001, 3000.0, 5.0);
  DeviceSample s;
  s.q = VecX::Zero(6);
  s.qd = VecX::Zero(6);
  p.reset(s);
  double t = 0.0;
  for (auto _ : state) {
    t += 1e-3;
    s.t = t;
    benchmark::DoNotOptimize(p.tick(s, 1e-3, wall));
  }
  state.SetLabel(std::string(method_name(m)) + (contact ? ", contact" : ", free"));
}
BENCHMARK(BM_ReferenceTick)
    ->ArgsProduct({{static_cast<int>(Method::kExplicitVc), static_cast<int>(Method::kPmiVc),
                    static_cast<int>(Method::kPmiPd)},
                   {0, 1}});

// The tool-tip sphere against the procedural molar at 128^3: octree descent + contact set.
void BM_ToothCollision(benchmark::State& state) {
  static const VoxelTooth tooth(voxelize_procedural_molar(MolarParams{}, 128));
  const VoxelGrid& g = tooth.grid();
  // A point on the occlusal surface: the highest solid voxel of the centre column, tip sunk 0.1 mm.
  const int c = g.n / 2;
  int top = 0;
  for (int k = 0; k < g.n; ++k) {
    if (g.solid(c, c, k)) top = k;
  }
  ToolTip tip;
  tip.radius = static_cast<double>(state.range(0)) * 1e-4;
  Pose pose;
  pose.x = g.center(c, c, top) + Vec3(0, 0, 0.5 * g.voxel_size + tip.radius - 1e-4);
  CollisionScratch scratch;
  std::vector<Contact> contacts;
  contacts.reserve(4096);
  for (auto _ : state) {
    contacts.clear();
    collide_tool_tip(tooth, pose, tip, 3000.0, 5.0, &scratch, &contacts);
    benchmark::DoNotOptimize(contacts.data());
  }
  state.counters["contacts"] = static_cast<double>(contacts.size());
}
BENCHMARK(BM_ToothCollision)->Arg(3)->Arg(5)->Arg(10);

}  // namespace
}  // namespace dentsim

BENCHMARK_MAIN();
