#include "sim/run_report.h"

#include <array>

#include "reference/core/params.h"
#include "reference/tooth/materials.h"

namespace dentsim {

nlohmann::json run_report_json(const Scene& scene, const RunResult& r) {
  nlohmann::json j;
  j["scene"] = scene.name;
  j["scene_origin"] = scene.origin;
  j["method"] = method_name(scene.method.method);
  j["device_model"] = r.device_model;
  j["pipeline"] = r.pipeline;
  // Stopped early (RunOptions::stop, e.g. Ctrl-C): the figures cover the ticks that ran; the
  // command adds its reason (cli/cmd_run.cc).
  j["partial"] = r.stopped;
  j["skip_unneeded"] = r.skip_unneeded;
  j["tick_hz"] = scene.tick_hz;
  j["simulated_s"] = r.simulated_s;
  j["wall_s"] = r.wall_s;
  j["setup_s"] = r.setup_s;
  j["ticks"] = r.ticks;
  j["contact_ticks"] = r.contact_ticks;
  j["max_contact_force_n"] = r.max_contact_force_n;
  j["rms_contact_force_n"] = r.rms_contact_force_n;
  j["max_penetration_m"] = r.max_penetration_m;
  j["rendered_stiffness_n_per_m"] = r.rendered_stiffness_n_per_m;
  j["virtual_energy_generated_j"] = r.virtual_energy_generated_j;
  j["virtual_contact_work_j"] = r.virtual_contact_work_j;
  j["late_ticks"] = r.late_ticks;
  j["max_tick_s"] = r.max_tick_s;
  j["device"] = r.device;
  if (!r.hd_loop.empty()) {
    j["hd_loop"] = r.hd_loop;
    j["callback_dropped_ticks"] = r.callback_dropped_ticks;
  }
  j["hand_work_j"] = r.has_ground_truth ? nlohmann::json(r.hand_work_j) : nlohmann::json(nullptr);
  j["hand_work_min_j"] =
      r.has_ground_truth ? nlohmann::json(r.hand_work_min_j) : nlohmann::json(nullptr);
  // Passive toward the hand: it never got back more energy than it put in (tolerance: 1 uJ).
  // Unknown (null) on a real device: the hand's force is not measured.
  j["passive_at_hand"] =
      r.has_ground_truth ? nlohmann::json(r.hand_work_min_j >= -1e-6) : nlohmann::json(nullptr);
  j["passive_at_motors"] = r.virtual_energy_generated_j <= 0.0;
  j["observer_rms_error_n"] =
      r.has_ground_truth ? nlohmann::json(r.observer_rms_error_n) : nlohmann::json(nullptr);
  nlohmann::json rv;
  for (int m = 1; m < kMaterialCount; ++m)
    rv[material_properties(m).name] = r.removed_volume_mm3[m];
  rv["total"] = r.removed_volume_total_mm3;
  j["removed_volume_mm3"] = rv;
  j["pulp_exposed_at_s"] =
      r.pulp_exposed_at_s ? nlohmann::json(*r.pulp_exposed_at_s) : nlohmann::json(nullptr);
  j["field_edit_late_publishes"] = r.field_edit_late_publishes;
  j["field_edit_servo_takeovers"] = r.field_edit_servo_takeovers;
  j["field_edit_worker_waits"] = r.field_edit_worker_waits;
  j["field_edit_worker_wakes"] = r.field_edit_worker_wakes;
  nlohmann::json tj;
  for (const auto& [name, s] : r.timing) {
    tj[name] = {{"median", s.median_us}, {"p99", s.p99_us}, {"max", s.max_us}};
  }
  j["timing_us"] = tj;
  j["faults"] = r.faults;
  if (r.realtime) {
    const ServoTimingStats& s = *r.realtime;
    j["realtime"] = {
        {"ticks", s.ticks},
        {"overruns", s.overruns},
        {"skipped_deadlines", s.skipped_deadlines},
        {"period_us",
         {{"median", s.period_median_us}, {"p99", s.period_p99_us}, {"max", s.period_max_us}}},
        {"exec_us",
         {{"median", s.exec_median_us},
          {"p99", s.exec_p99_us},
          {"max", s.exec_max_us},
          {"mean", s.exec_mean_us}}},
        {"sched_fifo", s.sched_fifo},
        {"memory_locked", s.memory_locked},
        {"warning", s.warning}};
  }
  if (r.recorded_ticks > 0 || r.record_dropped_ticks > 0) {
    j["recorded_ticks"] = r.recorded_ticks;
    j["record_dropped_ticks"] = r.record_dropped_ticks;
  }
  if (!r.faults.empty()) j["torque_after_fault_n_m"] = r.torque_after_fault_n_m;
  j["quiet"] = quiet_report_json(run_quiet_report(scene, r));
  return j;
}

QuietReport run_quiet_report(const Scene& scene, const RunResult& r, const QuietBounds& bounds) {
  std::vector<QuietScriptKey> keys;
  keys.reserve(scene.script.size());
  for (const SceneHandKey& k : scene.script) keys.push_back({k.t, k.offset, k.force, k.phase});
  return quiet_report(r.quiet_series, keys, bounds, r.tip_quantum_m);
}

nlohmann::json quiet_report_json(const QuietReport& q) {
  // A figure that was not measured (no steady stretch long enough for a ripple, no penetration
  // for a stiffness, no still stretch for a power) is left out, never written as null (issue #32:
  // no report holds null for a measured figure).
  auto put = [](nlohmann::json& o, const char* key, const std::optional<double>& v) {
    if (v) o[key] = *v;
  };
  const QuietBounds& b = q.bounds;
  nlohmann::json j;
  j["bounds"] = {{"ripple_max", b.ripple_max},
                 {"contact_fraction_min", b.contact_fraction_min},
                 {"contact_losses_max", b.contact_losses_max},
                 {"ripple_window_s", b.window_s},
                 {"settle_s", b.settle_s},
                 {"min_steady_s", b.min_steady_s},
                 {"pulse_threshold_n", b.pulse_threshold_n},
                 {"still_settle_s", b.still_settle_s}};
  j["tip_quantum_m"] = q.tip_quantum_m;
  nlohmann::json phases = nlohmann::json::array();
  for (const QuietPhase& p : q.phases) {
    nlohmann::json ph = {{"phase", p.phase},
                      {"kind", p.kind},
                      {"t_begin_s", p.t_begin_s},
                      {"t_end_s", p.t_end_s},
                      {"steady_from_s", p.steady_from_s},
                      {"ticks", p.ticks},
                      {"contact_fraction", p.contact_fraction},
                      {"contact_losses", p.contact_losses},
                      {"oscillation_amplitude_m", p.oscillation_amplitude_m},
                      {"oscillation_amplitude_quanta", p.oscillation_amplitude_quanta},
                      {"mean_contact_force_n", p.mean_contact_force_n},
                      {"mean_device_force_n", p.mean_device_force_n},
                      {"mean_device_penetration_m", p.mean_penetration_m},
                      {"motor_energy_j", p.motor_energy_j},
                      {"quiet", p.quiet}};
    put(ph, "ripple_contact_force", p.ripple_contact_force);
    put(ph, "ripple_device_force", p.ripple_device_force);
    put(ph, "static_stiffness_n_per_m", p.static_stiffness_n_per_m);
    put(ph, "observer_rms_error_n", p.observer_rms_error_n);
    phases.push_back(ph);
  }
  j["phases"] = phases;
  const QuietFreeSpace& f = q.free_space;
  j["free_space"] = {
      {"moving_ticks", f.moving_ticks},
      {"moving_force_rms_n", f.moving_force_rms_n},
      {"still_ticks", f.still_ticks},
      {"still_force_rms_n", f.still_force_rms_n},
      {"still_pulses", f.still_pulses},
      {"still_pulse_rate_per_s", f.still_pulse_rate_per_s},
      {"still_motor_energy_j", f.still_motor_energy_j}};
  if (f.still_s > 0.0) j["free_space"]["still_motor_power_w"] = f.still_motor_energy_j / f.still_s;
  put(j["free_space"], "moving_observer_rms_error_n", f.moving_observer_rms_error_n);
  put(j["free_space"], "still_observer_rms_error_n", f.still_observer_rms_error_n);
  put(j["free_space"], "still_true_motor_energy_j", f.still_true_motor_energy_j);
  // No steady press or slide phase: no verdict (the key is left out).
  if (q.quiet) j["quiet"] = *q.quiet;
  return j;
}

namespace {

// clang-format off
constexpr std::array<RunSeriesColumn, 27> kColumns = {{
    {"t_s",                  [](const RunSample& x) { return x.t; }},
    {"phase",                nullptr},
    {"contacts",             [](const RunSample& x) { return static_cast<double>(x.contacts); }},
    {"contact_force_n",      [](const RunSample& x) { return x.contact_force_n; }},
    {"device_force_n",       [](const RunSample& x) { return x.device_force_n; }},
    {"penetration_m",        [](const RunSample& x) { return x.penetration_m; }},
    {"device_penetration_m", [](const RunSample& x) { return x.device_penetration_m; }},
    {"proxy_x_m",            [](const RunSample& x) { return x.proxy_x.x(); }},
    {"proxy_y_m",            [](const RunSample& x) { return x.proxy_x.y(); }},
    {"proxy_z_m",            [](const RunSample& x) { return x.proxy_x.z(); }},
    {"device_x_m",           [](const RunSample& x) { return x.device_x.x(); }},
    {"device_y_m",           [](const RunSample& x) { return x.device_x.y(); }},
    {"device_z_m",           [](const RunSample& x) { return x.device_x.z(); }},
    {"proxy_rx_rad",         [](const RunSample& x) { return x.proxy_rotvec.x(); }},
    {"proxy_ry_rad",         [](const RunSample& x) { return x.proxy_rotvec.y(); }},
    {"proxy_rz_rad",         [](const RunSample& x) { return x.proxy_rotvec.z(); }},
    {"device_rx_rad",        [](const RunSample& x) { return x.device_rotvec.x(); }},
    {"device_ry_rad",        [](const RunSample& x) { return x.device_rotvec.y(); }},
    {"device_rz_rad",        [](const RunSample& x) { return x.device_rotvec.z(); }},
    {"hand_fx_n",            [](const RunSample& x) { return x.hand_force_n.x(); }},
    {"hand_fy_n",            [](const RunSample& x) { return x.hand_force_n.y(); }},
    {"hand_fz_n",            [](const RunSample& x) { return x.hand_force_n.z(); }},
    {"observer_fx_n",        [](const RunSample& x) { return x.observer_force_n.x(); }},
    {"observer_fy_n",        [](const RunSample& x) { return x.observer_force_n.y(); }},
    {"observer_fz_n",        [](const RunSample& x) { return x.observer_force_n.z(); }},
    {"energy_virtual_j",     [](const RunSample& x) { return x.energy_virtual_j; }},
    {"hand_work_j",          [](const RunSample& x) { return x.hand_work_j; }},
}};
// clang-format on

}  // namespace

std::span<const RunSeriesColumn> run_series_columns() { return kColumns; }

}  // namespace dentsim
