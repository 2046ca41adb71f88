// The servo tick's stage times over the timed ticks of a closed-loop benchmark (BM_Tick in
// bench/tick_bench.cc, BM_Skip in bench/skip_bench.cc): each tick's total is the benchmark's
// manual time, and the mean of each stage becomes a counter "<stage>_ns".
#pragma once

#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <string>

#include "reference/core/pipeline.h"

namespace dentsim {

struct StageTimes {
  std::array<double, kStageCount> sum{};
  long ticks = 0;

  // Adds one tick; returns its total [s] (for State::SetIterationTime).
  double add(const TickResult& r) {
    long total = 0;
    for (int i = 0; i < kStageCount; ++i) {
      total += r.stage_ns[i];
      sum[i] += static_cast<double>(r.stage_ns[i]);
    }
    ++ticks;
    return 1e-9 * static_cast<double>(total);
  }
  void set_counters(benchmark::State& state) const {
    for (int i = 0; i < kStageCount; ++i) {
      state.counters[std::string(tick_stage_name(i)) + "_ns"] = sum[i] / std::max(1L, ticks);
    }
  }
};

}  // namespace dentsim
