// Tests of view/snapshot.h (the lock-free publication of the servo loop's state) and of the
// TickObserver hook of run_scene (sim/tick_observer.h): the reader never sees a torn snapshot,
// its copy of the tooth converges to the writer's, and a stalled renderer does not change a single
// tick of the run.
#include "view/snapshot.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <set>
#include <thread>

#include "sim/simulator.h"
#include "tooth_io/procedural_molar.h"

namespace dentsim::view {
namespace {

// Every field of the snapshot of tick k is a function of k, so a torn read shows as a mismatch.
TickSnapshotView view_of(long k, const VoxelGrid* tooth) {
  TickSnapshotView v;
  v.tick = k;
  v.t = 1e-3 * k;
  v.device.x = Vec3(k, 2.0 * k, 3.0 * k);
  v.proxy.x = Vec3(-k, -2.0 * k, -3.0 * k);
  v.tool_radius_m = 0.5 * k;
  v.contact_force_n = Vec3::Constant(4.0 * k);
  v.device_force_n = Vec3::Constant(5.0 * k);
  v.contacts = static_cast<int>(k % 1000);
  v.max_depth_m = 6.0 * k;
  v.tick_us = static_cast<double>(k % 7);
  v.removed_volume_mm3 = {0.0, 1.0 * k, 2.0 * k, 3.0 * k};
  v.tooth = tooth;
  return v;
}

bool consistent(const TickSnapshot& s) {
  const double k = static_cast<double>(s.tick);
  return s.t == 1e-3 * k && s.device.x == Vec3(k, 2 * k, 3 * k) &&
         s.proxy.x == Vec3(-k, -2 * k, -3 * k) && s.tool_radius_m == 0.5 * k &&
         s.contact_force_n == Vec3::Constant(4 * k) && s.device_force_n == Vec3::Constant(5 * k) &&
         s.contacts == static_cast<int>(s.tick % 1000) && s.max_depth_m == 6 * k &&
         s.removed_volume_mm3[3] == 3 * k;
}

TEST(SnapshotChannel, ReaderNeverSeesATornSnapshotAndEndsOnTheLatest) {
  SnapshotChannel ch(8);
  const long n = 200000;
  std::atomic<bool> done{false}, started{false};
  std::atomic<long> reads{0};
  long torn = 0, backwards = 0;
  std::thread reader([&] {
    TickSnapshot s;
    long last = -1;
    started.store(true);
    while (!done.load()) {
      if (ch.latest(&s)) {
        reads.fetch_add(1);
        torn += !consistent(s);
        backwards += s.tick < last;
        last = s.tick;
      }
      if (reads.load() % 64 == 0) std::this_thread::yield();
    }
  });
  // On a loaded machine the reader thread may not be scheduled before the writer is done: the
  // writer starts once the reader runs and stops once it has read at least once.
  while (!started.load()) std::this_thread::yield();
  for (long k = 0; k < n; ++k) ch.on_tick(view_of(k, nullptr));
  while (reads.load() == 0) std::this_thread::yield();
  done.store(true);
  reader.join();
  EXPECT_EQ(torn, 0);
  EXPECT_EQ(backwards, 0);
  EXPECT_GT(reads.load(), 0);
  TickSnapshot last;
  EXPECT_TRUE(ch.latest(&last) || last.tick == n - 1);
  EXPECT_EQ(last.tick, n - 1);
  EXPECT_TRUE(consistent(last));
  EXPECT_EQ(ch.ticks_published(), n);
  // Tick times k % 7 us: 0..6 in (almost) equal numbers -> median bin 3 us, p99 bin 6 us.
  double median = 0.0, p99 = 0.0;
  ch.tick_time_stats(&median, &p99);
  EXPECT_DOUBLE_EQ(median, 3.0 + 0.5 * SnapshotChannel::kBinUs);
  EXPECT_DOUBLE_EQ(p99, 6.0 + 0.5 * SnapshotChannel::kBinUs);
}

TEST(SnapshotChannel, ReaderToothConvergesToTheWritersWhileBeingDrilled) {
  VoxelGrid tooth = voxelize_procedural_molar(MolarParams{}, 32);
  SnapshotChannel ch(32);
  VoxelGrid mirror;
  std::vector<std::size_t> changed;
  EXPECT_FALSE(ch.sync_tooth(&mirror, &changed)) << "nothing before tick 0";
  ch.on_tick(view_of(0, &tooth));
  ASSERT_TRUE(ch.sync_tooth(&mirror, &changed));
  EXPECT_EQ(mirror.voxels, tooth.voxels);
  EXPECT_EQ(mirror.origin, tooth.origin);

  // The writer removes every solid voxel, in flat order, 3 per tick, listing them as touched
  // (plus an untouched-by-drilling solid neighbour, which must not be copied as removed).
  std::vector<std::size_t> solid;
  for (std::size_t i = 0; i < tooth.voxels.size(); ++i) {
    if (tooth.voxels[i] != 0) solid.push_back(i);
  }
  std::atomic<bool> done{false};
  std::set<std::size_t> seen_changed;
  std::thread reader([&] {
    VoxelGrid g = mirror;
    std::vector<std::size_t> c;
    while (!done.load()) {
      ch.sync_tooth(&g, &c);
      seen_changed.insert(c.begin(), c.end());
    }
    ch.sync_tooth(&g, &c);
    seen_changed.insert(c.begin(), c.end());
    mirror = g;
  });
  long k = 1;
  for (std::size_t a = 0; a < solid.size(); a += 3, ++k) {
    std::vector<std::size_t> touched;
    for (std::size_t b = a; b < std::min(a + 3, solid.size()); ++b) {
      tooth.voxels[solid[b]] = 0;
      touched.push_back(solid[b]);
    }
    if (a + 3 < solid.size()) touched.push_back(solid[a + 3]);
    TickSnapshotView v = view_of(k, &tooth);
    v.touched_voxels = touched;
    ch.on_tick(v);
  }
  done.store(true);
  reader.join();
  EXPECT_EQ(mirror.voxels, tooth.voxels);
  EXPECT_EQ(seen_changed, std::set<std::size_t>(solid.begin(), solid.end()));
}

// An observer that stalls the render side: it publishes through a real SnapshotChannel while a
// reader thread takes snapshots and sleeps 20 ms per frame (a renderer at 50 Hz that is slow).
TEST(SnapshotChannel, StalledRendererDoesNotChangeASingleTick) {
  Scene scene = load_scene("drill");
  RunOptions plain;
  plain.duration_override = 1.8;  // past t = 1.5 s: the bur is in the enamel, drilling
  const RunResult a = run_scene(scene, plain);

  SnapshotChannel ch(scene.tooth.resolution);
  std::atomic<bool> done{false};
  long frames = 0;
  VoxelGrid g;  // the renderer's copy of the tooth (the channel has one reader)
  std::vector<std::size_t> c;
  std::thread renderer([&] {
    TickSnapshot s;
    while (!done.load()) {
      ch.latest(&s);
      ch.sync_tooth(&g, &c);
      ++frames;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });
  RunOptions observed = plain;
  observed.observer = &ch;
  const RunResult b = run_scene(scene, observed);
  done.store(true);
  renderer.join();

  ASSERT_GT(a.removed_volume_total_mm3, 0.0) << "the run must drill to exercise the tooth path";
  EXPECT_GT(frames, 0);
  EXPECT_EQ(ch.ticks_published(), b.ticks);
  EXPECT_EQ(a.ticks, b.ticks);
  EXPECT_EQ(a.contact_ticks, b.contact_ticks);
  EXPECT_EQ(a.removed_volume_mm3, b.removed_volume_mm3);
  EXPECT_EQ(a.max_contact_force_n, b.max_contact_force_n);
  EXPECT_EQ(a.rendered_stiffness_n_per_m, b.rendered_stiffness_n_per_m);
  EXPECT_EQ(a.virtual_energy_generated_j, b.virtual_energy_generated_j);
  EXPECT_EQ(a.hand_work_j, b.hand_work_j);
  EXPECT_EQ(a.faults, b.faults);
  EXPECT_EQ(a.tooth_after.unpack().voxels, b.tooth_after.unpack().voxels);
  ASSERT_EQ(a.series.size(), b.series.size());
  for (std::size_t i = 0; i < a.series.size(); ++i) {
    const RunSample& x = a.series[i];
    const RunSample& y = b.series[i];
    ASSERT_EQ(x.t, y.t);
    ASSERT_EQ(x.contact_force_n, y.contact_force_n) << "tick " << i;
    ASSERT_EQ(x.device_force_n, y.device_force_n) << "tick " << i;
    ASSERT_EQ(x.proxy_x, y.proxy_x) << "tick " << i;
    ASSERT_EQ(x.device_x, y.device_x) << "tick " << i;
    ASSERT_EQ(x.observer_force_n, y.observer_force_n) << "tick " << i;
    ASSERT_EQ(x.contacts, y.contacts) << "tick " << i;
  }
  // The reader's final copy of the tooth is the run's.
  TickSnapshot last;
  ch.latest(&last);
  ch.sync_tooth(&g, &c);
  EXPECT_EQ(g.voxels, b.tooth_after.unpack().voxels);
  EXPECT_EQ(last.tick, b.ticks - 1);
  EXPECT_EQ(last.removed_volume_mm3, b.removed_volume_mm3);
}

}  // namespace
}  // namespace dentsim::view
