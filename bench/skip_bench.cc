// What each of the fast pipeline's skips saves (issue #14; PipelineModel::skip_unneeded): the
// variants of validation/skip_variants.h (the list tests/fast/skip_test.cc checks equal), each run
// in closed loop with skips on and off. BM_Skip/<variant>/<on|off>: one servo tick, manual time =
// the tick's stage times (the simulated device's physics between ticks is not timed), every tick
// of the run (free space and contact); counters: the mean time of each stage [ns].
// Results: docs/benchmarks.md "Skips".
#include <benchmark/benchmark.h>

#include <array>
#include <memory>
#include <string>

#include "bench/stage_times.h"
#include "validation/skip_variants.h"

namespace dentsim {
namespace {

void BM_Skip(benchmark::State& state, const SkipVariant* v, bool skip) {
  std::unique_ptr<SceneRig> rig;
  long ticks_in_run = 0;
  const long run_ticks = 4000;
  StageTimes times;
  for (auto _ : state) {
    if (!rig || ticks_in_run >= run_ticks) {
      rig = build_skip_variant_rig(*v, skip);  // not timed: manual time is the tick's stages
      rig->loop->start();
      ticks_in_run = 0;
    }
    const TickResult& r = rig->loop->step();
    ++ticks_in_run;
    if (rig->loop->faulted()) {
      state.SkipWithError(rig->loop->fault_name());
      return;
    }
    state.SetIterationTime(times.add(r));
  }
  times.set_counters(state);
  state.SetLabel(v->skips);
}

const int kRegistered = [] {
  for (const SkipVariant& v : skip_variants()) {
    for (const bool skip : {true, false}) {
      const std::string name = "BM_Skip/" + v.name + (skip ? "/on" : "/off");
      benchmark::RegisterBenchmark(name.c_str(), BM_Skip, &v, skip)
          ->UseManualTime()
          ->Unit(benchmark::kMicrosecond);
    }
  }
  return 0;
}();

}  // namespace
}  // namespace dentsim
