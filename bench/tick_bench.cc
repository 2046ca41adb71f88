// The servo tick of every implementation in the registry (fast/registry.h), stage by stage, on
// the drill scene's closed loop (simulated Phantom, procedural molar at 128^3, 0.5 mm bur: ~68
// contacts, drilling): the same registry that drives the differential tests.
//
// BM_Tick/<impl>/<method>/<model>/<free|contact>: one servo tick (the pipeline's seven stages;
// the simulated device's physics runs between ticks and is not timed: manual time = the tick's own
// stage times). model: sdf (the scene's surface proxy), faces (the thesis's face model, ~68
// contacts for this bur) or field (the surface proxy on the sampled field, issue #30); free: ticks
// before the first contact, contact: in contact (and drilling). Counters: the mean time of each
// stage over the timed ticks [ns], and the mean contact count. BM_Friction/<impl>: the friction
// solve alone (below). Results: docs/benchmarks.md "The tick, stage by stage".
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "bench/stage_times.h"
#include "fast/registry.h"
#include "reference/core/contact_provider.h"
#include "reference/core/pipeline.h"
#include "sim/scene.h"
#include "sim/simulator.h"
#include "validation/friction_states.h"

namespace dentsim {
namespace {

void BM_Tick(benchmark::State& state, const StageTable* table, bool contact, const char* method,
             const char* model) {
  Scene scene = load_scene("drill");
  scene.method.method = parse_method(method);
  scene.tooth.contact_model = model;
  SceneRigOptions options;
  options.pipeline = table->implementation;
  std::unique_ptr<SceneRig> rig;
  long ticks_in_run = 0;
  const long run_ticks = static_cast<long>(scene.duration * scene.tick_hz);
  StageTimes times;
  double contacts = 0.0;
  for (auto _ : state) {
    for (;;) {
      if (!rig || ticks_in_run >= run_ticks) {
        rig = build_scene_rig(scene, options);
        rig->loop->start();
        ticks_in_run = 0;
      }
      const TickResult& r = rig->loop->step();
      ++ticks_in_run;
      if (rig->loop->faulted()) {
        state.SkipWithError(rig->loop->fault_name());
        return;
      }
      if (r.contacts.empty() == contact) continue;
      contacts += static_cast<double>(r.contacts.size());
      state.SetIterationTime(times.add(r));
      break;
    }
  }
  times.set_counters(state);
  state.counters["contacts"] = contacts / std::max(1L, times.ticks);
  state.SetLabel(std::string(table->implementation) + ", " + method + ", " + model +
                 (contact ? ", contact + drilling" : ", free space"));
}

// What the stage timing itself costs: pipeline_tick over seven stages that do nothing, with
// PipelineModel::time_stages on (a steady_clock read before the stages and after each) and off
// (no clock read). BM_TickTiming/1 - BM_TickTiming/0 is the timing's cost per tick.
TickStatus empty_stage(const PipelineModel&, PipelineData&) { return TickStatus::kOk; }
TickStatus empty_reset(const PipelineModel&, PipelineData&) { return TickStatus::kOk; }

void BM_TickTiming(benchmark::State& state) {
  StageTable table{"empty", {}, &empty_reset};
  for (StageFn& f : table.stage) f = &empty_stage;
  PipelineModel m;
  m.time_stages = state.range(0) != 0;
  auto d = std::make_unique<PipelineData>();
  DeviceSample s;
  s.q = VecX::Zero(6);
  s.qd = VecX::Zero(6);
  NoContacts none;
  for (auto _ : state) {
    s.t += 1e-3;
    benchmark::DoNotOptimize(pipeline_tick(table, m, *d, s, 1e-3, none));
  }
  state.SetLabel(m.time_stages ? "stages timed (8 clock reads)" : "stages not timed");
}
BENCHMARK(BM_TickTiming)->Arg(0)->Arg(1)->Unit(benchmark::kNanosecond);

// BM_Friction/<impl>: the registry's friction solve (Implementation::friction) alone, on the
// drill scene's contact ticks (validation/friction_states.h: the solve stage's input on every tick
// of the fast pipeline's closed loop with a contact set, sdf model), one solve per iteration in
// turn over them. Results: docs/benchmarks.md "Stop 49: the friction solve's fast twin".
void BM_Friction(benchmark::State& state, const Implementation* impl) {
  static const std::vector<FrictionState> kStates = record_friction_states("drill", 5000);
  std::size_t i = 0;
  long sliding = 0, ticks = 0;
  FrictionSolution out;
  for (auto _ : state) {
    const FrictionState& c = kStates[i];
    i = i + 1 == kStates.size() ? 0 : i + 1;
    if (!impl->friction(c.sys, c.contacts, c.proxy, c.normal, c.fp, &out)) {
      state.SkipWithError("the friction solve failed");
      return;
    }
    benchmark::DoNotOptimize(out);
    sliding += out.sliding ? 1 : 0;
    ++ticks;
  }
  state.counters["states"] = static_cast<double>(kStates.size());
  state.counters["sliding"] =
      static_cast<double>(sliding) / static_cast<double>(std::max(1L, ticks));
  state.SetLabel(std::string(impl->name()) + ", drill scene contact ticks (sdf)");
}

const int kRegistered = [] {
  for (const Implementation* impl : implementations()) {
    benchmark::RegisterBenchmark((std::string("BM_Friction/") + impl->name()).c_str(), BM_Friction,
                                 impl)
        ->Unit(benchmark::kNanosecond);
  }
  for (const StageTable* t : stage_tables()) {
    for (const char* method : {"pmi-pd", "pmi"}) {
      for (const char* model : {"sdf", "faces", "field"}) {
        for (const bool contact : {false, true}) {
          const std::string name = std::string("BM_Tick/") + t->implementation + "/" + method +
                                   "/" + model + (contact ? "/contact" : "/free");
          benchmark::RegisterBenchmark(name.c_str(), BM_Tick, t, contact, method, model)
              ->UseManualTime()
              ->Unit(benchmark::kMicrosecond);
        }
      }
    }
  }
  return 0;
}();

}  // namespace
}  // namespace dentsim
