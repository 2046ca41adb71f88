#include "view/live_tooth.h"

#include <algorithm>
#include <ctime>

#include "reference/core/io.h"
#include "reference/tooth/neighbors.h"
#include "reference/tooth/sdf.h"

namespace dentsim::view {

namespace {

// This thread's CPU time [s] (not the wall clock: the machine may be shared).
// Calls f(x, y, z) for every sample of the brick slots `slots` (ns slots per axis), in order.
template <class F>
void for_each_slot_sample(const std::vector<int>& slots, int ns, F f) {
  for (const int slot : slots) {
    const int x0 = kFieldBrick * (slot % ns), y0 = kFieldBrick * ((slot / ns) % ns),
              z0 = kFieldBrick * (slot / (ns * ns));
    for (int z = z0; z < z0 + kFieldBrick; ++z) {
      for (int y = y0; y < y0 + kFieldBrick; ++y) {
        for (int x = x0; x < x0 + kFieldBrick; ++x) f(x, y, z);
      }
    }
  }
}

double thread_seconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

}  // namespace

LiveTooth::LiveTooth(int block_size) : block_size_(block_size) {}

bool LiveTooth::sync(SnapshotChannel& channel, bool cutaway) {
  if (!channel.sync_tooth(&grid_, &changed_)) return false;
  if (!mesher_) {
    const double t0 = thread_seconds();
    // The first read: the whole tooth as it is now. With a field, the field and the tooth it was
    // built on are the ones before the first tick: the voxels removed since are subtracted first.
    if (channel.field_before() != nullptr) {
      VoxelGrid before = channel.tooth_before().unpack();
      if (before.n != grid_.n || before.voxels.size() != grid_.voxels.size()) {
        throw InputError("view: the field's tooth is " + std::to_string(before.n) +
                         "^3 but the published tooth " + std::to_string(grid_.n) + "^3");
      }
      field_ = std::make_unique<SampledField>(*channel.field_before());
      // The servo's provider's spare room (reference/tooth/tooth_contacts.cc); edit_field tops
      // it up before each frame's edit.
      field_->reserve_spare_bricks(std::max<std::size_t>(256, field_->brick_count() / 2));
      tooth_ = std::make_unique<VoxelTooth>(std::move(before));
      removed_.clear();
      for (std::size_t v = 0; v < grid_.voxels.size(); ++v) {
        if (tooth_->grid().voxels[v] != kEmpty && grid_.voxels[v] == kEmpty) removed_.push_back(v);
      }
      if (!removed_.empty()) edit_field();
    }
    mesher_.emplace(grid_, field_.get(), block_size_, cutaway ? centre_cut(grid_) : CutAway{});
    stats_.setup_s = thread_seconds() - t0;
    return true;
  }
  ++stats_.frames;
  if (changed_.empty()) return false;
  ++stats_.frames_with_removal;
  double edit_s = 0.0;
  if (field_ != nullptr) {
    const double t0 = thread_seconds();
    removed_.clear();
    for (const std::size_t v : changed_) {  // voxels only go from solid to empty
      if (grid_.voxels[v] == kEmpty && tooth_->grid().voxels[v] != kEmpty) removed_.push_back(v);
    }
    if (!removed_.empty()) edit_field();
    edit_s = thread_seconds() - t0;
  } else {
    stats_.voxels += static_cast<long>(changed_.size());
  }
  const double t1 = thread_seconds();
  const std::vector<int> blocks = field_ != nullptr ? mesher_->update(grid_, changed_, samples_)
                                                    : mesher_->update(grid_, changed_);
  stats_.blocks += static_cast<long>(blocks.size());
  samples_.clear();
  const double mesh_s = thread_seconds() - t1;
  stats_.edit_s += edit_s;
  stats_.mesh_s += mesh_s;
  stats_.frame_max_s = std::max(stats_.frame_max_s, edit_s + mesh_s);
  return true;
}

void LiveTooth::edit_field() {
  const VoxelGrid& g = tooth_->grid();
  const std::size_t n = static_cast<std::size_t>(g.n);
  std::vector<std::size_t>& order = removed_;
  for (const std::size_t v : order) {  // as drill_tick removes them (reference/tooth/drilling.cc)
    const int i = static_cast<int>(v % n), j = static_cast<int>((v / n) % n),
              k = static_cast<int>(v / (n * n));
    tooth_->octree.remove_voxel(i, j, k);
    reencode_local(tooth_->octree.grid(), i, j, k, &tooth_->codes);
  }
  // At stride k > 1 the edit subtracts consecutive voxels of one coarse cell floor(c / k)
  // together (reference/tooth/field_edit_core.h): in that cell's order, as the servo's provider
  // queues them. The order changes no value (live_tooth.h), only the work.
  const int stride = field_->stride();
  if (stride > 1) {
    const std::size_t kk = static_cast<std::size_t>(stride), nk = n / kk + 1;
    const auto key = [n, nk, kk](std::size_t v) {
      return (v % n) / kk + nk * (((v / n) % n) / kk + nk * ((v / (n * n)) / kk));
    };
    std::stable_sort(order.begin(), order.end(),
                     [&key](std::size_t a, std::size_t b) { return key(a) < key(b); });
  }
  // Room for every brick the edit may open: a voxel's box of 2R + 1 samples per axis meets at
  // most ceil((2R + 1) / 8) + 1 brick slots per axis, and no more slots than the lattice has.
  const std::size_t per_axis =
      static_cast<std::size_t>((2 * field_->edit_radius() + 1 + kFieldBrick - 1) / kFieldBrick + 1);
  const std::size_t slots_per_axis =
      static_cast<std::size_t>(field_->samples_per_axis() / kFieldBrick);
  const std::size_t slots = slots_per_axis * slots_per_axis * slots_per_axis;
  const std::size_t need = std::min(order.size() * per_axis * per_axis * per_axis,
                                    slots - std::min(slots, field_->brick_count()));
  if (field_->spare_bricks() < need) {
    field_->reserve_spare_bricks(std::max(need, field_->brick_count() / 2));
  }
  // The samples the edit changes, for the mesher (SurfaceMesher::update with samples): the
  // edit writes only within R samples of each voxel's box centre floor(c / k) + P
  // (reference/tooth/field_contact.h), so the brick slots meeting those boxes are read before
  // and after it (slots all outside never change: skipped).
  const bool diff = mesher_.has_value();
  if (diff) read_edit_slots();
  edit_field_for_removed_voxels(field_.get(), *tooth_, order, &signed_distance, &stats_.field);
  stats_.voxels += static_cast<long>(order.size());
  samples_.clear();
  if (diff) diff_edit_slots();
}

void LiveTooth::read_edit_slots() {
  const int k = field_->stride(), pad = field_->padding(), reach = field_->edit_radius();
  const int last = field_->samples_per_axis() - 1;
  const int ns = field_->samples_per_axis() / kFieldBrick;  // slots per axis
  const std::size_t n = static_cast<std::size_t>(grid_.n);
  slots_.clear();
  for (const std::size_t v : removed_) {
    const int c[3] = {static_cast<int>(v % n), static_cast<int>((v / n) % n),
                      static_cast<int>(v / (n * n))};
    int lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      const int centre = c[a] / k + pad;  // c >= 0: floor
      lo[a] = std::clamp(centre - reach, 0, last) / kFieldBrick;
      hi[a] = std::clamp(centre + reach, 0, last) / kFieldBrick;
    }
    for (int z = lo[2]; z <= hi[2]; ++z) {
      for (int y = lo[1]; y <= hi[1]; ++y) {
        for (int x = lo[0]; x <= hi[0]; ++x) slots_.push_back(x + ns * (y + ns * z));
      }
    }
  }
  std::sort(slots_.begin(), slots_.end());
  slots_.erase(std::unique(slots_.begin(), slots_.end()), slots_.end());
  // Drop the slots all outside (their samples hold c_out, the most an edit can write).
  std::erase_if(slots_, [&](int slot) {
    const int lo[3] = {kFieldBrick * (slot % ns), kFieldBrick * ((slot / ns) % ns),
                       kFieldBrick * (slot / (ns * ns))};
    const int hi[3] = {lo[0] + kFieldBrick - 1, lo[1] + kFieldBrick - 1, lo[2] + kFieldBrick - 1};
    return field_->all_outside(lo, hi);
  });
  slot_samples_.resize(slots_.size() * static_cast<std::size_t>(SampledField::kBrickSamples));
  std::size_t at = 0;
  for_each_slot_sample(slots_, ns,
                       [&](int x, int y, int z) { slot_samples_[at++] = field_->at(x, y, z); });
}

void LiveTooth::diff_edit_slots() {
  std::size_t at = 0;
  // Values only rise (SampledField::raise): a changed sample compares greater.
  for_each_slot_sample(slots_, field_->samples_per_axis() / kFieldBrick, [&](int x, int y, int z) {
    if (field_->at(x, y, z) != slot_samples_[at++]) samples_.push_back({x, y, z});
  });
}

}  // namespace dentsim::view
