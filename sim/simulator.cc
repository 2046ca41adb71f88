#include "sim/simulator.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <numbers>
#include <thread>

#include "device/backend.h"
#include "device/callback_loop.h"
#include "device/closed_loop.h"
#include "device/hdapi/hdapi_device.h"
#include "device/phantom_device.h"
#include "device/servo_pacer.h"
#include "device/simulated_phantom.h"
#include "fast/registry.h"
#include "reference/core/io.h"
#include "reference/core/so3.h"
#include "reference/grasp_mass_model.h"
#include "reference/phantom/phantom_model.h"
#include "reference/phantom/phantom_params.h"
#include "reference/tick.h"
#include "reference/tools.h"
#include "reference/tooth/collision.h"
#include "reference/tooth/drilling.h"
#include "reference/tooth/tooth_contacts.h"
#include "sim/session_record.h"
#include "tooth_io/mesh.h"
#include "tooth_io/procedural_molar.h"
#include "tooth_io/tooth_field.h"
#include "tooth_io/voxelize.h"

namespace dentsim {
namespace {

VoxelGrid build_tooth(const SceneTooth& t) { return build_tooth_grid_cached(tooth_source(t)); }

// The top of the occlusal surface near the crown's axis: the highest solid voxel top among the
// columns within 1.5 mm (at least one voxel) of the solid's centroid in x, y.
Vec3 occlusal_anchor(const VoxelGrid& g) {
  Vec3 c = Vec3::Zero();
  long n = 0;
  for (int k = 0; k < g.n; ++k) {
    for (int j = 0; j < g.n; ++j) {
      for (int i = 0; i < g.n; ++i) {
        if (g.solid(i, j, k)) {
          c += g.center(i, j, k);
          ++n;
        }
      }
    }
  }
  if (n == 0) throw InputError("the tooth has no solid voxel");
  c /= static_cast<double>(n);
  const double radius = std::max(1.5e-3, g.voxel_size);
  double top = -1e300;
  for (int k = 0; k < g.n; ++k) {
    for (int j = 0; j < g.n; ++j) {
      for (int i = 0; i < g.n; ++i) {
        if (!g.solid(i, j, k)) continue;
        const Vec3 p = g.center(i, j, k);
        if (std::hypot(p.x() - c.x(), p.y() - c.y()) <= radius) {
          top = std::max(top, p.z() + 0.5 * g.voxel_size);
        }
      }
    }
  }
  return Vec3(c.x(), c.y(), top);
}

// Device penetrations below this (the Phantom's tip resolution, ~0.03 mm, docs/device_facts.md §3)
// are encoder noise and do not enter the stiffness fit.
constexpr double kMinDepthForStiffness = 3e-5;
// The loop owner's velocity guard [rad/s] (phantom_safety_limits' value, device/safety_chain.h).
constexpr double kSceneMaxJointSpeed = 20.0;

// RunResult::tip_quantum_m: max over the world axes a of sum_i |J_t(a, i)| 2 pi / counts_i at home.
double tip_encoder_quantum(const SceneRig& rig) {
  const Mat6 Jt = rig.model->model().tool_jacobian(Vec6(rig.q_home));
  double quantum = 0.0;
  for (int a = 0; a < 3; ++a) {
    double sum = 0.0;
    for (int i = 0; i < 6; ++i) {
      sum += std::abs(Jt(a, i)) * 2.0 * std::numbers::pi / rig.params.encoder_counts_per_rev(i);
    }
    quantum = std::max(quantum, sum);
  }
  return quantum;
}

StageStats stats_of(std::vector<double>& v) {
  StageStats s;
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  s.median_us = v[v.size() / 2];
  s.p99_us = v[std::min(v.size() - 1, static_cast<std::size_t>(0.99 * v.size()))];
  s.max_us = v.back();
  double sum = 0.0;
  for (double x : v) sum += x;
  s.mean_us = sum / static_cast<double>(v.size());
  return s;
}

}  // namespace

const VoxelGrid& SceneRig::tooth_grid() const { return pipeline_tooth->grid(); }

void SceneRig::tip_contacts(const Pose& pose, std::vector<Contact>* out) {
  pipeline_tooth->tip_contacts(pose, out);
}

// The safety chain's ramp-in and watchdog on a real device (hdapi); none in simulation.
constexpr double kHardwareRampS = 0.5;
constexpr double kHardwareWatchdogPeriods = 20.0;
// The safety chain's sustained-saturation guard in every scene run.
constexpr double kMaxSaturationS = 2.0;

double SceneRig::tip_depth(const Pose& pose) {
  if (field) {  // the "field" model: the tip sphere's overlap with the field's own solid
    // As the provider reads it (the fast pipeline's published bricks: the field itself may be
    // mid-edit on the provider's worker thread).
    const Vec3 c = pose.x + pose.R * tip.offset_body;
    return std::max(0.0, tip.radius - (tooth_provider != nullptr ? tooth_provider->field_value(c)
                                                                 : field->value(c)));
  }
  tip_contacts(pose, &measure_contacts);
  double d = 0.0;
  for (const Contact& c : measure_contacts) d = std::max(d, c.depth);
  return d;
}

namespace {

// The device: the model file drives both the simulated plant and the pipeline's model.
void load_device(const Scene& scene, SceneRig& g) {
  g.params = scene.device.model_file.empty() ? default_phantom_params()
                                             : load_phantom_params(scene.device.model_file);
  g.model = std::make_unique<PhantomModel>(g.params);
  g.q_home = phantom_home_q(g.params);
  g.home = g.model->forward_kinematics(g.q_home);

  SimulatedDeviceConfig dcfg = phantom_device_config(g.params);
  dcfg.quantize = scene.device.quantize;
  dcfg.saturate = scene.device.saturate;
  dcfg.jitter.period = g.tick;
  if (scene.device.jitter_us > 0.0) {
    dcfg.jitter.kind = TickJitterKind::kUniform;
    dcfg.jitter.half_width = 1e-6 * scene.device.jitter_us;
  }
  g.device = std::make_unique<SimulatedPhantom>(phantom_plant(g.params), dcfg, g.q_home);
}

DeviceBackend scene_backend(const Scene& scene, const SceneRigOptions& options) {
  const std::string backend_name = options.device.empty() ? scene.device.type : options.device;
  const std::optional<DeviceBackend> found = find_device_backend(backend_name);
  if (!found) {
    throw InputError("device '" + backend_name + "': expected " + device_backend_list());
  }
  return *found;
}

// The tooth, placed so its occlusal anchor sits at home + anchor_offset, and its field.
void place_tooth(const Scene& scene, SceneRig& g) {
  VoxelGrid grid = build_tooth(scene.tooth);
  g.anchor = g.home.x + scene.tooth.anchor_offset;
  const Vec3 tooth_shift = g.anchor - occlusal_anchor(grid);
  grid.origin += tooth_shift;
  g.tooth_before = VoxelRuns(grid);
  g.tooth = std::make_unique<VoxelTooth>(std::move(grid));
  g.tip.radius = scene.tool.bur_radius;
  g.measure_contacts.reserve(4096);
  g.k_tooth = scene.tooth.k_tooth;
  g.b_tooth = scene.tooth.b_tooth;
  // The tooth's sampled field, built from its source (contact model "field"; tooth_io/
  // tooth_field.h), which every implementation's tooth reads.
  if (parse_contact_model(scene.tooth.contact_model) == ContactModel::kField) {
    const double h = g.tooth->grid().voxel_size;
    if (scene.tooth.field_spacing > 0.0 && scene.tooth.field_spacing < h * (1.0 - 1e-9)) {
      throw InputError(scene.origin + ": tooth.field_spacing_mm: " +
                       std::to_string(1e3 * scene.tooth.field_spacing) +
                       " mm is below the voxel size " + std::to_string(1e3 * h) + " mm at " +
                       std::to_string(scene.tooth.resolution) +
                       "^3 (the field samples voxel centres; 0 or absent: automatic)");
    }
    const int stride = field_stride_for(g.tip.radius, h, scene.tooth.field_spacing);
    g.field = std::make_unique<SampledField>(
        build_tooth_field(tooth_source(scene.tooth), g.tooth->grid(), tooth_shift,
                          field_band_for_tip(g.tip.radius, h, stride)));
  }
}

// The implementation's tooth on the placed tooth: its contacts and, if the tool drills, drilling.
void make_pipeline_tooth(const Scene& scene, const SceneRigOptions& options,
                         const Implementation& impl, bool hdapi, SceneRig& g) {
  DrillParams drill;
  drill.bur_speed_rad_s = scene.tool.bur_speed_rpm * 2.0 * std::numbers::pi / 60.0;
  drill.cutting_coefficient = scene.tool.cutting_coefficient;
  const DrillParams* drilling = scene.tool.drills() ? &drill : nullptr;
  const ContactModel contact_model = parse_contact_model(scene.tooth.contact_model);
  PipelineToothSetup tooth_setup;
  tooth_setup.tip = g.tip;
  tooth_setup.k_tooth = g.k_tooth;
  tooth_setup.b_tooth = g.b_tooth;
  tooth_setup.drilling = drilling;
  tooth_setup.contact_model = contact_model;
  tooth_setup.skip_unneeded = options.skip_unneeded;
  tooth_setup.field = g.field.get();
  // A loop paced by a clock (an HDAPI device, --realtime) never waits for the field edit's
  // worker (fast/tooth/field.h).
  tooth_setup.real_time = hdapi || options.realtime;
  g.pipeline_tooth = impl.tooth(*g.tooth, tooth_setup);
  g.contacts = &g.pipeline_tooth->provider();
  g.tooth_provider = dynamic_cast<ToothContactProvider*>(g.contacts);
}

// The scripted hand, its keyframes relative to the tooth's anchor.
void script_hand(const Scene& scene, SceneRig& g) {
  std::vector<HandKeyframe> keys;
  for (const SceneHandKey& k : scene.script) {
    HandKeyframe hk;
    hk.t = k.t;
    hk.x_ref = g.anchor + k.offset;
    hk.wrench_ff = stack(k.force, Vec3::Zero());
    keys.push_back(hk);
  }
  g.hand = std::make_unique<ScriptedHand>(scene.hand, keys, g.home.R);
  g.device->set_hand(g.hand.get());
}

// The pipeline on the implementation's device model.
void make_scene_pipeline(const Scene& scene, const SceneRigOptions& options,
                         const Implementation& impl, SceneRig& g) {
  // The pipeline's device model: the model file's, plus the gripping hand's nominal mass at the
  // tip when the scene asks for it (reference/grasp_mass_model.h): always (a fixed mass), or
  // tick by tick as the grip detector decides (method.grip_detector; then the pipeline's model
  // is the device alone and the detector adds the mass).
  // Each implementation evaluates the same model file through its own device model.
  g.pipeline_model = make_phantom_model(impl.name(), g.params, options.float_device_terms);
  const SixDofDeviceModel* base = g.pipeline_model.get();
  if (scene.method.grasp_mass_scale > 0.0) {
    g.grasp =
        std::make_unique<GraspMassModel>(*base, scene.method.grasp_mass_scale * scene.hand.mass,
                                         scene.method.grasp_mass_scale * scene.hand.inertia);
  }
  const bool detect = g.grasp && scene.method.grip_detector;
  const SixDofDeviceModel& belief =
      g.grasp && !detect ? static_cast<const SixDofDeviceModel&>(*g.grasp) : *base;

  // Pipeline.
  PipelineConfig pc;
  pc.method = scene.method.method;
  pc.proxy = scene.method.proxy;
  pc.coupling = scene.method.coupling;
  pc.friction = scene.method.friction;
  // The tool's desired inertia sits on this device's locked inertia M_L = M1 + M2 at home
  // (thesis §3.1.2: M_d at least the device's own inertia, or the feed-forward makes the tool
  // feel lighter than the device by injecting energy); with the detector, on the gripped model.
  {
    const SixDofDeviceModel& heaviest =
        g.grasp ? static_cast<const SixDofDeviceModel&>(*g.grasp) : *base;
    const Mat6 J1 = heaviest.twist_to_joint(g.q_home);
    const Mat6 M1 = J1.transpose() * heaviest.mass_matrix(g.q_home) * J1;
    pc.tool = tool_preset(scene.tool.preset, M1 + scene.method.proxy.M());
  }
  pc.observer_gain = VecX::Constant(6, scene.method.observer_gain);
  // The observer's input matched to the driver's velocity estimate (reference/observer.h): without
  // it the decomposition's feed-forward closes a loop through the velocity filter's lag.
  pc.observer_input = matched_observer_input(g.device->capabilities());
  pc.torque_limit = phantom_torque_clamp(g.params);  // the motors' peak with a thermal limit
  if (detect) pc.grasp_model = g.grasp.get();
  pc.encoder_kalman = scene.method.encoder_kalman;
  pc.encoder_kalman_params.model_friction = scene.method.encoder_kalman_friction;
  pc.encoder_kalman_params.stick_slip = scene.method.encoder_kalman_stick_slip;
  pc.encoder_quantum = g.device->capabilities().encoder_quantum;
  pc.lag_compensation = scene.method.lag_compensation;
  pc.saturation_passive = scene.method.saturation_passive;
  pc.velocity_estimate = matched_observer_input(g.device->capabilities());
  pc.skip_unneeded = options.skip_unneeded;
  if (options.configure_pipeline) options.configure_pipeline(pc);
  g.pipeline = make_pipeline(options.pipeline, belief, pc);
}

// The loop owner's safety chain.
void make_safety_chain(DeviceBackend backend, SceneRig& g) {
  SafetyLimits limits;
  limits.tau_max = phantom_torque_clamp(g.params);
  limits.qd_max = VecX::Constant(g.device->dof(), kSceneMaxJointSpeed);
  limits.ramp_time_s = 0.0;
  if (backend == DeviceBackend::kHdapi) {
    // A real device: force engages over the first kHardwareRampS, and a tick whose own work took
    // longer than kHardwareWatchdogPeriods periods of CPU time (not slow but broken: the
    // Release drill tick's worst is ~0.7 ms; under the sanitizers its first contact took over
    // 5 ms; the device's own watchdog would trip later) means zero torque.
    limits.ramp_time_s = kHardwareRampS;
    limits.watchdog_s = kHardwareWatchdogPeriods * g.tick;
  }
  limits.nominal_period = g.tick;
  limits.monotonic_time = true;
  limits.max_joint_step = g.device->limits().max_joint_step;
  // A hand pushing harder than the device can render holds the motors at their peak: a safe stop
  // after kMaxSaturationS (both backends; a built-in scene never saturates that long).
  limits.max_saturation_s = kMaxSaturationS;
  g.safety = std::make_unique<SafetyChain>(limits);
}

// The device the loop drives, started last: a device with its own clock (HDAPI's scheduler;
// the emulator's scripted hand starts at hdInitDevice) runs from here on.
void connect_loop_device(const Scene& scene, const SceneRigOptions& options, DeviceBackend backend,
                         SceneRig& g) {
  Device* loop_device = g.device.get();
  if (backend == DeviceBackend::kHdapi) {
    // The project's emulator simulates the plant and the hand of the scene named by
    // DENTSIM_HD_EMU_SCENE (device/hdapi/emulator): hand it this scene, as parsed, unless the
    // caller chose one; a real device's library ignores the variable.
    if (std::getenv("DENTSIM_HD_EMU_SCENE") == nullptr) {
      const std::string path = (std::filesystem::temp_directory_path() /
                                ("dentsim_hd_scene_" + std::to_string(::getpid()) + ".json"))
                                   .string();
      write_file_atomic(path, scene.text);
      ::setenv("DENTSIM_HD_EMU_SCENE", path.c_str(), 0);
    }
    HdapiConfig hc;
    hc.library = options.hd_library;
    hc.rate_hz = static_cast<int>(std::lround(scene.tick_hz));
    g.backend = std::make_unique<HdapiDevice>(hc);
    loop_device = g.backend.get();
  }
  if (options.fault.kind != InjectedFault::kNone) {
    g.faulty = std::make_unique<FaultInjectingDevice>(*loop_device, options.fault);
    loop_device = g.faulty.get();
  }
  g.loop_device = loop_device;
}

// The closed loop with its safety chain and virtual supervisor.
void close_loop(const Scene& scene, SceneRig& g) {
  g.loop = std::make_unique<ClosedLoop>(*g.loop_device, *g.pipeline, *g.contacts);
  g.loop->set_safety_chain(g.safety.get());
  SupervisorLimits supervision;
  supervision.tool_radius_m = g.tip.radius;
  supervision.nominal_period_s = g.tick;
  // A late tick is ridden through up to what the momentum observer integrates stably in one
  // step (L T_k < 2, reference/observer.h), and never less than 5 periods: 67 ms at the
  // built-ins' L = 30 /s. Beyond it the estimate (and pmi-pd's feed-forward) would overshoot.
  supervision.max_tick_s = std::max(5.0 * g.tick, 2.0 / scene.method.observer_gain);
  g.supervisor = std::make_unique<VirtualSupervisor>(supervision);
  g.loop->set_supervisor(g.supervisor.get());
}

}  // namespace

std::unique_ptr<SceneRig> build_scene_rig(const Scene& scene, const SceneRigOptions& options) {
  auto rig = std::make_unique<SceneRig>();
  SceneRig& g = *rig;
  g.tick = 1.0 / scene.tick_hz;
  load_device(scene, g);
  const DeviceBackend backend = scene_backend(scene, options);
  place_tooth(scene, g);
  // The implementation of the tick (fast/registry.h): its tooth and its device model.
  const Implementation& impl = implementation(options.pipeline);
  make_pipeline_tooth(scene, options, impl, backend == DeviceBackend::kHdapi, g);
  script_hand(scene, g);
  make_scene_pipeline(scene, options, impl, g);
  make_safety_chain(backend, g);
  connect_loop_device(scene, options, backend, g);
  close_loop(scene, g);
  return rig;
}

namespace {

// --hd-loop names a loop, and a loop inside the vendor's callback cannot be wrapped, viewed or
// paced by the caller's loop.
void check_loop_options(const Scene& scene, const RunOptions& options) {
  const std::string backend = options.device.empty() ? scene.device.type : options.device;
  if (options.hd_loop != "callback" && options.hd_loop != "caller") {
    throw InputError("--hd-loop '" + options.hd_loop + "': expected callback or caller");
  }
  if (find_device_backend(backend) == DeviceBackend::kHdapi && options.hd_loop == "callback") {
    const char* why = options.fault.kind != InjectedFault::kNone ? "--inject-fault wraps"
                      : options.observer != nullptr              ? "the view runs on"
                      : options.realtime                         ? "--realtime paces"
                      : !options.tick_times_path.empty()         ? "--tick-times counts on"
                                                                 : nullptr;
    if (why != nullptr) {
      throw InputError(std::string("with --device hdapi the tick runs in the vendor's callback (") +
                       "--hd-loop callback), but " + why +
                       " the caller's loop: add --hd-loop caller");
    }
  }
}

SceneRigOptions scene_rig_options(const RunOptions& options) {
  SceneRigOptions rig_options;
  rig_options.pipeline = options.pipeline;
  rig_options.fault = options.fault;
  rig_options.float_device_terms = options.float_device_terms;
  rig_options.skip_unneeded = options.skip_unneeded;
  rig_options.device = options.device;
  rig_options.hd_library = options.hd_library;
  rig_options.realtime = options.realtime;
  return rig_options;
}

// What ran: the device model, the implementation, the backend and its loop.
void describe_run(const Scene& scene, const RunOptions& options, const SceneRig& rig,
                  RunResult& res) {
  const bool truth = rig.backend == nullptr;
  res.device_model =
      scene.device.model_file.empty() ? "default Phantom Premium 1.5A" : scene.device.model_file;
  res.pipeline = rig.pipeline->name();
  res.skip_unneeded = options.skip_unneeded;
  res.tooth_before = rig.tooth_before;
  if (rig.field) res.field_before = std::make_shared<const SampledField>(*rig.field);
  if (!truth) res.hd_loop = options.hd_loop;
  res.device =
      device_backend_name(truth ? DeviceBackend::kSimulatedPhantom : DeviceBackend::kHdapi);
  res.has_ground_truth = truth;
}

// The recorder (RunOptions::record_path; null without one): its writer thread drains a
// preallocated ring.
std::unique_ptr<SessionWriter> make_session_recorder(const Scene& scene, const RunOptions& options,
                                                     const RunResult& res, int dof, double duration,
                                                     long n_ticks) {
  if (options.record_path.empty()) return nullptr;
  SessionHeader h;
  h.dof = dof;
  h.tick_rate_hz = scene.tick_hz;
  const nlohmann::json context = {{"scene", nlohmann::json::parse(scene.text)},
                                  {"scene_origin", scene.origin},
                                  {"pipeline", res.pipeline},
                                  {"duration_s", duration}};
  h.context = context.dump();
  const std::size_t capacity = static_cast<std::size_t>(std::min<long>(n_ticks + 2, 1L << 18));
  return std::make_unique<SessionWriter>(options.record_path, h, capacity);
}

// --realtime: absolute deadlines, overruns counted and skipped (device/servo_pacer.h).
struct RealtimePacing {
  std::unique_ptr<ServoPacer> pacer;
  bool fifo = false, locked = false;

  // `provider` (may be null): its helper thread (the field edit's worker) runs just below the
  // servo's SCHED_FIFO priority where permitted, a warning where not.
  void start(const RunOptions& options, double T, ToothContactProvider* provider) {
    if (!options.realtime) return;
    pacer = std::make_unique<ServoPacer>(T);
    std::string warning;
    if (options.realtime_priority) {
      request_realtime(&fifo, &locked, &warning);
      if (fifo && provider != nullptr) {
        const std::string worker = provider->set_worker_priority(kRealtimePriority - 1);
        if (!worker.empty()) warning += (warning.empty() ? "" : "; ") + worker;
      }
      if (!warning.empty()) std::fprintf(stderr, "dentsim run: warning: %s\n", warning.c_str());
    }
    pacer->set_privileges(fifo, locked, warning);
    pacer->start();
  }
  void finish(RunResult& res) {
    if (!pacer) return;
    release_realtime(fifo, locked);
    res.realtime = pacer->stats();
  }
};

// --hd-loop callback: the tick runs on the vendor's scheduler thread, so the provider's helper
// thread (the field edit's worker) runs just below that thread when it is real-time
// (helper_priority_below), a warning where the worker may not; nothing when it is time-shared.
void place_worker_below_scheduler(SceneRig& rig) {
  if (rig.tooth_provider == nullptr) return;
  int policy = 0, priority = 0;
  if (!static_cast<HdapiDevice&>(*rig.backend).scheduler_policy(&policy, &priority)) return;
  const int below = helper_priority_below(policy, priority);
  if (below == 0) return;
  const std::string why = rig.tooth_provider->set_worker_priority(below);
  if (!why.empty()) std::fprintf(stderr, "dentsim run: warning: %s\n", why.c_str());
}

// What the loop thread's kernel counted over one tick's loop step (RunOptions::tick_times_path).
struct StepCounts {
  long minor_faults = 0;
  long voluntary_switches = 0;
  long involuntary_switches = 0;
  long removed_voxels = 0;  // the tick's drilling's (ToothProviderBase::last_removed)
};

// The calling thread's rusage (RUSAGE_THREAD).
rusage thread_usage() {
  rusage u{};
  getrusage(RUSAGE_THREAD, &u);
  return u;
}

// The measurements of a scene run, tick by tick, whichever thread ran the tick (run_direct's loop,
// or the vendor's scheduler callback: device/callback_loop.h), and the session recorder's feed.
struct RunMeasurements {
  RunMeasurements(const Scene& scene_in, const RunOptions& options_in, SceneRig& rig_in,
                  RunResult& res_in, long n_ticks_in)
      : scene(scene_in),
        options(options_in),
        rig(rig_in),
        res(res_in),
        n_ticks(n_ticks_in),
        truth(rig_in.backend == nullptr) {
    for (auto& v : stage_us) v.reserve(n_ticks);
    if (!options.tick_times_path.empty()) {
      tick_counts.reserve(static_cast<std::size_t>(std::max(0L, n_ticks)));
      tick_contacts.reserve(static_cast<std::size_t>(std::max(0L, n_ticks)));
    }
    res.series.reserve(n_ticks / std::max(1, options.log_every) + 1);
    res.quiet_series.tick_s = rig.tick;
    res.quiet_series.reserve(static_cast<std::size_t>(std::max(0L, n_ticks)) + 1);
    res.tip_quantum_m = tip_encoder_quantum(rig);
    // The loop copies the tick's input sample into rec_sample (no allocation: same sizes).
    rec_sample = rig.loop->sample();
    rec_tau = VecX::Zero(rec_sample.q.size());
  }

  // One tick's measurements; false ends the run. `stand_in_ns`: what the tick's publish spent in
  // the field edit worker's stead (ToothContactProvider::field_edit_stand_in_ns; 0 in real time).
  bool consume(const TickRecord& rec, double device_us, long stand_in_ns) {
    if (recorder) record(rec);
    res.virtual_energy_generated_j = rec.energy_virtual_j;
    if (rec.faulted) {
      // The loop latched a fault and commanded zero torque: end the run here; the report and the
      // time series up to the fault are kept.
      res.faults.push_back(std::string(rec.fault_name) + " at t = " + std::to_string(rec.fault_t) +
                           " s");
      return false;
    }
    res.hand_work_min_j = std::min(res.hand_work_min_j, hand_work);
    const long tick_ns = time_stages(rec, device_us, stand_in_ns);
    const Vec3 f_hand = measure(rec);
    if (rec.k % std::max(1, options.log_every) == 0) keep_sample(rec, f_hand);
    if (options.observer != nullptr) show(rec, tick_ns);
    return keep_running(rec);
  }

  void record(const TickRecord& rec) {
    rec_sample.q = rec.q.head(rec_sample.q.size());
    rec_sample.qd = rec.qd.head(rec_sample.qd.size());
    rec_sample.t = rec.t;
    rec_tau = rec.tau_pipeline.head(rec_tau.size());
    recorder->push(static_cast<std::uint64_t>(rec.k), rec_sample, rec_tau,
                   static_cast<std::uint32_t>(rec.contacts));
  }

  // The stages' times, the tick's, the device simulation's, the servo's own tick's and the field
  // edit's stand-in's [us]; returns the tick's [ns].
  long time_stages(const TickRecord& rec, double device_us, long stand_in_ns) {
    long tick_ns = 0;
    for (int s = 0; s < kStageCount; ++s) {
      stage_us[s].push_back(1e-3 * rec.stage_ns[s]);
      tick_ns += rec.stage_ns[s];
    }
    stage_us[kStageCount].push_back(1e-3 * tick_ns);
    stage_us[kStageCount + 1].push_back(device_us);
    // The servo's own tick: the publish's stand-in ran inside the collide stage (contacts()).
    stage_us[kStageCount + 2].push_back(1e-3 * (tick_ns - stand_in_ns));
    stage_us[kStageCount + 3].push_back(1e-3 * stand_in_ns);
    res.tick_ns_total += tick_ns;
    res.servo_tick_ns_total += tick_ns - stand_in_ns;
    if (!options.tick_times_path.empty()) {
      tick_counts.push_back(step_counts);
      tick_contacts.push_back(rec.contacts);
    }
    return tick_ns;
  }

  // Forces, penetrations, the stiffness fit's sums, the quiet series, the observer's error;
  // returns the true hand force (zero without ground truth).
  Vec3 measure(const TickRecord& rec) {
    const double f_contact = rec.f_contact.norm();
    const double f_device = rec.f_device.norm();
    const double d_dev = rec.device_depth;
    if (rec.contacts > 0) {
      ++res.contact_ticks;
      sum_f2 += f_contact * f_contact;
      res.max_contact_force_n = std::max(res.max_contact_force_n, f_contact);
      res.max_penetration_m = std::max(res.max_penetration_m, rec.max_depth);
    }
    if (d_dev > kMinDepthForStiffness) {
      sum_fd += f_device * d_dev;
      sum_dd += d_dev * d_dev;
    }
    const Vec3 f_hand = truth ? Vec3(rig.device->hand_wrench().head<3>()) : Vec3::Zero();
    QuietSeries& qs = res.quiet_series;
    qs.t.push_back(rec.t);
    qs.contacts.push_back(rec.contacts);
    qs.contact_force_n.push_back(f_contact);
    qs.device_force_n.push_back(f_device);
    qs.device_penetration_m.push_back(d_dev);
    qs.tip_x_m.push_back(rec.device.x.x());
    qs.tip_y_m.push_back(rec.device.x.y());
    qs.tip_z_m.push_back(rec.device.x.z());
    qs.energy_j.push_back(rec.energy_virtual_j);
    if (truth) qs.true_energy_j.push_back(motor_work);
    if (truth) qs.observer_error_n.push_back((rec.f_observer - f_hand).norm());
    sum_obs2 += (rec.f_observer - f_hand).squaredNorm();
    ++res.ticks;
    return f_hand;
  }

  // One sample of the report's time series.
  void keep_sample(const TickRecord& rec, const Vec3& f_hand) {
    RunSample smp;
    smp.t = rec.t;
    smp.contact_force_n = rec.f_contact.norm();
    smp.device_force_n = rec.f_device.norm();
    smp.device_force = rec.f_device;
    smp.penetration_m = rec.max_depth;
    smp.device_penetration_m = rec.device_depth;
    smp.proxy_x = rec.proxy.x;
    smp.device_x = rec.device.x;
    smp.proxy_rotvec = log_so3(rec.proxy.R);
    smp.device_rotvec = log_so3(rec.device.R);
    smp.hand_force_n = f_hand;
    smp.observer_force_n = rec.f_observer;
    smp.contacts = rec.contacts;
    smp.energy_virtual_j = rec.energy_virtual_j;
    smp.hand_work_j = hand_work;
    for (const SceneHandKey& key : scene.script) {
      if (key.t <= rec.t) smp.phase = key.phase;
    }
    res.series.push_back(std::move(smp));
  }

  // The tick as the live view sees it (RunOptions::observer).
  void show(const TickRecord& rec, long tick_ns) {
    const ToothProviderBase& contacts = *rig.contacts;
    TickSnapshotView view;
    view.tick = rec.k;
    view.t = rec.t;
    view.device = rec.device;
    view.proxy = rec.proxy;
    view.tool_radius_m = rig.tip.radius;
    view.contact_force_n = rec.f_contact;
    view.device_force_n = rec.f_device;
    view.contacts = rec.contacts;
    view.max_depth_m = rec.max_depth;
    view.tick_us = 1e-3 * tick_ns;
    for (int m = 1; m < kMaterialCount && contacts.drills(); ++m) {
      view.removed_volume_mm3[m] = contacts.drill_state().removed_volume_m3(m) * 1e9;
    }
    view.faults = rig.loop_device->faults();
    view.tooth = &rig.tooth_grid();
    view.touched_voxels = contacts.last_removed();
    options.observer->on_tick(view);
  }

  // A device fault or a stop request ends the run after this tick; progress is reported.
  bool keep_running(const TickRecord& rec) {
    const Device& driven = *rig.loop_device;
    if (driven.faults() != kFaultNone) {
      res.faults.push_back(fault_string(driven.faults()) + " at t = " + std::to_string(rec.t) +
                           " s");
      return false;
    }
    if (options.stop != nullptr && options.stop->load(std::memory_order_relaxed)) {
      res.stopped = true;  // at a tick boundary: this tick is measured, the next one never runs
      return false;
    }
    if (options.progress && rec.k >= next_progress) {
      options.progress(static_cast<double>(rec.k) / n_ticks);
      next_progress = rec.k + std::max(1L, n_ticks / 100);
    }
    return true;
  }

  // The run's totals: RMS force, rendered stiffness, hand work, observer error, stage timing.
  void summarise() {
    res.rms_contact_force_n = res.contact_ticks > 0 ? std::sqrt(sum_f2 / res.contact_ticks) : 0.0;
    res.rendered_stiffness_n_per_m = sum_dd > 0.0 ? sum_fd / sum_dd : 0.0;
    res.hand_work_j = hand_work;
    res.observer_rms_error_n = res.ticks > 0 ? std::sqrt(sum_obs2 / res.ticks) : 0.0;
    // Before the statistics, which sort the times in place.
    if (!options.tick_times_path.empty()) write_tick_times();
    for (int s = 0; s < kStageCount; ++s) {
      res.timing.emplace_back(tick_stage_name(s), stats_of(stage_us[s]));
    }
    res.timing.emplace_back("tick", stats_of(stage_us[kStageCount]));
    res.timing.emplace_back("device_simulation", stats_of(stage_us[kStageCount + 1]));
    res.timing.emplace_back("servo_tick", stats_of(stage_us[kStageCount + 2]));
    res.timing.emplace_back("field_edit_stand_in", stats_of(stage_us[kStageCount + 3]));
  }

  // RunOptions::tick_times_path: one row per measured tick.
  void write_tick_times() const {
    std::ofstream f(options.tick_times_path);
    if (!f) throw InputError("cannot write " + options.tick_times_path);
    f.precision(12);  // every ns of the times
    f << "k";
    for (int s = 0; s < kStageCount; ++s) f << ',' << tick_stage_name(s) << "_us";
    f << ",tick_us,device_simulation_us,servo_tick_us,field_edit_stand_in_us,contacts,"
         "removed_voxels,minor_faults,voluntary_switches,involuntary_switches\n";
    for (std::size_t k = 0; k < tick_counts.size(); ++k) {
      f << k;
      for (const std::vector<double>& us : stage_us) f << ',' << us[k];
      const StepCounts& c = tick_counts[k];
      f << ',' << tick_contacts[k] << ',' << c.removed_voxels << ',' << c.minor_faults << ','
        << c.voluntary_switches << ',' << c.involuntary_switches << '\n';
    }
    if (!f) throw InputError("cannot write " + options.tick_times_path);
  }

  const Scene& scene;
  const RunOptions& options;
  SceneRig& rig;
  RunResult& res;
  const long n_ticks;
  const bool truth;  // the simulator's ground truth (no backend)
  // The stages, then tick, device_simulation, servo_tick, field_edit_stand_in [us].
  std::vector<double> stage_us[kStageCount + 4];
  double sum_f2 = 0.0, sum_fd = 0.0, sum_dd = 0.0, sum_obs2 = 0.0;
  double hand_work = 0.0;
  double motor_work = 0.0;  // the motors' true work so far (ground truth only)
  long next_progress = 0;
  std::unique_ptr<SessionWriter> recorder;
  DeviceSample rec_sample;
  VecX rec_tau;
  // RunOptions::tick_times_path: the current step's counts (set by the loop before consume) and
  // every measured tick's, with its contact count.
  StepCounts step_counts;
  std::vector<StepCounts> tick_counts;
  std::vector<int> tick_contacts;
};

// Where the run's ticks go: from t_begin (the device clock at start) for the duration, at most
// max_ticks of them.
struct RunSpan {
  double t_begin = 0.0;
  double duration = 0.0;
  long max_ticks = 0;
};

// The tick inside the vendor's scheduler callback (device/callback_loop.h); this thread consumes
// the records until the device's clock has covered the duration. Returns the device clock at the
// end of the last tick consumed.
double run_in_callback(SceneRig& rig, RunMeasurements& m, const RunSpan& span) {
  const double T = rig.tick;
  RunResult& res = m.res;
  HdapiDevice& hd = static_cast<HdapiDevice&>(*rig.backend);
  auto depth = [](void* ctx, const Pose& pose) {
    return static_cast<SceneRig*>(ctx)->tip_depth(pose);
  };
  CallbackServo servo(hd, *rig.loop, *rig.pipeline, depth, &rig,
                      static_cast<std::size_t>(std::min<long>(span.max_ticks + 16, 1L << 16)));
  servo.start();
  double t_end = span.t_begin;
  TickRecord rec;
  bool running = true;
  while (running) {
    if (servo.pop(rec)) {
      if (rec.t - span.t_begin >= span.duration - 0.5 * T) {
        t_end = rec.t;
        break;
      }
      running = m.consume(rec, 0.0, 0);  // real time: no stand-in
      t_end = rec.t;
      if (rec.k + 1 >= span.max_ticks) break;
      continue;
    }
    if (hd.servo_done() || !hd.wait_ticks(1)) {
      // The scheduler stopped calling us (the backend latched scheduler_stopped and disabled
      // force output): what is left in the ring is still measured.
      while (running && servo.pop(rec)) running = m.consume(rec, 0.0, 0);
      if (running) {
        res.faults.push_back(fault_string(rig.loop_device->faults() | kFaultSchedulerStopped) +
                             " at t = " + std::to_string(t_end) + " s");
      }
      break;
    }
  }
  servo.request_stop();
  hd.wait_ticks(2);  // the callback has returned DONE with zero torque (or the scheduler is gone)
  res.callback_dropped_ticks = servo.dropped();
  return t_end;
}

// The caller's loop: a device with its own clock (hdapi) runs until its clock has covered the
// duration, the simulated device for the nominal number of ticks. Returns the device clock at the
// end of the last tick consumed.
double run_direct(SceneRig& rig, RunMeasurements& m, const RunSpan& span, RealtimePacing& pacing) {
  const double T = rig.tick;
  const bool truth = m.truth;
  SimulatedPhantom& device = *rig.device;
  ClosedLoop& loop = *rig.loop;
  ServoPacer* pacer = pacing.pacer.get();
  VecX q_true_prev = device.true_q();
  DeviceSample step_in = loop.sample();  // the direct loop's copy of a tick's input sample
  TickRecord record;
  double t_end = span.t_begin;
  // The field edit's stand-in so far (the provider's running total, read on this, the servo's,
  // thread between ticks): each tick's is the difference.
  const ToothContactProvider* provider = rig.tooth_provider;
  long stand_in_seen = 0;
  const bool count_steps = !m.options.tick_times_path.empty();
  rusage usage_before{};
  for (long k = 0; !loop.faulted() && k < span.max_ticks; ++k) {
    if (!truth && loop.sample().t - span.t_begin >= span.duration - 0.5 * T) break;
    if (pacer) pacer->wait_next();
    if (count_steps) usage_before = thread_usage();
    const auto t0 = std::chrono::steady_clock::now();
    if (truth) q_true_prev = device.true_q();
    const DeviceSample& in = loop.sample();
    step_in.q = in.q;  // the tick's input (same sizes: no allocation)
    step_in.qd = in.qd;
    step_in.t = in.t;
    const TickResult& r = loop.step();
    if (pacer) pacer->tick_done();
    const double step_us = 1e-3 * std::chrono::duration_cast<std::chrono::nanoseconds>(
                                      std::chrono::steady_clock::now() - t0)
                                      .count();
    if (count_steps) {
      const rusage after = thread_usage();
      m.step_counts.minor_faults = after.ru_minflt - usage_before.ru_minflt;
      m.step_counts.voluntary_switches = after.ru_nvcsw - usage_before.ru_nvcsw;
      m.step_counts.involuntary_switches = after.ru_nivcsw - usage_before.ru_nivcsw;
      m.step_counts.removed_voxels = static_cast<long>(rig.contacts->last_removed().size());
    }
    // Hand port: the hand's joint torques (averaged over the tick) times the true joint motion.
    // The motors' true work: the torque applied over the tick times the same true motion.
    if (truth) {
      m.hand_work += device.hand_joint_torque().dot(device.true_q() - q_true_prev);
      m.motor_work += device.applied_torque().dot(device.true_q() - q_true_prev);
    }
    // The servo tick is what a real loop computes: the pipeline's stages and drilling. The
    // simulated device's physics (MuJoCo substeps, hand) runs inside loop.step too and is
    // reported apart, as "device_simulation". The device tip's own penetration (rendered
    // stiffness) is measured outside the tick.
    long tick_ns = 0;
    for (int s = 0; s < kStageCount; ++s) tick_ns += r.stage_ns[s];
    const double d_dev = loop.faulted() ? 0.0 : rig.tip_depth(r.device);
    fill_tick_record(k, step_in, r, loop, *rig.pipeline, d_dev, record);
    t_end = loop.sample().t;
    const long stand_in = provider != nullptr ? provider->field_edit_stand_in_ns() : 0;
    const long stand_in_ns = stand_in - stand_in_seen;
    stand_in_seen = stand_in;
    if (!m.consume(record, step_us - 1e-3 * tick_ns, stand_in_ns)) break;
  }
  return t_end;
}

// The tooth after the run: removed volumes, pulp exposure, the drilling log, the voxels.
void report_tooth(const SceneRig& rig, RunResult& res) {
  const ToothProviderBase& contacts = *rig.contacts;
  for (int m = 1; m < kMaterialCount; ++m) {
    res.removed_volume_mm3[m] =
        contacts.drills() ? contacts.drill_state().removed_volume_m3(m) * 1e9 : 0.0;
    res.removed_volume_total_mm3 += res.removed_volume_mm3[m];
  }
  if (contacts.pulp_exposed_tick() > 0) {
    res.pulp_exposed_at_s = contacts.pulp_exposed_tick() * rig.tick;
  }
  if (const ToothContactProvider* tooth = rig.tooth_provider) {
    res.field_edit_late_publishes = tooth->field_edit_late_publishes();
    res.field_edit_servo_takeovers = tooth->field_edit_servo_takeovers();
    res.field_edit_worker_waits = tooth->field_edit_worker_waits();
    res.field_edit_worker_wakes = tooth->field_edit_worker_wakes();
    res.field_edit_stand_in_ns = tooth->field_edit_stand_in_ns();
  }
  res.drill_log = contacts.drill_log();
  res.tooth_after = VoxelRuns(rig.tooth_grid());
}

// The supervisor's totals; its reason appended to a fault it raised.
void report_supervisor(const SceneRig& rig, RunResult& res) {
  const VirtualSupervisor& sup = *rig.supervisor;
  res.virtual_contact_work_j = sup.contact_work_j();
  res.late_ticks = sup.late_ticks();
  res.max_tick_s = sup.max_tick_s();
  if (sup.fault() != SupervisorFault::kNone && !res.faults.empty() &&
      res.faults.front().rfind(supervisor_fault_name(sup.fault()), 0) == 0) {
    res.faults.front() += " (" + sup.describe() + ")";
  }
}

}  // namespace

RunResult run_scene(const Scene& scene, const RunOptions& options) {
  const auto setup_start = std::chrono::steady_clock::now();
  RunResult res;
  res.scene = scene.name;
  const double duration =
      options.duration_override > 0.0 ? options.duration_override : scene.duration;
  check_loop_options(scene, options);
  const std::unique_ptr<SceneRig> rig = build_scene_rig(scene, scene_rig_options(options));
  const double T = rig->tick;
  describe_run(scene, options, *rig, res);
  if (options.prepare_rig) options.prepare_rig(*rig);
  if (options.observer != nullptr) {  // the view's setup, before the first tick (tick_observer.h)
    RunStartView start;
    start.field = res.field_before;
    start.tooth_before = &res.tooth_before;
    options.observer->on_start(start);
  }
  const bool truth = rig->backend == nullptr;
  // With HDAPI the tick runs inside the vendor's scheduler callback (RunOptions::hd_loop).
  const bool callback = !truth && options.hd_loop == "callback";
  ClosedLoop& loop = *rig->loop;

  const long n_ticks = static_cast<long>(std::ceil(duration / T));
  // The drill log's pages before the first tick, not in the ticks that fill them (issue #30).
  if (rig->contacts != nullptr && rig->contacts->drills()) {
    rig->contacts->prefault_drill_log(static_cast<std::size_t>(std::max(0L, n_ticks)));
  }
  RunMeasurements measurements(scene, options, *rig, res, n_ticks);
  const auto wall_start = std::chrono::steady_clock::now();
  res.setup_s = std::chrono::duration<double>(wall_start - setup_start).count();
  measurements.recorder =
      make_session_recorder(scene, options, res, rig->device->dof(), duration, n_ticks);
  loop.start();
  if (loop.faulted()) {
    res.faults.push_back(std::string(loop.fault_name()) +
                         " at t = " + std::to_string(loop.fault_time()) + " s");
  }
  RealtimePacing pacing;
  pacing.start(options, T, rig->tooth_provider);
  if (callback) place_worker_below_scheduler(*rig);
  // A device with its own clock (hdapi) runs until its clock has covered the duration (its ticks
  // need not be the nominal ones); the simulated device for the nominal number of ticks.
  RunSpan span;
  span.t_begin = loop.sample().t;
  span.duration = duration;
  span.max_ticks = truth ? n_ticks : 4 * n_ticks + 16;
  const double t_end = callback ? run_in_callback(*rig, measurements, span)
                                : run_direct(*rig, measurements, span, pacing);
  if (options.progress) options.progress(1.0);
  pacing.finish(res);
  if (measurements.recorder) {
    measurements.recorder->stop();  // drains every pushed tick, the faulting one included
    res.recorded_ticks = static_cast<long>(measurements.recorder->written());
    res.record_dropped_ticks = static_cast<long>(measurements.recorder->dropped());
  }

  res.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  res.simulated_s = truth ? res.ticks * T : t_end - span.t_begin;
  measurements.summarise();
  if (!callback) res.virtual_energy_generated_j = loop.energy_virtual_j();
  res.tick_s = T;
  report_tooth(*rig, res);
  if (rig->field) {
    // Undrilled, the field is the one the run started with; drilled, the rig's own field is
    // handed over (the rig ends here; the object, which its tooth points to, stays where it is):
    // no third copy of the band beside field_before (#30).
    if (res.drill_log.empty() && res.field_before) {
      res.field_after = res.field_before;
    } else {
      res.field_after = std::shared_ptr<const SampledField>(std::move(rig->field));
    }
  }
  report_supervisor(*rig, res);
  const bool faulted = callback ? !res.faults.empty() : loop.faulted();
  res.torque_after_fault_n_m = faulted ? rig->loop_device->applied_torque().norm() : 0.0;
  return res;
}

}  // namespace dentsim
