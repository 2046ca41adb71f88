// Tests of view/live_tooth.h (issue #30: the live view meshes the field the tool touches): on the
// drill scene with the contact model "field", a reader that follows the run through a
// SnapshotChannel frame by frame, as the window does, ends with a field equal to the run's
// field_after sample by sample and a mesh equal to the pictures' after-mesh (view/pictures.h:
// a SurfaceMesher of tooth_after and field_after) bit for bit, whole and cut away; so does a
// reader that reads the tooth once, after the run (every removal in one edit). The reader's
// edits change nothing in the run. Without the field model the reader meshes the voxels as before.
#include "view/live_tooth.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <thread>

#include "sim/simulator.h"
#include "tooth_io/tooth_source.h"

namespace dentsim::view {
namespace {

// Forwards the run to two observers (each channel has one reader). From tick 1000 (before the
// drill scene cuts, at 1.5 s) it waits every 100th tick until the reader has drawn another frame
// (`frames` moved): however loaded the machine, the reader is set up before the cutting and
// follows it over many frames (the run's results do not depend on its pace: not paced).
class FanOut : public TickObserver {
 public:
  FanOut(TickObserver* a, TickObserver* b, const std::atomic<long>* frames)
      : a_(a), b_(b), frames_(frames) {}
  void on_start(const RunStartView& s) override {
    a_->on_start(s);
    b_->on_start(s);
  }
  void on_tick(const TickSnapshotView& t) override {
    a_->on_tick(t);
    b_->on_tick(t);
    if (t.tick < 1000 || t.tick % 100 != 0) return;
    const long seen = frames_->load();
    while (frames_->load() == seen) std::this_thread::sleep_for(std::chrono::microseconds(100));
  }

 private:
  TickObserver* a_;
  TickObserver* b_;
  const std::atomic<long>* frames_;
};

// Samples of `a` that differ from `b`'s (bit patterns; both on the same lattice).
long differing_samples(const SampledField& a, const SampledField& b) {
  EXPECT_EQ(a.samples_per_axis(), b.samples_per_axis());
  EXPECT_EQ(a.stride(), b.stride());
  EXPECT_EQ(a.sample_position(0, 0, 0), b.sample_position(0, 0, 0));
  const int m = std::min(a.samples_per_axis(), b.samples_per_axis());
  long differ = 0;
  for (int z = 0; z < m; ++z) {
    for (int y = 0; y < m; ++y) {
      for (int x = 0; x < m; ++x) {
        const float u = a.at(x, y, z), v = b.at(x, y, z);
        differ += std::memcmp(&u, &v, sizeof u) != 0;
      }
    }
  }
  return differ;
}

// Blocks whose meshes differ (vertex count, positions, normals, materials or triangles).
int differing_blocks(const SurfaceMesher& a, const SurfaceMesher& b) {
  EXPECT_EQ(a.blocks().size(), b.blocks().size());
  int differ = 0;
  for (std::size_t i = 0; i < std::min(a.blocks().size(), b.blocks().size()); ++i) {
    const BlockMesh& x = a.blocks()[i];
    const BlockMesh& y = b.blocks()[i];
    // An empty block's data() may be null, which memcmp must not get (UBSan), even for 0 bytes.
    const bool same = x.vertices.size() == y.vertices.size() && x.indices == y.indices &&
                      (x.vertices.empty() ||
                       std::memcmp(x.vertices.data(), y.vertices.data(),
                                   x.vertices.size() * sizeof(MeshVertex)) == 0);
    differ += !same;
  }
  return differ;
}

// Runs `scene` on a thread with `observer` (which feeds `channel`) while `live` reads `channel`
// every `frame_ms` (as the window does), then once more after the run (the window's last frame).
RunResult run_followed(const Scene& scene, RunOptions options, TickObserver* observer,
                       SnapshotChannel& channel, LiveTooth& live, int frame_ms,
                       std::atomic<long>* frames = nullptr) {
  options.observer = observer;
  std::atomic<bool> done{false};
  RunResult r;
  std::thread servo([&] {
    r = run_scene(scene, options);
    done.store(true, std::memory_order_release);
  });
  while (!done.load(std::memory_order_acquire)) {
    live.sync(channel);
    if (frames != nullptr) frames->fetch_add(1);
    std::this_thread::sleep_for(std::chrono::milliseconds(frame_ms));
  }
  servo.join();
  live.sync(channel);
  return r;
}

struct FieldRun {
  RunResult result;
  long frames_with_removal = 0;  // the live reader's
  long voxels = 0;
  long samples_lost = 0;
};

// The drill scene with the field model (`patch` merged into it), observed by a live reader (a
// frame every `frame_ms`, as the window) and by a reader that reads once after the run; both
// compared with the run's field_after and the pictures' after-mesh.
FieldRun check_live_field(const nlohmann::json& patch, int frame_ms) {
  const Scene scene = load_scene_patched("drill", patch, "live tooth test");
  SnapshotChannel live_channel(scene.tooth.resolution), late_channel(scene.tooth.resolution);
  std::atomic<long> frames{0};
  FanOut both(&live_channel, &late_channel, &frames);
  RunOptions options;
  options.pipeline = "fast";  // `dentsim run`'s default
  FieldRun out;
  LiveTooth live;
  out.result = run_followed(scene, options, &both, live_channel, live, frame_ms, &frames);
  LiveTooth late;
  EXPECT_TRUE(late.sync(late_channel));
  const RunResult& r = out.result;
  out.frames_with_removal = live.stats().frames_with_removal;
  out.voxels = live.stats().voxels;
  out.samples_lost = live.stats().field.samples_lost;
  std::printf(
      "live reader: %ld frames, %ld with removed voxels, %ld voxels, %ld blocks "
      "re-meshed; CPU: edit %.1f ms, re-mesh %.1f ms in all, %.2f ms at most in a frame\n",
      live.stats().frames, live.stats().frames_with_removal, live.stats().voxels,
      live.stats().blocks, 1e3 * live.stats().edit_s, 1e3 * live.stats().mesh_s,
      1e3 * live.stats().frame_max_s);

  if (r.field_before == nullptr || r.field_after == nullptr) {
    ADD_FAILURE() << "the field model's run has no field";
    return out;
  }
  EXPECT_NE(r.field_before, r.field_after) << "the run must drill (field_after is its own)";
  const VoxelGrid after = r.tooth_after.unpack();
  for (const LiveTooth* t : {&live, &late}) {
    EXPECT_TRUE(t->ready());
    if (!t->ready() || t->field() == nullptr) {
      ADD_FAILURE() << "no field surface";
      continue;
    }
    EXPECT_EQ(t->grid().voxels, after.voxels);
    EXPECT_EQ(differing_samples(*t->field(), *r.field_after), 0);
  }
  // The edit did something: many samples rose, and the after-mesh differs from the before-mesh.
  const long edited = differing_samples(*r.field_before, *r.field_after);
  std::printf("samples the run's drilling edited: %ld\n", edited);
  EXPECT_GT(edited, 100);
  const SurfaceMesher before_mesh(r.tooth_before.unpack(), r.field_before.get());
  const SurfaceMesher after_mesh(after, r.field_after.get());  // the pictures' (render_offscreen)
  const int changed_blocks = differing_blocks(before_mesh, after_mesh);
  std::printf("blocks the drilling changed: %d\n", changed_blocks);
  EXPECT_GT(changed_blocks, 2);
  EXPECT_EQ(differing_blocks(live.mesher(), after_mesh), 0);
  EXPECT_EQ(differing_blocks(late.mesher(), after_mesh), 0);
  EXPECT_EQ(live.mesher().triangle_count(), after_mesh.triangle_count());
  // Cut away (key C; the pictures' right panel): the same.
  const CutAway cut = centre_cut(after);
  live.mesher().set_cut(cut);
  EXPECT_EQ(differing_blocks(live.mesher(), SurfaceMesher(after, r.field_after.get(),
                                                          SurfaceMesher::kDefaultBlockSize, cut)),
            0);
  return out;
}

// At 128^3 the 0.5 mm bur's field has one sample per voxel (stride 1); the reader draws a frame
// every 2 ms and at least one every 100 ticks of the cutting (FanOut), so each frame holds the
// removals of up to 100 ticks.
TEST(LiveToothField, FollowsTheRunsFieldOnTheDrillScene) {
  const FieldRun run = check_live_field({{"tooth", {{"contact_model", "field"}}}}, 2);
  EXPECT_GT(run.frames_with_removal, 5) << "several frames must carry removals";
  EXPECT_GT(run.voxels, 0);
  EXPECT_EQ(run.samples_lost, 0);
}

// At stride 2 (a field sample every other voxel centre: field_spacing 2 h) the edit batches the
// voxels of one coarse cell, and the mesh reads the interpolated field.
TEST(LiveToothField, FollowsTheRunsFieldAtStride2) {
  const Scene scene = load_scene_patched("drill", {{"tooth", {{"contact_model", "field"}}}}, "");
  const double h_mm = 1e3 * build_tooth_grid_cached(tooth_source(scene.tooth)).voxel_size;
  const FieldRun run = check_live_field(
      {{"tooth", {{"contact_model", "field"}, {"field_spacing_mm", 2.0 * h_mm}}}}, 2);
  ASSERT_NE(run.result.field_after, nullptr);
  EXPECT_EQ(run.result.field_after->stride(), 2);
  EXPECT_GT(run.frames_with_removal, 5);
  EXPECT_EQ(run.samples_lost, 0);
}

// The reader's edits stay on its thread: the run with it is the run without it, tick for tick.
TEST(LiveToothField, TheReaderChangesNothingInTheRun) {
  const Scene scene = load_scene_patched("drill", {{"tooth", {{"contact_model", "field"}}}}, "");
  RunOptions plain;
  plain.pipeline = "fast";
  plain.duration_override = 2.5;  // a second of drilling
  const RunResult a = run_scene(scene, plain);
  SnapshotChannel channel(scene.tooth.resolution);
  LiveTooth live;
  const RunResult b = run_followed(scene, plain, &channel, channel, live, 5);
  ASSERT_GT(a.removed_volume_total_mm3, 0.0);
  EXPECT_EQ(a.removed_volume_mm3, b.removed_volume_mm3);
  EXPECT_EQ(a.tooth_after.unpack().voxels, b.tooth_after.unpack().voxels);
  ASSERT_NE(a.field_after, nullptr);
  ASSERT_NE(b.field_after, nullptr);
  EXPECT_EQ(differing_samples(*a.field_after, *b.field_after), 0);
  ASSERT_EQ(a.series.size(), b.series.size());
  for (std::size_t i = 0; i < a.series.size(); ++i) {
    ASSERT_EQ(a.series[i].device_force, b.series[i].device_force) << "tick " << i;
    ASSERT_EQ(a.series[i].proxy_x, b.series[i].proxy_x) << "tick " << i;
  }
}

// Without the field model nothing changes: the reader meshes the voxels (no field), and its
// mesh after the run is the voxel mesh of the tooth after.
TEST(LiveToothVoxels, MeshesTheVoxelsWithoutTheFieldModel) {
  const Scene scene = load_scene("drill");
  SnapshotChannel channel(scene.tooth.resolution);
  RunOptions options;
  options.pipeline = "fast";
  options.duration_override = 2.0;
  LiveTooth live;
  const RunResult r = run_followed(scene, options, &channel, channel, live, 5);
  ASSERT_TRUE(live.ready());
  EXPECT_EQ(live.field(), nullptr);
  EXPECT_EQ(channel.field_before(), nullptr);
  ASSERT_GT(r.removed_volume_total_mm3, 0.0);
  const VoxelGrid after = r.tooth_after.unpack();
  EXPECT_EQ(live.grid().voxels, after.voxels);
  EXPECT_EQ(differing_blocks(live.mesher(), SurfaceMesher(after)), 0);
}

}  // namespace
}  // namespace dentsim::view
