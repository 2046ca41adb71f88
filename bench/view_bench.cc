// Google Benchmark of the view's surface mesh (view/surface_mesh.h): meshing the whole 128^3
// procedural molar against the incremental update after drilling a small ball (what the live view
// does per frame while the bur cuts). Results and the command: docs/view.md.
// Run: build/release/bench/dentsim_view_bench
#include <benchmark/benchmark.h>

#include <cmath>

#include "tooth_io/procedural_molar.h"
#include "view/surface_mesh.h"

namespace dentsim::view {
namespace {

const VoxelGrid& molar() {
  static const VoxelGrid g = voxelize_procedural_molar(MolarParams{}, 128);
  return g;
}

// Full mesh of the tooth, block size arg 0.
void BM_FullMesh(benchmark::State& state) {
  const int block = static_cast<int>(state.range(0));
  for (auto _ : state) {
    SurfaceMesher m(molar(), block);
    benchmark::DoNotOptimize(m.triangle_count());
  }
}
BENCHMARK(BM_FullMesh)->Arg(8)->Arg(16)->Arg(32)->Unit(benchmark::kMillisecond);

// Incremental update after removing a ball of radius arg 1 voxels at the top of the crown's
// centre column; block size arg 0. Each iteration restores the ball (untimed) and removes it.
void BM_DrillUpdate(benchmark::State& state) {
  const int block = static_cast<int>(state.range(0));
  const int r = static_cast<int>(state.range(1));
  VoxelGrid g = molar();
  const int c = g.n / 2;
  int top = 0;
  for (int k = 0; k < g.n; ++k) {
    if (g.solid(c, c, k)) top = k;
  }
  std::vector<std::size_t> ball;
  for (int k = top - r; k <= top + r; ++k) {
    for (int j = c - r; j <= c + r; ++j) {
      for (int i = c - r; i <= c + r; ++i) {
        if (std::hypot(i - c, j - c, k - top) <= r && g.solid(i, j, k))
          ball.push_back(g.index(i, j, k));
      }
    }
  }
  SurfaceMesher m(g, block);
  const VoxelGrid original = g;
  std::size_t blocks = 0;
  for (auto _ : state) {
    state.PauseTiming();
    for (std::size_t idx : ball) g.voxels[idx] = original.voxels[idx];
    m.update(g, ball);
    for (std::size_t idx : ball) g.voxels[idx] = 0;
    state.ResumeTiming();
    blocks = m.update(g, ball).size();
  }
  state.counters["voxels"] = static_cast<double>(ball.size());
  state.counters["blocks"] = static_cast<double>(blocks);
}
BENCHMARK(BM_DrillUpdate)
    ->Args({8, 3})
    ->Args({16, 3})
    ->Args({32, 3})
    ->Args({16, 8})
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace dentsim::view

BENCHMARK_MAIN();
