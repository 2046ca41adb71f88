// What a run of a scene reports (issue #20): the document of report.json and the columns of the
// time series, built in one place so that `dentsim run` (cli/cmd_run.cc: report.json,
// timeseries.csv) and the Python module (`dentsim.run`, python/) cannot drift apart.
//
// report.json (docs/scenes.md describes every key): the scene, the method, the device model, the
// pipeline, the tick rate; the counts, forces, penetration, rendered stiffness and passivity
// observers of simulator.h; the removed volume per material; the time the pulp opened; the
// timing statistics per stage; the faults. Keys that only some runs have: `hd_loop` and
// `callback_dropped_ticks` (hdapi), `realtime` (--realtime), `recorded_ticks` and
// `record_dropped_ticks` (--record), `torque_after_fault_n_m` (a fault). Values that depend on
// the wall clock: `wall_s`, `setup_s`, `timing_us`, `realtime`.
//
// The time series: one row per logged tick (RunOptions::log_every), the columns of
// run_series_columns() in order; every column is a number but `phase` (the script's label).
#pragma once

#include <nlohmann/json.hpp>
#include <span>

#include "sim/scene.h"
#include "sim/simulator.h"

namespace dentsim {

// The report.json document of a run of `scene`.
nlohmann::json run_report_json(const Scene& scene, const RunResult& r);

// The quiet measures of a run (sim/quiet_measures.h): its steady press and slide phases and
// its free space, cut by the scene's script; and their JSON, the report's `quiet` block:
// {"bounds", "tip_quantum_m", "phases": [{"phase", "kind", ..., "quiet"}], "free_space",
// "quiet"} (docs/scenes.md).
QuietReport run_quiet_report(const Scene& scene, const RunResult& r,
                             const QuietBounds& bounds = {});
nlohmann::json quiet_report_json(const QuietReport& q);

// One column of the time series: its name (units in the suffix) and, for a numeric column, its
// value in a sample; `value` is null for the one text column, "phase" (RunSample::phase).
struct RunSeriesColumn {
  const char* name;
  double (*value)(const RunSample&);
};

// Every column of timeseries.csv, in the file's order ("t_s", "phase", "contacts", ...).
std::span<const RunSeriesColumn> run_series_columns();

}  // namespace dentsim
