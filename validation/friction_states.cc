#include "validation/friction_states.h"

#include <memory>
#include <stdexcept>
#include <string>

#include "fast/registry.h"
#include "sim/scene.h"
#include "sim/simulator.h"

namespace dentsim {

namespace {

TickStatus no_stage(const PipelineModel&, PipelineData&) { return TickStatus::kOk; }

}  // namespace

std::vector<FrictionState> record_friction_states(const std::string& scene_name, long ticks) {
  SceneRigOptions ro;
  ro.pipeline = "fast";
  const std::unique_ptr<SceneRig> rig = build_scene_rig(load_scene(scene_name), ro);
  const StageTable& table = *implementation("fast").stages;
  // The stages up to assemble (pipeline_tick loads the sample); the rest run one by one below.
  StageTable head = table;
  for (int i = kStageSolve; i < kStageCount; ++i) head.stage[i] = &no_stage;
  const PipelineModel& m = dynamic_cast<const StagedPipeline&>(*rig->pipeline).model();
  auto d = std::make_unique<PipelineData>();
  Device& dev = *rig->device;
  DeviceSample s = dev.make_sample();
  dev.read(s);
  if (pipeline_reset(table, m, *d, s) != TickStatus::kOk) {
    throw std::runtime_error("record_friction_states: the pipeline could not start");
  }
  std::vector<FrictionState> out;
  double T = dev.capabilities().nominal_period;
  for (long k = 0; k < ticks; ++k) {
    TickStatus st = pipeline_tick(head, m, *d, s, T, *rig->contacts);
    if (st == TickStatus::kOk && !d->r.contacts.empty()) {
      out.push_back({d->sys,
                     {d->r.contacts.begin(), d->r.contacts.end()},
                     d->proxy.pose,
                     d->contact,
                     m.friction});
    }
    for (int i = kStageSolve; i < kStageCount && st == TickStatus::kOk; ++i) {
      st = table.stage[i](m, *d);
    }
    if (st != TickStatus::kOk) {
      throw std::runtime_error(std::string("record_friction_states: tick ") + std::to_string(k) +
                               " failed: " + tick_status_name(st));
    }
    const double t_prev = s.t;  // the next tick's length: the sample clock's step
    dev.write(d->r.tau);
    dev.advance();
    dev.read(s);
    if (s.t > t_prev) T = s.t - t_prev;
  }
  return out;
}

}  // namespace dentsim
