// Publication of the servo loop's state to the render thread without locks (issue #19).
//
// The servo thread (TickObserver::on_tick, sim/tick_observer.h) writes; one render thread
// reads. Neither ever waits for the other, and on_tick neither allocates nor throws:
//  - Tick state (poses, forces, timing, removed volume, faults): a triple buffer. Three slots;
//    the writer fills its private back slot, then atomically exchanges it with the shared middle
//    slot, setting a "fresh" bit; the reader, when the bit is set, exchanges its private front
//    slot with the middle one. Each side owns one slot at any time, the exchange is one
//    std::atomic<uint8_t>::exchange (acq_rel), so the reader always gets the latest complete
//    snapshot and a stalled reader only makes the writer overwrite the middle slot.
//  - The tooth: a shadow copy of the voxel materials as std::atomic<uint8_t> (preallocated for
//    the scene's resolution N^3 at construction; filled from the tooth at tick 0). Each tick the
//    writer compares the voxels its contacts touched (the only ones drilling can remove) with the
//    shadow, stores the removed ones (relaxed) and bumps their block's generation counter
//    (release). The reader polls the generations (acquire) and re-reads changed blocks. Voxels
//    only go from solid to empty, so a block read while being written is simply read again when
//    its generation moves on: the reader's copy converges to the writer's.
//  - The tooth's field (contact model "field"; issue #30): on_start, before the loop, keeps the
//    run's field before the first tick (RunResult::field_before: immutable, shared, not copied
//    on the servo thread) and the tooth before it (as runs); tick 0's release of the tooth
//    publishes them. The reader copies the field and edits its copy by the voxels removed since
//    (view/live_tooth.h): the servo's own field is never shared.
//  - Tick time statistics: a histogram of std::atomic<uint32_t> counters (0.25 us bins up to
//    2 ms, the last bin collects the rest), from which the reader takes median and p99.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "sim/tick_observer.h"
#include "reference/tooth/sampled_field.h"
#include "reference/tooth/voxel_grid.h"
#include "reference/tooth/voxel_runs.h"

namespace dentsim::view {

// One tick's state, as the render thread sees it (plain data; see TickSnapshotView for units).
struct TickSnapshot {
  long tick = -1;  // -1: nothing published yet
  double t = 0.0;
  Pose device, proxy;
  double tool_radius_m = 0.0;
  Vec3 contact_force_n = Vec3::Zero();
  Vec3 device_force_n = Vec3::Zero();
  int contacts = 0;
  double max_depth_m = 0.0;
  double tick_us = 0.0;
  std::array<double, kMaterialCount> removed_volume_mm3{};
  std::uint32_t faults = 0;
  Mat3 device_R0 = Mat3::Identity();  // R1 at tick 0 (the home pose), for drawing the shank
};

class SnapshotChannel : public TickObserver {
 public:
  static constexpr int kBlock = 16;       // voxels per block edge for the generation counters
  static constexpr double kBinUs = 0.25;  // tick-time histogram bin [us]
  static constexpr int kBins = 8000;      // 2 ms of bins; the last one collects the rest

  // `resolution`: the scene's tooth resolution N (voxels per axis).
  explicit SnapshotChannel(int resolution);

  // Writer side (the servo thread, before its loop): with the field model, keeps the run's field
  // before the first tick (an immutable shared object: not copied) and the tooth before it (its
  // runs, copied: a few bytes per row crossing the tooth).
  void on_start(const RunStartView& start) override;
  // Writer side (servo thread): publish one tick.
  void on_tick(const TickSnapshotView& tick) override;

  // Reader side (one render thread). Copies the newest snapshot into *out; returns true if it is
  // newer than the previous call's.
  bool latest(TickSnapshot* out);
  // True once the tooth was published (tick 0 seen); then `grid` receives the tooth's geometry
  // (n, origin, h) and the voxel materials of every block whose generation changed since the last
  // call, and `changed` the flat indices whose material differs from *grid's previous content.
  // The first call copies the whole tooth. Returns false (and does nothing) before tick 0.
  bool sync_tooth(VoxelGrid* grid, std::vector<std::size_t>* changed);
  // The tooth's sampled field before the first tick (contact model "field"), else null. Read it
  // only once sync_tooth returned true (on_start wrote it before tick 0's publication, which
  // sync_tooth acquired). Immutable: the reader copies it to edit (view/live_tooth.h).
  const std::shared_ptr<const SampledField>& field_before() const { return field_before_; }
  // With field_before(): the tooth before the first tick (the voxels field_before() is of).
  const VoxelRuns& tooth_before() const { return tooth_before_; }
  // Median and 99th percentile of the tick time over all published ticks [us] (bin centres).
  void tick_time_stats(double* median_us, double* p99_us) const;
  long ticks_published() const { return published_.load(std::memory_order_acquire); }
  // True if the scene's tooth did not have the resolution given at construction (not shown).
  bool tooth_mismatch() const { return mismatch_.load(std::memory_order_acquire); }

 private:
  // Triple buffer.
  std::array<TickSnapshot, 3> slots_;
  std::atomic<std::uint8_t> middle_{1};  // index of the middle slot | kFresh
  std::uint8_t back_ = 0, front_ = 2;
  static constexpr std::uint8_t kFresh = 0x4;

  // Tooth shadow.
  int n_;
  int nb_;
  std::unique_ptr<std::atomic<std::uint8_t>[]> shadow_;
  std::unique_ptr<std::atomic<std::uint32_t>[]> generation_;
  std::vector<std::uint32_t> seen_generation_;  // reader's
  std::atomic<bool> tooth_ready_{false};
  std::atomic<bool> mismatch_{false};
  // on_start's, published by tooth_ready_ (field model; else null and empty).
  std::shared_ptr<const SampledField> field_before_;
  VoxelRuns tooth_before_;
  Mat3 device_R0_ = Mat3::Identity();  // writer's, set at tick 0
  Vec3 origin_ = Vec3::Zero();         // written before tooth_ready_ (release)
  double h_ = 0.0;
  bool reader_has_tooth_ = false;

  std::unique_ptr<std::atomic<std::uint32_t>[]> histogram_;
  std::atomic<long> published_{0};
};

}  // namespace dentsim::view
