// `dentsim run SCENE --out DIR`: the main job — the dental simulator on the embedded default
// (simulated Phantom, voxel tooth, scripted hand). Writes DIR/report.json, DIR/timeseries.csv,
// DIR/force_penetration.png, DIR/observer.png, DIR/quiet.png (what the hand feels: issue #29),
// DIR/tooth_before.png, DIR/tooth_after.png and, when the tool drills, DIR/drill_depth.png.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <span>
#include <sstream>

#include "cli/interrupt.h"
#include "cli/outputs.h"
#include "device/backend.h"
#include "cli/plot.h"
#include "cli/png_writer.h"
#include "cli/progress.h"
#include "cli/registry.h"
#include "cli/run_view.h"
#include "device/fault_injection.h"
#include "sim/run_report.h"
#include "sim/scene.h"
#include "sim/simulator.h"
#include "sim/scene_stability.h"
#include "fast/registry.h"
#include "reference/core/io.h"
#include "reference/tooth/materials.h"
#include "tooth_io/render_png.h"

namespace dentsim::cli {
namespace {

struct RunCliOptions {
  std::string scene;
  std::string out = "out/run";
  bool realtime = false;
  double duration = 0.0;
  double tick_hz = 0.0;  // 0 = the scene's
  bool list = false;
  bool show = false;
  int log_every = 1;
  RunViewOptions view;
  std::string pipeline = "fast";
  std::string inject_fault;
  std::string record;      // --record FILE
  std::string tick_times;  // --tick-times FILE
  std::string device;      // "" = the scene's device.type
  std::string hd_library;
  std::string hd_loop = "callback";
  bool no_skip = false;  // --no-skip
  bool force = false;    // --force: run a scene its method's stability bound refuses
};

// timeseries.csv: the columns of run_series_columns() (sim/run_report.h, shared with the
// Python module), 9 significant digits.
std::string csv_of(const RunResult& r) {
  const std::span<const RunSeriesColumn> cols = run_series_columns();
  std::ostringstream s;
  s.precision(9);
  for (std::size_t c = 0; c < cols.size(); ++c) s << (c ? "," : "") << cols[c].name;
  s << '\n';
  for (const RunSample& x : r.series) {
    for (std::size_t c = 0; c < cols.size(); ++c) {
      if (c) s << ',';
      if (cols[c].value == nullptr) {
        s << x.phase;
      } else {
        s << cols[c].value(x);
      }
    }
    s << '\n';
  }
  return s.str();
}

// DIR/drill_depth.png (drilling scenes): the contact force and the removal rate against the
// depth of the cut below its first contact, one colour per material under the bur. The rate is
// the removed volume over a moving window of 100 drilling ticks.
void write_drill_plot(const RunResult& r, const std::string& dir) {
  if (r.drill_log.empty()) return;
  constexpr std::size_t kWindow = 100;
  const double voxel_mm3 = r.tooth_before.voxel_volume() * 1e9;
  std::vector<double> removed_mm3;
  for (const DrillRecord& d : r.drill_log) {
    int n = 0;
    for (const int c : d.removed) n += c;
    removed_mm3.push_back(n * voxel_mm3);
  }
  plot::Figure force{"Drilling: contact force against depth (colour: material under the bur)",
                     "depth below the first contact [mm]",
                     "force [N]",
                     {},
                     false,
                     false};
  plot::Figure rate{"Drilling: removal rate against depth (moving window of 100 ticks)",
                    "depth below the first contact [mm]",
                    "removal rate [mm^3/s]",
                    {},
                    false,
                    false};
  double window_sum = 0.0;
  std::vector<double> rates;
  for (std::size_t i = 0; i < r.drill_log.size(); ++i) {
    window_sum += removed_mm3[i];
    if (i >= kWindow) window_sum -= removed_mm3[i - kWindow];
    const double ticks = static_cast<double>(std::min(i + 1, kWindow));
    rates.push_back(window_sum / (ticks * r.tick_s));
  }
  for (int m = 1; m < kMaterialCount; ++m) {
    plot::Series fs{material_properties(m).name, {}, {}, true, m - 1, false};
    plot::Series rs{material_properties(m).name, {}, {}, true, m - 1, false};
    for (std::size_t i = 0; i < r.drill_log.size(); ++i) {
      if (r.drill_log[i].material != m) continue;
      fs.x.push_back(r.drill_log[i].depth_m * 1e3);
      fs.y.push_back(r.drill_log[i].force_n);
      rs.x.push_back(r.drill_log[i].depth_m * 1e3);
      rs.y.push_back(rates[i]);
    }
    if (fs.x.empty()) continue;
    force.series.push_back(std::move(fs));
    rate.series.push_back(std::move(rs));
  }
  plot::write_png({force, rate}, dir + "/drill_depth.png", 1, 900, 360);
}

void write_plots(const RunResult& r, const std::string& dir) {
  write_drill_plot(r, dir);
  std::vector<double> t, fc, fd, pen, dpen, e, wh;
  std::vector<double> hx, hz, ox, oz;
  for (const RunSample& x : r.series) {
    t.push_back(x.t);
    fc.push_back(x.contact_force_n);
    fd.push_back(x.device_force_n);
    pen.push_back(x.penetration_m * 1e3);
    dpen.push_back(x.device_penetration_m * 1e3);
    e.push_back(x.energy_virtual_j * 1e3);
    wh.push_back(x.hand_work_j * 1e3);
    hx.push_back(x.hand_force_n.x());
    hz.push_back(x.hand_force_n.z());
    ox.push_back(x.observer_force_n.x());
    oz.push_back(x.observer_force_n.z());
  }
  plot::Figure force{"Contact force (proxy) and force fed back (device)",
                     "time [s]",
                     "force [N]",
                     {},
                     false,
                     false};
  force.series.push_back({"contact force on proxy", t, fc, false, 0, false});
  force.series.push_back({"force on device", t, fd, false, 1, true});
  plot::Figure depth{"Penetration of the tooth", "time [s]", "depth [mm]", {}, false, false};
  depth.series.push_back({"proxy tip", t, pen, false, 0, false});
  depth.series.push_back({"device tip", t, dpen, false, 1, true});
  plot::Figure energy{"Passivity observers: hand port W_h (>= 0: passive), motor port E_v",
                      "time [s]",
                      "energy [mJ]",
                      {},
                      false,
                      false};
  // On a device (has_ground_truth false) the hand's work and force are not known: not drawn as
  // zero (issue #33).
  if (r.has_ground_truth) {
    energy.series.push_back({"W_h: work done by the hand", t, wh, false, 2, false});
  } else {
    energy.title = "Passivity observer: motor port E_v (the hand's work is not known on a device)";
  }
  energy.series.push_back({"E_v: motors, net of gravity", t, e, false, 4, true});
  plot::write_png({force, depth, energy}, dir + "/force_penetration.png", 1, 900, 320);

  plot::Figure ob{"Human force: observer estimate vs true hand force",
                  "time [s]",
                  "force [N]",
                  {},
                  false,
                  false};
  if (!r.has_ground_truth) {
    ob.title = "Human force: observer estimate (no true hand force on a device)";
  }
  if (r.has_ground_truth) ob.series.push_back({"hand f_z (true)", t, hz, false, 0, false});
  ob.series.push_back({"observer f_z", t, oz, false, 1, true});
  if (r.has_ground_truth) ob.series.push_back({"hand f_x (true)", t, hx, false, 2, false});
  ob.series.push_back({"observer f_x", t, ox, false, 3, true});
  plot::write_png({ob}, dir + "/observer.png", 1, 900, 420);
}

// DIR/quiet.png: what the hand feels. Top: the force on the device and its 0.1 s centred moving
// average (the steady force), each steady press/slide phase shaded by a line at its mean with its
// ripple and contact losses in the legend, every contact loss marked. Bottom: the force ripple
// over the window (RMS of the force minus its moving average, over that average) of the force on
// the device and of the contact force, against the bound.
void write_quiet_plot(const RunResult& r, const QuietReport& q, const std::string& dir) {
  const QuietSeries& s = r.quiet_series;
  const int h = quiet_half_window(q.bounds, s.tick_s);
  const std::size_t n = s.t.size();
  plot::Figure felt{"What the hand feels: force on the device (contact losses marked)",
                    "time [s]",
                    "force [N]",
                    {},
                    false,
                    false};
  felt.series.push_back({"force on device", s.t, s.device_force_n, false, 1, false});
  plot::Figure ripple{"Force ripple over 0.1 s (RMS of force - moving average, / average)",
                      "time [s]",
                      "ripple [%]",
                      {},
                      false,
                      false};
  const std::size_t w = 2 * static_cast<std::size_t>(h) + 1;
  if (n >= w) {
    const std::vector<double> avg = centred_moving_average(s.device_force_n, h);
    std::vector<double> ta(s.t.begin() + h, s.t.begin() + h + avg.size());
    felt.series.push_back({"0.1 s average", ta, avg, false, 0, true});
    // Rolling ripple over the steady press/slide phases (the stretches the verdict measures).
    auto steady = [&q](double t) {
      for (const QuietPhase& p : q.phases) {
        if (t >= p.steady_from_s && t < p.t_end_s) return true;
      }
      return false;
    };
    for (int which = 0; which < 2; ++which) {
      const std::vector<double>& f = which == 0 ? s.device_force_n : s.contact_force_n;
      const std::vector<double> a = centred_moving_average(f, h);
      plot::Series rs{which == 0 ? "force on device" : "contact force",
                      {},
                      {},
                      true,
                      which == 0 ? 1 : 0,
                      false};
      for (std::size_t j = h; j + h < a.size(); j += 5) {
        if (!steady(s.t[j + h]) || !(a[j] > 0.0)) continue;
        double sum = 0.0;
        for (std::size_t i = j - h; i <= j + h; ++i) {
          const double res = f[i + h] - a[i];
          sum += res * res;
        }
        rs.x.push_back(s.t[j + h]);
        rs.y.push_back(100.0 * std::sqrt(sum / static_cast<double>(w)) / a[j]);
      }
      ripple.series.push_back(std::move(rs));
    }
  }
  plot::Series losses{"contact loss", {}, {}, true, 3, false};
  for (std::size_t i = 0; i + 1 < n; ++i) {
    if (s.contacts[i] > 0 && s.contacts[i + 1] <= 0) {
      losses.x.push_back(s.t[i + 1]);
      losses.y.push_back(0.0);
    }
  }
  felt.series.push_back(std::move(losses));
  int color = 4;
  for (const QuietPhase& p : q.phases) {
    char label[200];
    std::snprintf(label, sizeof label, "%s: ripple %.0f/%.0f %%, %d losses%s", p.phase.c_str(),
                  100.0 * p.ripple_device_force.value_or(0.0),
                  100.0 * p.ripple_contact_force.value_or(0.0), p.contact_losses,
                  p.quiet ? ", quiet" : "");
    felt.series.push_back({label,
                           {p.steady_from_s, p.t_end_s},
                           {p.mean_device_force_n, p.mean_device_force_n},
                           false,
                           color++,
                           false});
  }
  if (!s.t.empty()) {
    ripple.series.push_back(
        {"bound " + std::to_string(static_cast<int>(std::lround(100.0 * q.bounds.ripple_max))) +
             " %",
         {s.t.front(), s.t.back()},
         {100.0 * q.bounds.ripple_max, 100.0 * q.bounds.ripple_max},
         false,
         2,
         true});
  }
  plot::write_png({felt, ripple}, dir + "/quiet.png", 1, 900, 360);
}

void write_run_outputs(const RunCliOptions& o, const Scene& scene, const RunResult& r,
                       const std::string& partial_reason);

void run(const RunCliOptions& o) {
  if (o.list) {
    int width = 0;  // the names in one column
    for (const std::string& n : builtin_scene_names()) width = std::max(width, static_cast<int>(n.size()));
    for (const std::string& n : builtin_scene_names()) {
      const Scene s = load_scene(n);
      std::printf("%-*s %s\n", width, n.c_str(), s.description.c_str());
    }
    return;
  }
  if (o.scene.empty()) throw InputError("run: a SCENE (built-in name or file) is required");
  if (o.show) {
    bool builtin = false;
    for (const std::string& n : builtin_scene_names()) builtin = builtin || n == o.scene;
    std::printf("%s\n", builtin ? builtin_scene_text(o.scene).c_str() : read_file(o.scene).c_str());
    return;
  }
  if (o.duration < 0.0) throw InputError("--duration must be positive");
  if (o.log_every < 1) throw InputError("--log-every must be at least 1");
  if (find_stage_table(o.pipeline) == nullptr) {
    throw InputError("--pipeline '" + o.pipeline + "': expected one of " + stage_table_names());
  }
  const InjectedFault fault = o.inject_fault.empty()
                                  ? InjectedFault{}
                                  : parse_injected_fault(o.inject_fault, "--inject-fault");
  check_outputs({{"--record", o.record}, {"--tick-times", o.tick_times}},
                {{"--out", o.out}, {"--view-shots", o.view.shots_dir}}, {{"scene", o.scene}});
  const Scene scene =
      o.tick_hz > 0.0
          ? load_scene_patched(o.scene, {{"tick_hz", o.tick_hz}},
                               "at --tick-hz " + std::to_string(static_cast<long>(o.tick_hz)))
          : load_scene(o.scene);
  // What cannot be stable is refused before the run (sim/scene_stability.h).
  if (!o.force) check_scene_stability(scene);
  make_output_dir({"--out", o.out});
  // Ctrl-C / SIGTERM: the loop stops at a tick boundary and every output of the ticks that ran is
  // written, report.json "partial": true (cli/interrupt.h). Installed before the first line.
  const StopOnSignal stop;

  std::fprintf(stderr, "dentsim run: scene '%s' (%s), %.2f s at %.0f Hz, method %s, %s pipeline\n",
               scene.name.c_str(), scene.origin.c_str(),
               o.duration > 0 ? o.duration : scene.duration, scene.tick_hz,
               method_name(scene.method.method), o.pipeline.c_str());
  ProgressBar bar("simulating");
  RunOptions ro;
  ro.pipeline = o.pipeline;
  ro.fault = fault;
  ro.realtime = o.realtime;
  ro.realtime_priority = o.realtime;
  ro.duration_override = o.duration;
  ro.log_every = o.log_every;
  ro.record_path = o.record;
  ro.tick_times_path = o.tick_times;
  ro.device = o.device;
  ro.hd_library = o.hd_library;
  ro.hd_loop = o.hd_loop;
  ro.skip_unneeded = !o.no_skip;
  ro.progress = [&bar](double f) { bar.update(f); };
  ro.stop = &stop.flag();
  RunViewOptions view = o.view;
  const double planned_s = o.duration > 0 ? o.duration : scene.duration;
  std::string partial_reason;
  view.on_done = [&](const RunResult& r) {
    bar.finish();
    if (r.stopped) {
      char why[160];
      std::snprintf(why, sizeof why, "stopped by %s at t = %.3f s of %.3f s",
                    stop.signal_name().c_str(), r.simulated_s, planned_s);
      partial_reason = why;
    }
    write_run_outputs(o, scene, r, partial_reason);
  };
  const RunResult r = run_scene_with_view(scene, ro, view);
  if (r.stopped) {
    throw Interrupted("run " + partial_reason + "; partial outputs in " + o.out +
                          "/ (report.json \"partial\": true)",
                      stop.exit_status());
  }
  if (!r.faults.empty())
    throw std::runtime_error("the device faulted (safe stop): " + r.faults.front());
}

// Writes every output of the run into o.out and prints the summary; `partial_reason` non-empty:
// the run was stopped early (report.json "partial": true, "partial_reason").
void write_run_outputs(const RunCliOptions& o, const Scene& scene, const RunResult& r,
                       const std::string& partial_reason) {
  nlohmann::json report = run_report_json(scene, r);
  report["partial"] = !partial_reason.empty();
  if (!partial_reason.empty()) report["partial_reason"] = partial_reason;
  write_json(o.out + "/report.json", report);
  write_file_atomic(o.out + "/timeseries.csv", csv_of(r));
  write_plots(r, o.out);
  const QuietReport quiet = run_quiet_report(scene, r);
  write_quiet_plot(r, quiet, o.out);
  write_tooth_pictures(r, o.out);

  std::printf("scene %s: %ld ticks (%ld in contact), %.2f s simulated in %.2f s\n",
              scene.name.c_str(), r.ticks, r.contact_ticks, r.simulated_s, r.wall_s);
  std::printf("  contact force max %.3f N, rms %.3f N; penetration max %.3f mm\n",
              r.max_contact_force_n, r.rms_contact_force_n, r.max_penetration_m * 1e3);
  std::printf(
      "  rendered stiffness %.0f N/m; energy from the motors %.3g J; hand port min %.3g J (%s)\n",
      r.rendered_stiffness_n_per_m, r.virtual_energy_generated_j, r.hand_work_min_j,
      !r.has_ground_truth          ? "the hand's force is not measured on this device"
      : r.hand_work_min_j >= -1e-6 ? "passive toward the hand"
                                   : "ACTIVE toward the hand");
  std::printf("  removed %.4f mm^3 (enamel %.4f, dentin %.4f, pulp %.4f)\n",
              r.removed_volume_total_mm3, r.removed_volume_mm3[kEnamel],
              r.removed_volume_mm3[kDentin], r.removed_volume_mm3[kPulp]);
  for (const auto& [name, s] : r.timing) {
    if (name == "tick") {
      std::printf("  tick time median %.1f us, p99 %.1f us, max %.1f us\n", s.median_us, s.p99_us,
                  s.max_us);
    }
    // A simulated run whose servo did or waited for the field edit worker's batches: its own tick.
    if (name == "servo_tick" && r.field_edit_stand_in_ns > 0) {
      std::printf(
          "  servo's own tick median %.1f us, p99 %.1f us, max %.1f us (without the field edit's "
          "%ld takeovers and %ld waits, %.1f ms: the worker's work in real time)\n",
          s.median_us, s.p99_us, s.max_us, r.field_edit_servo_takeovers,
          r.field_edit_worker_waits, 1e-6 * static_cast<double>(r.field_edit_stand_in_ns));
    }
  }
  for (const QuietPhase& p : quiet.phases) {
    std::printf(
        "  quiet %s (%s, %.2f-%.2f s): ripple %.1f %% contact, %.1f %% device; in contact %.1f %% "
        "of ticks, %d losses; oscillation %.1f quanta; static stiffness %.0f N/m; motors %.3g J: "
        "%s\n",
        p.phase.c_str(), p.kind.c_str(), p.steady_from_s, p.t_end_s,
        100.0 * p.ripple_contact_force.value_or(0.0), 100.0 * p.ripple_device_force.value_or(0.0),
        100.0 * p.contact_fraction, p.contact_losses, p.oscillation_amplitude_quanta,
        p.static_stiffness_n_per_m.value_or(0.0), p.motor_energy_j,
        p.quiet ? "quiet" : "NOT quiet");
  }
  std::printf(
      "  free space: force felt %.3f N RMS moving (%ld ticks), %.3f N RMS still (%ld ticks), "
      "%ld pulses > %.2f N while still\n",
      quiet.free_space.moving_force_rms_n, quiet.free_space.moving_ticks,
      quiet.free_space.still_force_rms_n, quiet.free_space.still_ticks,
      quiet.free_space.still_pulses, quiet.bounds.pulse_threshold_n);
  std::printf("  faults: %s\n", r.faults.empty() ? "none" : r.faults.front().c_str());
  std::printf(
      "  outputs in %s/: report.json timeseries.csv force_penetration.png observer.png quiet.png "
      "tooth_before.png tooth_after.png%s\n",
      o.out.c_str(), r.drill_log.empty() ? "" : " drill_depth.png");
}

void setup_run(CLI::App& app) {
  auto o = std::make_shared<RunCliOptions>();
  std::string names;  // the built-in scenes, from the one list (--help never goes stale)
  for (const std::string& n : builtin_scene_names()) names += (names.empty() ? "" : ", ") + n;
  CLI::App* sub = app.add_subcommand(
      "run", "Run the dental simulator on a scene (built-in: " + names + "; or a scene file)");
  sub->add_option("scene", o->scene, "Built-in scene name or scene file (JSON, docs/scenes.md)");
  sub->add_option("--out", o->out, "Output directory")->capture_default_str();
  sub->add_flag("--realtime", o->realtime,
                "Pace the loop at the tick rate on absolute deadlines, at SCHED_FIFO with locked "
                "memory where permitted (a warning where not); overruns are counted and skipped, "
                "timing statistics go to report.json `realtime` (default: as fast as possible)");
  sub->add_option("--duration", o->duration, "Override the scene's duration [s] (0 = the scene's)")
      ->check(finite_range(0.0, 3600.0));
  sub->add_option("--tick-hz", o->tick_hz,
                  "Run the scene at this servo rate [Hz] instead of its tick_hz (100-20000)")
      ->check(finite_range(100.0, 20000.0));
  sub->add_option("--log-every", o->log_every, "Keep every n-th tick in the time series")
      ->capture_default_str();
  sub->add_option("--pipeline", o->pipeline, "The tick's implementation: " + stage_table_names())
      ->capture_default_str();
  sub->add_flag("--no-skip", o->no_skip,
                "Run every stage the scene does not need (observer without a gain, grip detector "
                "without a hand mass, decomposition, friction at mu = 0, drilling, the tooth's "
                "free-space early out) and discard what the method does not use: the same run, "
                "slower (report.json skip_unneeded; fast pipeline)");
  sub->add_option("--inject-fault", o->inject_fault,
                  "Inject a device fault, KIND@T (T [s]): nan-sample, inf-sample, encoder-jump, "
                  "frozen, clock-backwards, device-loss end in a named fault with zero torque and "
                  "the report written; late-tick (one sample 5 periods late) is ridden through "
                  "(device/fault_injection.h)");
  sub->add_option(
         "--device", o->device,
         "The device: simulated-phantom (the embedded default) or hdapi (a Phantom through "
         "OpenHaptics, or the project's emulator; docs/hardware.md); default: the "
         "scene's device.type")
      ->check(CLI::IsMember(device_backend_names()));
  sub->add_option("--hd-library", o->hd_library,
                  "With --device hdapi: the HDAPI library to load (default: DENTSIM_HD_LIBRARY, "
                  "then libHD.so, libHD.so.3.0, ...)");
  sub->add_option("--hd-loop", o->hd_loop,
                  "With --device hdapi, where the tick runs: callback (inside the vendor's "
                  "scheduler callback, every scheduler tick) or caller (this thread through "
                  "read/write/advance, every second scheduler tick; needed for --inject-fault, "
                  "--view, --realtime)")
      ->check(CLI::IsMember({"callback", "caller"}))
      ->capture_default_str();
  sub->add_option("--record", o->record,
                  "Record every tick's device sample, command and contact count to FILE (a "
                  "session for `dentsim replay`; kept up to a fault)");
  sub->add_option("--tick-times", o->tick_times,
                  "Write one CSV row per tick to FILE: the stages' and the device simulation's "
                  "times [us], contacts, voxels removed, and the loop thread's page faults and "
                  "context switches over the tick (diagnosis of the tick's tail)");
  sub->add_flag("--force", o->force,
                "Run a scene that its method's stability conditions refuse (an experiment; the "
                "supervisor still ends a diverging run in a named fault, sim/scene_stability.h)");
  sub->add_flag("--list", o->list, "List the built-in scenes");
  sub->add_flag("--view", o->view.view,
                "Show the simulation live in a 3-D window, paced at real time (docs/view.md)");
  sub->add_flag("--view-close", o->view.close, "Close the window when the run ends");
  sub->add_option("--view-shots", o->view.shots_dir,
                  "With --view: write DIR/first.png and DIR/last.png of the window, then close it");
  sub->add_flag("--show", o->show,
                "Print the scene file (e.g. to start a new scene from a built-in one)");
  sub->callback([o] { run(*o); });
}
DENTSIM_REGISTER_COMMAND(setup_run);

}  // namespace
}  // namespace dentsim::cli
