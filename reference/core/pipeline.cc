// The tick driver shared by every implementation of the stage list (reference/core/pipeline.h).
#include "reference/core/pipeline.h"

#include <chrono>
#include <cmath>

namespace dentsim {

const char* tick_status_name(TickStatus s) {
  switch (s) {
    case TickStatus::kOk:
      return "ok";
    case TickStatus::kBadTickLength:
      return "tick_bad_length";
    case TickStatus::kBadSample:
      return "tick_bad_sample";
    case TickStatus::kDeviceModelFailure:
      return "tick_device_model_failure";
    case TickStatus::kContactBufferFull:
      return "tick_contact_buffer_full";
    case TickStatus::kBadContact:
      return "tick_bad_contact";
    case TickStatus::kSolverFailure:
      return "tick_solver_failure";
    case TickStatus::kNonFiniteOutput:
      return "tick_non_finite_output";
    case TickStatus::kDrillWorkTableFull:
      return "tick_drill_work_table_full";
    case TickStatus::kFieldEditShortfall:
      return "tick_field_edit_shortfall";
  }
  return "tick_unknown_status";
}

const char* tick_stage_name(int stage) {
  static const char* const kNames[kStageCount] = {
#define DENTSIM_STAGE_NAME(id, name) name,
      DENTSIM_TICK_STAGES(DENTSIM_STAGE_NAME)
#undef DENTSIM_STAGE_NAME
  };
  return stage >= 0 && stage < kStageCount ? kNames[stage] : "?";
}

namespace {

// Copies a sample into the data; false if it is not a finite 6-joint sample.
bool load_sample(const DeviceSample& s, PipelineData& d) {
  if (s.q.size() != 6 || s.qd.size() != 6) return false;
  if (!s.q.allFinite() || !s.qd.allFinite() || !std::isfinite(s.t)) return false;
  d.q = s.q;
  d.qd = s.qd;
  d.t = s.t;
  return true;
}

TickStatus fail(PipelineData& d, TickStatus st) {
  d.r.status = st;
  d.r.tau.setZero();
  d.r.tau_gravity.setZero();
  d.tau_prev.setZero();
  return st;
}

}  // namespace

TickStatus pipeline_reset(const StageTable& table, const PipelineModel& m, PipelineData& d,
                          const DeviceSample& s) {
  TickResult& r = d.r;
  // The result back to its defaults, keeping the contact buffer's storage.
  ContactBuffer buffer = std::move(r.contacts);
  buffer.clear();
  r = TickResult{};
  r.contacts = std::move(buffer);
  d.have_prev = false;
  if (!load_sample(s, d)) return fail(d, TickStatus::kBadSample);
  d.t_prev = d.t;
  const TickStatus st = table.reset(m, d);
  if (st != TickStatus::kOk) return fail(d, st);
  return TickStatus::kOk;
}

TickStatus pipeline_tick(const StageTable& table, const PipelineModel& m, PipelineData& d,
                         const DeviceSample& s, double T, ContactProvider& env) {
  TickResult& r = d.r;
  r.status = TickStatus::kOk;
  for (long& ns : r.stage_ns) ns = 0;
  if (!(T > 0.0) || !std::isfinite(T)) return fail(d, TickStatus::kBadTickLength);
  if (!load_sample(s, d)) return fail(d, TickStatus::kBadSample);
  d.T = T;
  d.env = &env;
  if (!m.time_stages) {
    for (int i = 0; i < kStageCount; ++i) {
      const TickStatus st = table.stage[i](m, d);
      if (st != TickStatus::kOk) return fail(d, st);
    }
    return TickStatus::kOk;
  }
  auto last = std::chrono::steady_clock::now();
  for (int i = 0; i < kStageCount; ++i) {
    const TickStatus st = table.stage[i](m, d);
    const auto now = std::chrono::steady_clock::now();
    r.stage_ns[i] = std::chrono::duration_cast<std::chrono::nanoseconds>(now - last).count();
    last = now;
    if (st != TickStatus::kOk) return fail(d, st);
  }
  return TickStatus::kOk;
}

}  // namespace dentsim
