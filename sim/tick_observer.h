// A per-tick observer of `run_scene` (issue #19): the hook through which the live view (view/)
// sees the simulation. The loop owner calls TickObserver::on_tick once per servo tick, at the end
// of the tick's loop body, on the servo thread, with a view of that tick's state.
//
// Contract for implementations: on_tick runs inside the servo loop, so it must not block, wait,
// allocate or throw; it copies what it needs and returns (view/snapshot.h publishes it to the
// render thread without locks). Everything the view points to is valid only during the call.
//
// Frames and units: world frame {O}, SI units (m, N, s); rotations are R in SO(3) (body to world).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>

#include "reference/core/types.h"
#include "reference/tooth/materials.h"
#include "reference/tooth/sampled_field.h"
#include "reference/tooth/voxel_grid.h"
#include "reference/tooth/voxel_runs.h"

namespace dentsim {

struct TickSnapshotView {
  long tick = 0;                        // tick index k
  double t = 0.0;                       // simulated time at the tick's sample [s]
  Pose device;                          // x1, R1: the device's tool (the hand's position)
  Pose proxy;                           // x2, R2: the proxy (what the tooth sees)
  double tool_radius_m = 0.0;           // tip sphere radius rho [m]
  Vec3 contact_force_n = Vec3::Zero();  // force on the proxy from the tooth (F_contact, linear) [N]
  Vec3 device_force_n = Vec3::Zero();   // force fed back to the device (T1, linear) [N]
  int contacts = 0;                     // size of the tick's contact set
  double max_depth_m = 0.0;             // deepest penetration of the proxy [m]
  double tick_us = 0.0;                 // wall-clock time of the servo tick (stages + drilling)
  std::array<double, kMaterialCount> removed_volume_mm3{};  // per Material id so far (0 unused)
  std::uint32_t faults = 0;                    // the device's latched fault flags (device/device.h)
  // The tooth after this tick's drilling, and the flat indices of the voxels this tick's
  // drilling removed (the only voxels that changed; ToothProviderBase::last_removed).
  const VoxelGrid* tooth = nullptr;
  std::span<const std::size_t> touched_voxels;
};

// The run as it starts (TickObserver::on_start; issue #30): what the view needs once, before the
// first tick, beyond the ticks' views.
struct RunStartView {
  // The tooth's sampled field before the first tick (contact model "field"; RunResult::
  // field_before, the same immutable object: shared, never edited), null for the other models.
  // The live view copies it on its own thread and edits its copy as drilling removes voxels.
  std::shared_ptr<const SampledField> field;
  // The placed tooth before the first tick (RunResult::tooth_before), valid during the call: with
  // a field, the view's edit starts from it (every voxel removed since is subtracted).
  const VoxelRuns* tooth_before = nullptr;
};

class TickObserver {
 public:
  virtual ~TickObserver() = default;
  // Once, before the first tick, on the thread that runs the loop but outside the loop (it may
  // allocate; it should return quickly). Default: nothing.
  virtual void on_start(const RunStartView& start) { (void)start; }
  virtual void on_tick(const TickSnapshotView& tick) = 0;
};

}  // namespace dentsim
