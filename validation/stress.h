// Randomised whole-loop stress (issue #18): the full simulator — simulated Phantom, scripted
// hand, voxel tooth with drilling, the loop owner and its safety chain — run over many random
// configurations: gains over and beyond the Z-width grid (K_vc 100-8000 N/m, b_vc 0-12 N s/m,
// K_tooth 1000-40000 N/m), every method, both pipelines (fast/registry.h), tick rates 500-2000 Hz
// with jitter up to 40 % of half a tick, random hand scripts (pushes up to 5 N, paths of a few
// mm), probe or drill, tooth resolution 64 or 128. Each configuration is a patch of a built-in
// scene, so it passes the scene's own validation (a configuration the scene rejects is drawn
// again and counted).
//
// Invariants checked on every tick:
//   finite      the tick's outputs (tau, T1, the proxy's pose) are finite, or the tick's status
//               is a named fault (a safe stop is an allowed outcome, a NaN sent is not)
//   torque      the torque applied by the device is within its limit on every joint
//   zero after  once the loop has latched a fault, the torque applied is exactly zero
//   time        the device clock advances every tick (no stuck state) until the run ends
//   outside     with the surface-proxy contact (tooth.contact_model sdf) and a tool that does not
//               drill (probe), the rendered tip's centre g = x_o + rho n stays at least rho - s
//               from the solid (phi(g) >= rho - s, s = min(rho/4, h/2); reference/tooth/sdf.h):
//               no pop-through, whatever the gains, the rate or the push
//   bounded     under PMI (pmi, pmi-pd) the proxy never leaves the workspace (1 m from the
//               device): PMI's discrete energy balance bounds the proxy's energy by the work put
//               in; explicit Euler beyond its Z-width may explode (counted, the device stays
//               saturated and safe)
// Worst cases are reported: largest |tau_i| / tau_max_i, largest contact force and depth / rho
// (over runs whose proxy stayed bounded), faults by name, explosions by method.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace dentsim {

struct StressConfig {
  long ticks = 100000;        // in total over all runs
  long ticks_per_run = 2000;  // each configuration runs this many ticks (or until a fault)
  std::uint64_t seed = 1;
  // Only runs of this method and scene ("pmi", "drill"; empty: every one). The others are still
  // drawn, so the runs kept are exactly the unfiltered form's with the same seed and run index,
  // and count ticks_per_run each toward `ticks` without running: a filtered form covers the same
  // stretch of the draw as the unfiltered one (issue #32: the 10^7 form's PMI drilling runs).
  std::string only_method, only_scene;
  // Runs before this index are drawn and skipped alike (a later stretch of the same draw).
  long first_run = 0;
  // A JSON merge patch (RFC 7386) applied to every drawn patch after the draw (empty: none), e.g.
  // {"method": {"saturation_passive": false}}: the same draw under a variant of the simulator.
  std::string variant_patch;
};

// A run that ended in a named fault (issue #32): its configuration, what stopped it, and the
// state around the fault, so that a fault can be judged (physical: the hand pushing the device
// through a saturated rendering; numerical: a proxy diverging against a still device) and
// replayed as a scene file: the built-in scene `scene` (`dentsim run SCENE --show`) with `patch`
// merged (RFC 7386), run with `--pipeline PIPELINE`.
struct StressFaultedRun {
  long run = 0;  // the run index of the draw
  std::string method, scene, pipeline;
  double tick_hz = 0.0;
  double k_tooth = 0.0, b_tooth = 0.0;  // [N/m], [N s/m]
  double k_vc = 0.0, b_vc = 0.0;        // linear coupling [N/m], [N s/m]
  double proxy_mass_kg = 0.0, friction_mu = 0.0, jitter_us = 0.0;
  int resolution = 0;
  std::string fault;   // its name (ClosedLoop::fault_name)
  double t_s = 0.0;    // the device time it was raised at [s]
  long tick = 0;       // the run's tick it was raised on
  std::string detail;  // the figure against its bound (the supervisor's faults; else empty)
  // At the fault tick: |f| of the contact and the coupling force on the proxy [N], the deepest
  // contact [m]; the device's ticks saturated in a row just before it; how many of the last 20
  // ticks reversed the proxy's linear velocity (V_hat_k . V_hat_k-1 < 0: a proxy ringing tick
  // by tick is the signature of a numerical divergence).
  double contact_n = 0.0, coupling_n = 0.0, depth_m = 0.0;
  long saturated_run = 0;
  int reversals_last20 = 0;
  std::string patch;  // the drawn patch of the built-in scene (JSON)
};

struct StressResult {
  long runs = 0, ticks = 0;
  long rejected_configs = 0;           // drawn configurations the scene's validation refused
  long skipped_runs = 0;               // drawn runs the filter (only_method, only_scene) left out
  long violations = 0;                 // ticks that broke an invariant (must be 0)
  std::string first_violation;         // what and where (run, seed, tick), for the message
  std::map<std::string, long> faults;  // runs that ended in each named fault
  double worst_torque_ratio = 0.0;     // max |tau_i| / tau_max_i
  double worst_contact_force_n = 0.0;  // max |f| on the proxy
  double worst_depth_over_radius = 0.0;
  long surface_checks = 0;                 // ticks the `outside` invariant was checked on
  double min_clearance_over_radius = 1.0;  // min (phi(g) - rho) / rho over them (>= -s / rho)
  // Per method: the deepest contact / rho over runs whose proxy stayed bounded, and the run that
  // reached it (scene, pipeline, the scene patch), so a deep contact can be replayed and isolated.
  std::map<std::string, double> worst_depth_by_method;
  std::map<std::string, std::string> worst_depth_run;
  // Runs whose proxy left the workspace (more than 1 m from the device: a numerically exploded
  // virtual side, the device saturated and safe), by method. PMI's energy bound forbids it under
  // pmi and pmi-pd; explicit Euler beyond its Z-width is expected to.
  std::map<std::string, long> exploded;
  std::map<std::string, long> runs_by_method;
  std::vector<StressFaultedRun> faulted_runs;  // every run that ended in a named fault, in order
};

// `progress` is called after every run with the result so far (runs, ticks, faults).
StressResult run_stress(
    const StressConfig& config,
    const std::function<void(const StressResult& so_far, long total)>& progress = {});

// One line per faulted run: index, method, scene, pipeline, rate, the drawn gains, the fault,
// when, its figure against its bound, and the state at the fault (StressFaultedRun).
std::string describe_faulted_run(const StressFaultedRun& run);

}  // namespace dentsim
