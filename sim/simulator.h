// The simulator: runs a scene (sim/scene.h) end to end on the embedded default — the
// MuJoCo-simulated Phantom held by the scripted hand, the voxel tooth, the reference pipeline —
// and measures what the report of `dentsim run` needs (issue #6; docs/scenes.md).
//
// Per tick: ClosedLoop::step (read -> tick -> write -> advance, device/closed_loop.h), then
// drilling on the tick's contact set when the tool drills, then the measurements below.
// Nothing here writes files: cli/cmd_run.cc turns a RunResult into report.json, the time series,
// the plots and the tooth pictures.
//
// Measurements:
// - contact force: the penalty + friction force on the proxy, |f| of TickResult::F_contact [N];
// - penetration: the deepest contact of the proxy's tip [m];
// - rendered stiffness: the least-squares slope through the origin of the force fed back to the
//   device (|f| of T1) against the device tip's own penetration of the tooth (the tip sphere at
//   the device pose, same collision code), over ticks where that penetration exceeds the tip's
//   encoder resolution (0.03 mm) [N/m];
// - E_v: the passivity observer of the motor port (ClosedLoop): the energy the motors put into
//   the device beyond gravity compensation. <= 0 means the rendering never powered the device.
//   With passive decomposition (pmi-pd) E_v may be positive by design: the feed-forward supplies
//   the energy the device's own damping dissipates, so the hand feels the desired tool, not the
//   device's damping (thesis §3.1). The passivity that matters to the user is then at the hand:
// - W_h: the passivity observer of the hand port, W_h(t) = ∫ F_h^T v dt (the work the hand did
//   on the device, from the simulator's true hand torques and joint motion). The rendering is
//   passive toward the hand when W_h(t) >= 0 at all times: it never gave back more energy than
//   the hand put in (Hannaford & Ryu's time-domain passivity observer, applied at the handle);
// - timing: wall-clock time of every tick stage, of the whole servo tick (the pipeline's stages
//   + drilling), of the servo's own tick (the whole less what the field model's publish did in
//   its edit worker's stead: takeovers and waits, which only a simulated run has) and, apart, of
//   the simulated device's physics per tick [us];
// - faults: the device's latched faults (a fault stops the run: the device is in safe stop).
#pragma once

#include <array>
#include <atomic>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "device/closed_loop.h"
#include "device/fault_injection.h"
#include "sim/quiet_measures.h"
#include "sim/scene.h"
#include "device/scripted_hand.h"
#include "device/servo_pacer.h"
#include "device/simulated_phantom.h"
#include "sim/tick_observer.h"
#include "reference/grasp_mass_model.h"
#include "reference/phantom/phantom_model.h"
#include "reference/tick.h"
#include "reference/tooth/tooth_contacts.h"
#include "reference/tooth/voxel_grid.h"
#include "reference/tooth/voxel_runs.h"

namespace dentsim {

struct SceneRig;  // below

struct RunOptions {
  std::string pipeline = "reference";  // the tick's implementation (fast/registry.h)
  std::string device;                  // SceneRigOptions::device
  std::string hd_library;              // SceneRigOptions::hd_library
  // With an hdapi device, where the tick runs: "callback" (the default: inside the vendor's
  // scheduler callback, once per scheduler tick; device/callback_loop.h) or "caller" (this
  // thread, through read/write/advance: one loop tick per two scheduler ticks). The caller form
  // is needed for --inject-fault, the view and --realtime, which wrap or pace that thread.
  std::string hd_loop = "callback";
  InjectedFault fault;    // a device fault to inject (device/fault_injection.h)
  bool realtime = false;  // pace the loop at the tick rate (device/servo_pacer.h)
  // With realtime: ask for SCHED_FIFO and locked memory (a warning where refused).
  bool realtime_priority = false;
  double duration_override = 0.0;  // > 0: run this long instead of the scene's duration [s]
  int log_every = 1;               // keep every n-th tick in the time series
  // The fast pipeline's device terms in float (fast::PhantomModelFloat): a point on the
  // time-against-error curve (`dentsim bench`), never a default. Fast pipeline only.
  bool float_device_terms = false;
  // Skip what the scene does not need (PipelineModel::skip_unneeded; `dentsim run --no-skip`
  // turns every skip off: the same run, slower, for checking the skips).
  bool skip_unneeded = true;
  // Non-empty: record every tick's device sample, command and contact count to this file
  // (sim/session_record.h; the context holds the scene's JSON and the pipeline, so that
  // `dentsim replay` can rebuild the environment). The file is complete up to a fault.
  std::string record_path;
  // Non-empty: write one CSV row per tick to this file after the run (the tick's tail, issue #30):
  // the stages' times, the tick's and the device simulation's [us], the tick's contacts and
  // removed voxels, and the loop thread's minor page faults and voluntary / involuntary context
  // switches over the tick's loop step (getrusage, read outside the timed step). The simulated
  // device's own loop only (not with an hdapi scheduler callback).
  std::string tick_times_path;
  // Called every ~1 % of the run with the fraction done (progress bar).
  std::function<void(double)> progress;
  // Called once per tick at the end of the loop body, on the loop's thread (sim/tick_observer.h;
  // the live view). Not owned; null: none.
  TickObserver* observer = nullptr;  // Set (by a signal handler, cli/interrupt.h, or the view's
                                     // window): the loop owner stops at the
  // next tick boundary and returns what it measured, RunResult::stopped true. Not owned; null:
  // none.
  const std::atomic<bool>* stop = nullptr;
  // Tests: called once with the rig built, before the first tick (e.g. to hold the field edit's
  // worker, fast/tooth/field.h FieldEditWorker::hold). Null: none.
  std::function<void(SceneRig&)> prepare_rig;
};

// One row of the time series.
struct RunSample {
  double t;
  double contact_force_n;       // |f| on the proxy
  double device_force_n;        // |f| of T1 (fed back to the device)
  Vec3 device_force;            // f of T1, world [N]
  double penetration_m;         // proxy tip
  double device_penetration_m;  // device tip
  Vec3 proxy_x, device_x;
  Vec3 proxy_rotvec, device_rotvec;  // orientations as rotation vectors log(R) [rad]
  Vec3 hand_force_n;                 // true hand force (simulator ground truth), world
  Vec3 observer_force_n;             // observer estimate F1_hat (force part), world
  int contacts;
  double energy_virtual_j;
  double hand_work_j;
  std::string phase;
};

struct StageStats {
  double median_us = 0.0, p99_us = 0.0, max_us = 0.0, mean_us = 0.0;
};

struct RunResult {
  std::string scene;
  long ticks = 0;
  long contact_ticks = 0;
  double max_contact_force_n = 0.0;
  double rms_contact_force_n = 0.0;  // over contact ticks
  double max_penetration_m = 0.0;
  double rendered_stiffness_n_per_m = 0.0;
  double virtual_energy_generated_j = 0.0;
  // The supervisor (device/virtual_supervisor.h): the contact's work on the proxy W_c [J] (<= 0:
  // passive), the ticks longer than 1.5 nominal periods (ridden through) and the longest [s].
  double virtual_contact_work_j = 0.0;
  long late_ticks = 0;
  double max_tick_s = 0.0;
  double hand_work_j = 0.0;                                 // W_h at the end
  double hand_work_min_j = 0.0;                             // min over the run of W_h(t) (<= 0)
  std::array<double, kMaterialCount> removed_volume_mm3{};  // per Material id (0 unused)
  double removed_volume_total_mm3 = 0.0;
  // Scene time at the end of the tick whose drilling first opened the pulp (nominal ticks of
  // 1/tick_hz); empty if it never did.
  std::optional<double> pulp_exposed_at_s;
  // Contact model "field", fast pipeline: field edits published after their tick t + L (a
  // real-time loop whose edit worker was late; 0 in simulation). report.json
  // field_edit_late_publishes.
  long field_edit_late_publishes = 0;
  // Contact model "field", fast pipeline, simulation: field edits the servo did itself at their
  // tick t + L because the worker had not started them (docs/derivations/field_contact.md §8).
  // report.json field_edit_servo_takeovers.
  long field_edit_servo_takeovers = 0;
  // The same, simulation: field edits the servo waited for at their tick t + L because the worker
  // was editing them. report.json field_edit_worker_waits.
  long field_edit_worker_waits = 0;
  // The same, fast pipeline: hand-overs of a cut that found the edit worker asleep and woke it
  // (a futex wake in the servo's drill stage; thread scheduling decides it). report.json
  // field_edit_worker_wakes.
  long field_edit_worker_wakes = 0;
  // The servo tick's wall time summed over the run [ns]: all of it (report.json timing_us "tick")
  // and the servo's own (timing_us "servo_tick": without the field edit's takeovers and waits,
  // work the worker does in real time); their difference is field_edit_stand_in_ns, the
  // provider's clock on those two paths (timing_us "field_edit_stand_in" per tick; 0 in real time,
  // for the reference pipeline and for the other contact models: servo_tick is then tick).
  long tick_ns_total = 0, servo_tick_ns_total = 0, field_edit_stand_in_ns = 0;
  std::vector<DrillRecord> drill_log;  // every drilling tick (reference/tooth/tooth_contacts.h)
  double tick_s = 0.0;                 // nominal tick 1/tick_hz [s]
  // The stages, "tick", "device_simulation", "servo_tick" and "field_edit_stand_in" (above).
  std::vector<std::pair<std::string, StageStats>> timing;
  std::vector<std::string> faults;
  double observer_rms_error_n = 0.0;  // |F1_hat - F_hand| (force part), RMS over the run
  double simulated_s = 0.0;
  double wall_s = 0.0;   // the loop's wall time [s] (from the first tick to the last)
  // Wall time of the setup before the first tick [s]: the scene rig (the tooth's voxelisation and
  // structures, the device, the pipeline) and the run's measurements (issue #30's setup target).
  double setup_s = 0.0;
  std::vector<RunSample> series;
  std::string hd_loop;                  // hdapi: "callback" or "caller" (empty for a simulated run)
  long callback_dropped_ticks = 0;      // hdapi callback loop: records the full ring dropped
  // The tooth before the first tick and after the last, for pictures: as runs (reference/tooth/
  // voxel_runs.h; unpack() gives the grid), not two more N^3 grids beside the run's own (#30).
  VoxelRuns tooth_before, tooth_after;
  // The tooth's sampled field before the first tick and after the last (contact model "field",
  // as drilling edited it); null for the other models. For pictures (view/pictures.h).
  std::shared_ptr<const SampledField> field_before, field_after;
  std::string device_model;             // which device model file
  std::string pipeline;                 // the tick's implementation that ran
  bool skip_unneeded = true;            // RunOptions::skip_unneeded
  std::string device;                   // the backend that ran ("simulated-phantom", "hdapi")
  // false on a device without the simulator's ground truth (hdapi): the hand's work, the
  // passivity at the hand and the observer's error against the true hand force are not known.
  bool has_ground_truth = true;
  double torque_after_fault_n_m = 0.0;       // |tau| applied over the faulting tick (0 expected)
  std::optional<ServoTimingStats> realtime;  // --realtime: period and execution-time statistics
  long recorded_ticks = 0;                   // ticks written to RunOptions::record_path
  long record_dropped_ticks = 0;             // ticks the recorder's ring had no room for
  // Every tick's signals for the quiet measures (sim/quiet_measures.h; the report's `quiet`
  // block), whatever RunOptions::log_every, and the device tip's encoder quantum: the largest,
  // over the world axes a, of sum_i |J_t(a, i)| 2 pi / counts_i at home (one count on every joint).
  QuietSeries quiet_series;
  double tip_quantum_m = 0.0;
  // RunOptions::stop was set: the run ended early at a tick boundary (simulated_s says where);
  // everything above covers the ticks that ran.
  bool stopped = false;
};

// Everything a scene runs on, built once: the simulated Phantom (behind a fault injector when
// asked), the placed voxel tooth and its contact provider, the scripted hand, the pipeline and
// the loop owner. run_scene drives it; tests drive it tick by tick (the allocation test).
struct SceneRigOptions {
  // The device the loop drives: "" = the scene's device.type; "simulated-phantom" (the embedded
  // default) or "hdapi" (device/hdapi/hdapi_device.h: a Phantom through OpenHaptics, or any library
  // exporting HDAPI, such as the project's emulator). With hdapi the simulated Phantom is still
  // built (the placement of the tooth, the scripted hand's geometry) but not stepped.
  std::string device;
  std::string hd_library;  // --hd-library ("" = DENTSIM_HD_LIBRARY, then the usual sonames)
  std::string pipeline = "reference";
  InjectedFault fault;
  bool float_device_terms = false;  // RunOptions::float_device_terms
  bool skip_unneeded = true;        // RunOptions::skip_unneeded
  // The loop is paced by a clock (RunOptions::realtime; an hdapi device is real time anyway):
  // the field edit's worker is never waited for (PipelineToothSetup::real_time).
  bool realtime = false;
  // Adjusts the pipeline's configuration after the scene has set it (tests and benchmarks:
  // variants no scene file expresses, e.g. a method without an observer). Null: none.
  std::function<void(PipelineConfig&)> configure_pipeline;
};

struct SceneRig {
  double tick = 1e-3;  // nominal T [s]
  PhantomParams params;
  std::unique_ptr<PhantomModel> model;            // the reference model (plant, placement)
  // The pipeline implementation's evaluation of the model file (fast/registry.h).
  std::unique_ptr<SixDofDeviceModel> pipeline_model;
  VecX q_home;
  Pose home;
  Vec3 anchor = Vec3::Zero();  // the tooth's occlusal anchor (world)
  std::unique_ptr<SimulatedPhantom> device;
  std::unique_ptr<FaultInjectingDevice> faulty;  // set when a fault is injected
  std::unique_ptr<Device> backend;               // the hdapi device, when it drives the loop
  Device* loop_device = nullptr;                 // what the loop drives (device, backend, faulty)
  VoxelRuns tooth_before;  // the placed tooth before the first tick (unpack() for the grid)
  std::unique_ptr<VoxelTooth> tooth;        // the reference tooth (drilled by "reference")
  std::unique_ptr<SampledField> field;  // the tooth's field (contact model "field"), else null
  // The pipeline implementation's tooth over `tooth` (fast/registry.h): what its stages query
  // and drill (for the fast face model its own brick tooth, built from `tooth`).
  std::unique_ptr<PipelineTooth> pipeline_tooth;
  ToolTip tip;
  double k_tooth = 0.0, b_tooth = 0.0;
  ToothProviderBase* contacts = nullptr;  // pipeline_tooth's provider
  // The same provider as a ToothContactProvider (the surface proxy and field models, both
  // pipelines), else null: resolved once at setup.
  ToothContactProvider* tooth_provider = nullptr;
  std::unique_ptr<ScriptedHand> hand;
  std::unique_ptr<GraspMassModel> grasp;
  std::unique_ptr<Pipeline> pipeline;
  // The loop owner's safety chain (device/safety_chain.h): fault thresholds and the sample's
  // guards (clock, encoder jumps, velocity); no rate limit, ramp or watchdog in simulation, and a
  // saturation equal to the pipeline's own, so a healthy run's torques are unchanged.
  std::unique_ptr<SafetyChain> safety;
  // The supervisor of the virtual side (device/virtual_supervisor.h): the tool's radius from the
  // scene, every other limit its default.
  std::unique_ptr<VirtualSupervisor> supervisor;
  std::unique_ptr<ClosedLoop> loop;

  // The grid of the tooth the pipeline drills, and the contact set of the tool tip at `pose` on
  // it (for measurements outside the tick; same code as the pipeline's collision stage).
  const VoxelGrid& tooth_grid() const;
  void tip_contacts(const Pose& pose, std::vector<Contact>* out);
  // The deepest contact of the tool tip at `pose` [m] (0 when none): the device tip's own
  // penetration, for the rendered stiffness. Uses measure_contacts (reserved once: no allocation
  // when warm, so it may run in the vendor's callback).
  double tip_depth(const Pose& pose);
  std::vector<Contact> measure_contacts;
};

// Builds the rig of a scene. Throws InputError for a bad scene input (e.g. an unreadable mesh)
// or an unknown pipeline.
std::unique_ptr<SceneRig> build_scene_rig(const Scene& scene, const SceneRigOptions& options = {});

// Runs the scene. Throws InputError for a bad scene input (e.g. an unreadable mesh).
RunResult run_scene(const Scene& scene, const RunOptions& options = {});

}  // namespace dentsim
