#include "device/simulator.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <numbers>
#include <thread>

#include "device/closed_loop.h"
#include "device/phantom_device.h"
#include "device/simulated_phantom.h"
#include "reference/core/io.h"
#include "reference/core/so3.h"
#include "reference/grasp_mass_model.h"
#include "reference/phantom/phantom_model.h"
#include "reference/phantom/phantom_params.h"
#include "reference/tick.h"
#include "reference/tools.h"
#include "reference/tooth/collision.h"
#include "reference/tooth/drilling.h"
#include "reference/tooth/mesh.h"
#include "reference/tooth/procedural_molar.h"
#include "reference/tooth/tooth_contacts.h"
#include "reference/tooth/voxelize.h"

namespace dentsim {
namespace {

VoxelGrid build_tooth(const SceneTooth& t) {
  if (t.source == "procedural") {
    return voxelize_procedural_molar(MolarParams{}, t.resolution);
  }
  LoadedMesh loaded = load_mesh(t.mesh_path);
  const double k = t.mesh_scale > 0.0 ? t.mesh_scale : scale_for_size(loaded.mesh, 1e-3 * t.size_mm);
  scale_mesh(loaded.mesh, k);
  VoxelizeOptions opt;
  opt.resolution = t.resolution;
  return voxelize_mesh(loaded.mesh, opt);
}

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

// Device penetrations below this (the Phantom's tip resolution, ~0.03 mm, PHANTOM.md) are
// encoder noise and do not enter the stiffness fit.
constexpr double kMinDepthForStiffness = 3e-5;

StageStats stats_of(std::vector<double>& v) {
  StageStats s;
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  s.median_us = v[v.size() / 2];
  s.p99_us = v[std::min(v.size() - 1, static_cast<std::size_t>(0.99 * v.size()))];
  s.max_us = v.back();
  return s;
}

}  // namespace

RunResult run_scene(const Scene& scene, const RunOptions& options) {
  RunResult res;
  res.scene = scene.name;
  const double T = 1.0 / scene.tick_hz;
  const double duration = options.duration_override > 0.0 ? options.duration_override
                                                           : scene.duration;

  // Device: the model file drives both the simulated plant and the pipeline's model.
  const PhantomParams params = scene.device.model_file.empty()
                                   ? default_phantom_params()
                                   : load_phantom_params(scene.device.model_file);
  res.device_model = scene.device.model_file.empty() ? "default Phantom Premium 1.5A"
                                                     : scene.device.model_file;
  const PhantomModel model(params);
  const VecX q_home = phantom_home_q(params);
  const Pose home = model.forward_kinematics(q_home);

  SimulatedDeviceConfig dcfg = phantom_device_config(params);
  dcfg.quantize = scene.device.quantize;
  dcfg.saturate = scene.device.saturate;
  dcfg.jitter.period = T;
  if (scene.device.jitter_us > 0.0) {
    dcfg.jitter.kind = TickJitterKind::kUniform;
    dcfg.jitter.half_width = 1e-6 * scene.device.jitter_us;
  }
  SimulatedPhantom device(phantom_plant(params), dcfg, q_home);

  // Tooth, placed so its occlusal anchor sits at home + anchor_offset.
  VoxelGrid grid = build_tooth(scene.tooth);
  const Vec3 anchor_target = home.x + scene.tooth.anchor_offset;
  grid.origin += anchor_target - occlusal_anchor(grid);
  res.tooth_before = grid;
  VoxelTooth tooth(std::move(grid));
  ToolTip tip;
  tip.radius = scene.tool.bur_radius;
  DrillParams drill;
  drill.bur_speed_rad_s = scene.tool.bur_speed_rpm * 2.0 * std::numbers::pi / 60.0;
  drill.cutting_coefficient = scene.tool.cutting_coefficient;
  ToothContactProvider contacts(tooth, tip, scene.tooth.k_tooth, scene.tooth.b_tooth,
                                scene.tool.drills() ? &drill : nullptr);

  // Hand.
  std::vector<HandKeyframe> keys;
  for (const SceneHandKey& k : scene.script) {
    HandKeyframe hk;
    hk.t = k.t;
    hk.x_ref = anchor_target + k.offset;
    hk.wrench_ff = stack(k.force, Vec3::Zero());
    keys.push_back(hk);
  }
  const ScriptedHand hand(scene.hand, keys, home.R);
  device.set_hand(&hand);

  // The pipeline's device model: the model file's, plus the gripping hand's nominal mass at the
  // tip when the scene asks for it (reference/grasp_mass_model.h).
  std::unique_ptr<GraspMassModel> grasp;
  if (scene.method.grasp_mass_scale > 0.0) {
    grasp = std::make_unique<GraspMassModel>(model, scene.method.grasp_mass_scale * scene.hand.mass,
                                             scene.method.grasp_mass_scale * scene.hand.inertia);
  }
  const SixDofDeviceModel& belief = grasp ? *grasp : static_cast<const SixDofDeviceModel&>(model);

  // Pipeline.
  PipelineConfig pc;
  pc.method = scene.method.method;
  pc.proxy = scene.method.proxy;
  pc.coupling = scene.method.coupling;
  pc.friction = scene.method.friction;
  // The tool's desired inertia sits on this device's locked inertia M_L = M1 + M2 at home
  // (thesis §3.1.2: M_d at least the device's own inertia, or the feed-forward makes the tool
  // feel lighter than the device by injecting energy).
  {
    const Mat6 J1 = belief.twist_to_joint(q_home);
    const Mat6 M1 = J1.transpose() * belief.mass_matrix(q_home) * J1;
    pc.tool = tool_preset(scene.tool.preset, M1 + scene.method.proxy.M());
  }
  pc.observer_gain = VecX::Constant(6, scene.method.observer_gain);
  // The observer's input matched to the driver's velocity estimate (reference/observer.h): without
  // it the decomposition's feed-forward closes a loop through the velocity filter's lag.
  pc.observer_input = matched_observer_input(device.capabilities());
  pc.torque_limit = params.torque_limit_n_m;
  ReferencePipeline pipeline(belief, pc);
  ClosedLoop loop(device, pipeline, contacts);

  CollisionScratch scratch;
  std::vector<Contact> device_contacts;
  device_contacts.reserve(4096);

  const long n_ticks = static_cast<long>(std::ceil(duration / T));
  std::vector<double> stage_us[kStageCount + 3];
  for (auto& v : stage_us) v.reserve(n_ticks);
  res.series.reserve(n_ticks / std::max(1, options.log_every) + 1);

  double sum_f2 = 0.0, sum_fd = 0.0, sum_dd = 0.0, sum_obs2 = 0.0;
  double hand_work = 0.0;
  VecX q_true_prev = device.true_q();
  const auto wall_start = std::chrono::steady_clock::now();
  long next_progress = 0;
  loop.start();
  for (long k = 0; k < n_ticks; ++k) {
    if (options.realtime) {
      std::this_thread::sleep_until(wall_start + std::chrono::duration<double>(k * T));
    }
    const auto t0 = std::chrono::steady_clock::now();
    const double t = loop.sample().t;
    q_true_prev = device.true_q();
    const TickResult& r = loop.step();
    // Hand port: the hand's joint torques (averaged over the tick) times the true joint motion.
    hand_work += device.hand_joint_torque().dot(device.true_q() - q_true_prev);
    res.hand_work_min_j = std::min(res.hand_work_min_j, hand_work);
    long drill_ns = 0;
    if (scene.tool.drills() && !r.contacts.empty()) {
      const auto d0 = std::chrono::steady_clock::now();
      contacts.drill(r.contacts, loop.last_tick_length());
      drill_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                     std::chrono::steady_clock::now() - d0).count();
    }
    // The servo tick is what a real loop computes: the pipeline's stages and drilling. The
    // simulated device's physics (MuJoCo substeps, hand) runs inside loop.step too and is
    // reported apart, as "device_simulation".
    const double step_us = 1e-3 * std::chrono::duration_cast<std::chrono::nanoseconds>(
                                      std::chrono::steady_clock::now() - t0).count();
    long tick_ns = drill_ns;
    for (int s = 0; s < kStageCount; ++s) {
      stage_us[s].push_back(1e-3 * r.stage_ns[s]);
      tick_ns += r.stage_ns[s];
    }
    stage_us[kStageCount].push_back(1e-3 * drill_ns);
    stage_us[kStageCount + 1].push_back(1e-3 * tick_ns);
    stage_us[kStageCount + 2].push_back(step_us - 1e-3 * tick_ns);

    // Measurements.
    const double f_contact = r.F_contact.head<3>().norm();
    const double f_device = r.T1.head<3>().norm();
    device_contacts.clear();
    collide_tool_tip(tooth, r.device, tip, scene.tooth.k_tooth, scene.tooth.b_tooth, &scratch,
                     &device_contacts);
    double d_dev = 0.0;
    for (const Contact& c : device_contacts) d_dev = std::max(d_dev, c.depth);
    if (!r.contacts.empty()) {
      ++res.contact_ticks;
      sum_f2 += f_contact * f_contact;
      res.max_contact_force_n = std::max(res.max_contact_force_n, f_contact);
      res.max_penetration_m = std::max(res.max_penetration_m, r.max_depth);
    }
    if (d_dev > kMinDepthForStiffness) {
      sum_fd += f_device * d_dev;
      sum_dd += d_dev * d_dev;
    }
    const Vec3 f_hand = device.hand_wrench().head<3>();
    const Vec3 f_obs = r.F1_hat.head<3>();
    sum_obs2 += (f_obs - f_hand).squaredNorm();
    ++res.ticks;
    if (k % std::max(1, options.log_every) == 0) {
      RunSample smp;
      smp.t = t;
      smp.contact_force_n = f_contact;
      smp.device_force_n = f_device;
      smp.penetration_m = r.max_depth;
      smp.device_penetration_m = d_dev;
      smp.proxy_x = pipeline.proxy().pose.x;
      smp.device_x = r.device.x;
      smp.proxy_rotvec = log_so3(pipeline.proxy().pose.R);
      smp.device_rotvec = log_so3(r.device.R);
      smp.hand_force_n = f_hand;
      smp.observer_force_n = f_obs;
      smp.contacts = static_cast<int>(r.contacts.size());
      smp.energy_virtual_j = loop.energy_virtual_j();
      smp.hand_work_j = hand_work;
      for (const SceneHandKey& key : scene.script) {
        if (key.t <= t) smp.phase = key.phase;
      }
      res.series.push_back(std::move(smp));
    }
    if (options.observer != nullptr) {
      TickSnapshotView view;
      view.tick = k;
      view.t = t;
      view.device = r.device;
      view.proxy = pipeline.proxy().pose;
      view.tool_radius_m = tip.radius;
      view.contact_force_n = r.F_contact.head<3>();
      view.device_force_n = r.T1.head<3>();
      view.contacts = static_cast<int>(r.contacts.size());
      view.max_depth_m = r.max_depth;
      view.tick_us = 1e-3 * tick_ns;
      for (int m = 1; m < kMaterialCount && contacts.drills(); ++m) {
        view.removed_volume_mm3[m] = contacts.drill_state().removed_volume_m3(m) * 1e9;
      }
      view.faults = device.faults();
      view.tooth = &tooth.grid();
      view.touched_voxels = contacts.contact_voxels();
      options.observer->on_tick(view);
    }
    if (device.faults() != kFaultNone) {
      res.faults.push_back(fault_string(device.faults()) + " at t = " + std::to_string(t) + " s");
      break;
    }
    if (!pipeline.proxy().pose.x.allFinite()) {
      res.faults.push_back("proxy state not finite at t = " + std::to_string(t) + " s");
      break;
    }
    if (options.progress && k >= next_progress) {
      options.progress(static_cast<double>(k) / n_ticks);
      next_progress = k + std::max(1L, n_ticks / 100);
    }
  }
  if (options.progress) options.progress(1.0);

  res.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  res.simulated_s = res.ticks * T;
  res.rms_contact_force_n = res.contact_ticks > 0 ? std::sqrt(sum_f2 / res.contact_ticks) : 0.0;
  res.rendered_stiffness_n_per_m = sum_dd > 0.0 ? sum_fd / sum_dd : 0.0;
  res.virtual_energy_generated_j = loop.energy_virtual_j();
  res.hand_work_j = hand_work;
  res.observer_rms_error_n = res.ticks > 0 ? std::sqrt(sum_obs2 / res.ticks) : 0.0;
  for (int m = 1; m < kMaterialCount; ++m) {
    res.removed_volume_mm3[m] =
        contacts.drills() ? contacts.drill_state().removed_volume_m3(m) * 1e9 : 0.0;
    res.removed_volume_total_mm3 += res.removed_volume_mm3[m];
  }
  for (int s = 0; s < kStageCount; ++s) {
    res.timing.emplace_back(tick_stage_name(s), stats_of(stage_us[s]));
  }
  res.timing.emplace_back("drilling", stats_of(stage_us[kStageCount]));
  res.timing.emplace_back("tick", stats_of(stage_us[kStageCount + 1]));
  res.timing.emplace_back("device_simulation", stats_of(stage_us[kStageCount + 2]));
  res.tooth_after = tooth.grid();
  return res;
}

}  // namespace dentsim
