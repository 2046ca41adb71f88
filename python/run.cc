// dentsim.run(scene): `dentsim run` without the files. The scene runs through the same library
// call (sim/simulator.h run_scene) with the same options as the CLI's, and the report is the
// same document (sim/run_report.h run_report_json, the function cmd_run.cc writes
// report.json with), converted to Python objects; the time series are the columns of
// timeseries.csv as NumPy arrays. The scenes: the built-in names, their text, a loaded scene.
#include <cmath>
#include <optional>

#include "device/fault_injection.h"
#include "sim/run_report.h"
#include "sim/scene.h"
#include "sim/simulator.h"
#include "fast/registry.h"
#include "python/module.h"
#include "reference/core/io.h"

namespace dentsim::python {
namespace {

bool is_builtin(const std::string& name) {
  for (const std::string& n : builtin_scene_names())
    if (n == name) return true;
  return false;
}

// The scene of run(): a built-in name or a scene file, at the given servo rate if any
// (`dentsim run --tick-hz`, same message).
Scene load_run_scene(const std::string& name, std::optional<double> tick_hz) {
  if (!tick_hz) return load_scene(name);
  return load_scene_patched(name, {{"tick_hz", *tick_hz}},
                            "at tick_hz " + std::to_string(static_cast<long>(*tick_hz)));
}

py::dict run(const py::handle& scene_in, const std::string& pipeline,
             std::optional<double> duration, std::optional<double> tick_hz, int log_every,
             bool skip_unneeded, std::optional<std::string> inject_fault,
             const py::object& record) {
  if (find_stage_table(pipeline) == nullptr) {
    throw InputError("run: pipeline '" + pipeline + "': expected one of " + stage_table_names());
  }
  if (duration && !(std::isfinite(*duration) && *duration > 0.0 && *duration <= 3600.0)) {
    throw InputError("run: duration " + std::to_string(*duration) +
                     " s: expected 0 < duration <= 3600 (None: the scene's)");
  }
  if (log_every < 1) throw InputError("run: log_every must be at least 1");
  RunOptions ro;
  ro.pipeline = pipeline;
  ro.duration_override = duration.value_or(0.0);
  ro.log_every = log_every;
  ro.skip_unneeded = skip_unneeded;
  if (inject_fault) ro.fault = parse_injected_fault(*inject_fault, "run: inject_fault");
  const std::string scene_name = path_arg(scene_in, "run: scene");
  if (!record.is_none()) {
    ro.record_path = path_arg(record, "run: record");
    check_output_paths({{"record", ro.record_path}}, {{"scene", scene_name}});
  }
  Scene scene;
  RunResult r;
  nlohmann::json report;
  {
    // The run is C++ from here on: other Python threads go on meanwhile.
    py::gil_scoped_release release;
    scene = load_run_scene(scene_name, tick_hz);
    r = run_scene(scene, ro);
    report = run_report_json(scene, r);
  }
  py::dict out = json_to_py(report);
  py::dict series;
  const std::size_t n = r.series.size();
  for (const RunSeriesColumn& c : run_series_columns()) {
    if (c.value == nullptr) {  // the text column (phase): a list of str
      py::list l;
      for (const RunSample& x : r.series) l.append(py::str(x.phase));
      series[c.name] = l;
      continue;
    }
    py::array_t<double> a(static_cast<py::ssize_t>(n));
    auto w = a.mutable_unchecked<1>();
    for (std::size_t i = 0; i < n; ++i) w(static_cast<py::ssize_t>(i)) = c.value(r.series[i]);
    series[c.name] = a;
  }
  out["timeseries"] = series;
  return out;
}

}  // namespace

void bind_run(py::module_& m) {
  m.def("run", &run, py::arg("scene"), py::arg("pipeline") = "fast",
        py::arg("duration") = py::none(), py::arg("tick_hz") = py::none(), py::arg("log_every") = 1,
        py::arg("skip_unneeded") = true, py::arg("inject_fault") = py::none(),
        py::arg("record") = py::none(),
        R"(Run a scene, as `dentsim run SCENE` does, and return its report.

scene         a built-in scene name (builtin_scenes(): probe, probe-groove, drill) or a scene file
              path (docs/scenes.md)
pipeline      the tick's implementation, "fast" (default) or "reference"
duration      simulated time [s] instead of the scene's (`--duration`)
tick_hz       the servo rate [Hz] instead of the scene's (`--tick-hz`)
log_every     keep every n-th tick in the time series (`--log-every`)
skip_unneeded False runs every stage the scene does not need (`--no-skip`)
inject_fault  "KIND@T", a device fault (`--inject-fault`)
record        a file to record every tick to, for read_session() and replay() (`--record`)

Returns a dict with exactly the keys of report.json (docs/scenes.md) plus "timeseries": the
columns of timeseries.csv (t_s, contact_force_n, penetration_m, observer_fx_n, ...) as NumPy
arrays, "phase" as a list of str. A device fault does not raise: the report's "faults" lists it
(the CLI exits 1 then). Bad inputs raise dentsim.InputError. The GIL is released during the run.)");

  m.def("builtin_scenes", &builtin_scene_names, "The names of the built-in scenes.");
  m.def(
      "scene_text", [](const std::string& name) { return builtin_scene_text(name); },
      py::arg("name"),
      "The JSON text of a built-in scene (`dentsim run NAME --show`): a start for a scene file.");
  m.def(
      "load_scene",
      [](const py::handle& scene) {
        const std::string name = path_arg(scene, "load_scene: scene");
        const Scene s = load_scene(name);
        py::dict d;
        d["name"] = s.name;
        d["description"] = s.description;
        d["origin"] = s.origin;
        d["builtin"] = is_builtin(name);  // load_scene's rule: a built-in name first
        d["duration_s"] = s.duration;
        d["tick_hz"] = s.tick_hz;
        d["document"] = json_to_py(nlohmann::json::parse(s.text));
        return d;
      },
      py::arg("scene"),
      "Load and validate a scene (built-in name or scene file; errors name the field): its name, "
      "description, origin, duration_s, tick_hz and the parsed JSON document.");
}

}  // namespace dentsim::python
