#include "device/run_report.h"

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
  j["skip_unneeded"] = r.skip_unneeded;
  j["tick_hz"] = scene.tick_hz;
  j["simulated_s"] = r.simulated_s;
  j["wall_s"] = r.wall_s;
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
