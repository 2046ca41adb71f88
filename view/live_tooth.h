// The tooth the live window draws (view/gl/window.cc; issue #19, issue #30), GL-free so that it
// is tested without a display (tests/view/live_tooth_test.cc).
//
// Each frame, sync() takes the voxels the servo's drilling removed since the last frame from the
// SnapshotChannel (view/snapshot.h: the blocks whose generation moved) and re-meshes the surface
// blocks they affect (view/surface_mesh.h). With the contact model "field" the surface is the
// zero level of the tooth's sampled field, the surface the tool touches, as in the pictures
// (view/pictures.h): this thread keeps its own copy of the field (copied from the channel's
// field_before at the first sync, outside the servo loop) and its own drillable voxel tooth
// (VoxelTooth: the octree the edit's distance queries read), removes each frame's voxels from
// that tooth and subtracts them from its field with the reference's drilling edit
// (reference/tooth/field_contact.h edit_field_for_removed_voxels, unbudgeted: all of the
// frame's voxels), reads which samples the edit changed (the brick slots within the edit's
// radius, before and after) and SurfaceMesher::update re-meshes only the blocks that read
// those samples or the removed voxels. Nothing is shared with the servo thread beyond what the
// channel hands over; the servo's tick does nothing more than it did.
//
// Why the copy ends equal to the servo's field, sample by sample, although the servo edits each
// tick's voxels (queued, with a budget of work per tick, fast or reference twin) against the
// tooth of that moment and this thread edits a frame's voxels together against the tooth of the
// frame: the edit only raises samples, an inside sample to -dist to the removed cube (exact, the
// same whenever it is applied), an outside one to the distance to the solid voxels left; a
// sample the servo edited at an earlier tooth and skips later (its test fails) is one whose
// nearest solid voxel the later removals did not take, so its distance did not change
// (docs/view.md "On the smooth tooth"). The test compares the two after the drill scene.
// The field may lead the servo's by the servo's edit latency (its queue and budget, or a worker
// thread): it follows the voxels' removal, not the servo's field object.
#pragma once

#include <array>
#include <cstddef>
#include <memory>
#include <optional>
#include <vector>

#include "reference/tooth/collision.h"
#include "reference/tooth/field_contact.h"
#include "reference/tooth/sampled_field.h"
#include "reference/tooth/voxel_grid.h"
#include "view/snapshot.h"
#include "view/surface_mesh.h"

namespace dentsim::view {

// What the frames' updates cost (this thread's CPU time; the viewer prints it at the end).
struct LiveToothStats {
  double setup_s = 0.0;          // the first sync: the copies, the first edit, the whole mesh
  long frames = 0;               // sync() calls after the first mesh
  long frames_with_removal = 0;  // of those, the ones that found removed voxels
  long voxels = 0;               // removed voxels applied
  long blocks = 0;               // surface blocks re-meshed
  // Per frame with removals [s]: the field's edit (the voxel tooth's removal included) and the
  // re-mesh of the dirty blocks; sums and the largest single frame's (edit + re-mesh).
  double edit_s = 0.0, mesh_s = 0.0, frame_max_s = 0.0;
  FieldEditStats field;  // the field edits' counters (field model)
};

class LiveTooth {
 public:
  explicit LiveTooth(int block_size = SurfaceMesher::kDefaultBlockSize);
  LiveTooth(const LiveTooth&) = delete;
  LiveTooth& operator=(const LiveTooth&) = delete;

  // Takes the newest tooth from `channel`: the first call after tick 0 copies the tooth (and, with
  // the field model, the field) and meshes it, with the centre cut-away when `cutaway`; later
  // calls apply the voxels removed since (the field edit, then the re-mesh). Returns true when
  // the mesh changed (built or re-meshed), false before the tooth is published or when nothing
  // was removed. Not on the servo thread: it allocates.
  bool sync(SnapshotChannel& channel, bool cutaway = false);

  bool ready() const { return mesher_.has_value(); }
  // Valid once ready().
  SurfaceMesher& mesher() { return *mesher_; }
  const SurfaceMesher& mesher() const { return *mesher_; }
  const VoxelGrid& grid() const { return grid_; }
  // This thread's field (contact model "field"), as edited so far; null for the other models.
  const SampledField* field() const { return field_.get(); }
  const LiveToothStats& stats() const { return stats_; }

 private:
  // Removes removed_ from the voxel tooth and subtracts them from the field (reorders them);
  // once the mesher exists, samples_ receives the samples the edit changed.
  void edit_field();
  // Before the edit: the brick slots of the field the edit of removed_ may write (slots_) and
  // their samples (slot_samples_). After it: the samples that changed (samples_).
  void read_edit_slots();
  void diff_edit_slots();

  int block_size_;
  VoxelGrid grid_;                       // the channel's tooth as last read
  std::vector<std::size_t> changed_;     // the voxels the last sync read as changed
  std::vector<std::size_t> removed_;     // scratch: this frame's removed voxels, edit order
  std::unique_ptr<SampledField> field_;  // field model: this thread's copy (the mesher reads it)
  std::unique_ptr<VoxelTooth> tooth_;    // field model: the voxels the edit's queries read
  std::vector<int> slots_;               // scratch: read_edit_slots()
  std::vector<float> slot_samples_;      // scratch: their samples before the edit
  std::vector<std::array<int, 3>> samples_;  // the samples the last edit changed
  std::optional<SurfaceMesher> mesher_;
  LiveToothStats stats_;
};

}  // namespace dentsim::view
