#include "view/snapshot.h"

#include <algorithm>
#include <cmath>

namespace dentsim::view {

SnapshotChannel::SnapshotChannel(int resolution)
    : n_(resolution), nb_((resolution + kBlock - 1) / kBlock) {
  const std::size_t n3 = static_cast<std::size_t>(n_) * n_ * n_;
  shadow_ = std::make_unique<std::atomic<std::uint8_t>[]>(n3);
  const std::size_t nblocks = static_cast<std::size_t>(nb_) * nb_ * nb_;
  generation_ = std::make_unique<std::atomic<std::uint32_t>[]>(nblocks);
  seen_generation_.assign(nblocks, 0);
  histogram_ = std::make_unique<std::atomic<std::uint32_t>[]>(kBins);
}

void SnapshotChannel::on_start(const RunStartView& start) {
  if (start.field == nullptr || start.tooth_before == nullptr) return;
  field_before_ = start.field;
  tooth_before_ = *start.tooth_before;
}

void SnapshotChannel::on_tick(const TickSnapshotView& v) {
  TickSnapshot& s = slots_[back_];
  s.tick = v.tick;
  s.t = v.t;
  s.device = v.device;
  s.proxy = v.proxy;
  s.tool_radius_m = v.tool_radius_m;
  s.contact_force_n = v.contact_force_n;
  s.device_force_n = v.device_force_n;
  s.contacts = v.contacts;
  s.max_depth_m = v.max_depth_m;
  s.tick_us = v.tick_us;
  s.removed_volume_mm3 = v.removed_volume_mm3;
  s.faults = v.faults;
  if (v.tick == 0) device_R0_ = v.device.R;
  s.device_R0 = device_R0_;
  back_ = middle_.exchange(static_cast<std::uint8_t>(back_ | kFresh), std::memory_order_acq_rel) &
          static_cast<std::uint8_t>(~kFresh);

  const int bin = std::clamp(static_cast<int>(v.tick_us / kBinUs), 0, kBins - 1);
  histogram_[bin].fetch_add(1, std::memory_order_relaxed);

  if (v.tooth != nullptr && !mismatch_.load(std::memory_order_relaxed)) {
    const VoxelGrid& g = *v.tooth;
    if (!tooth_ready_.load(std::memory_order_relaxed)) {
      if (g.n != n_) {
        mismatch_.store(true, std::memory_order_release);
      } else {
        for (std::size_t i = 0; i < g.voxels.size(); ++i) {
          shadow_[i].store(g.voxels[i], std::memory_order_relaxed);
        }
        origin_ = g.origin;
        h_ = g.voxel_size;
        tooth_ready_.store(true, std::memory_order_release);
      }
    } else {
      const std::size_t n = static_cast<std::size_t>(n_);
      for (std::size_t idx : v.touched_voxels) {
        if (idx >= g.voxels.size()) continue;
        const std::uint8_t m = g.voxels[idx];
        if (shadow_[idx].load(std::memory_order_relaxed) == m) continue;
        shadow_[idx].store(m, std::memory_order_relaxed);
        const std::size_t i = idx % n, j = (idx / n) % n, k = idx / (n * n);
        const std::size_t b = i / kBlock + nb_ * (j / kBlock + nb_ * (k / kBlock));
        generation_[b].fetch_add(1, std::memory_order_release);
      }
    }
  }
  published_.fetch_add(1, std::memory_order_release);
}

bool SnapshotChannel::latest(TickSnapshot* out) {
  if ((middle_.load(std::memory_order_acquire) & kFresh) == 0) {
    *out = slots_[front_];
    return false;
  }
  front_ = middle_.exchange(front_, std::memory_order_acq_rel) & static_cast<std::uint8_t>(~kFresh);
  *out = slots_[front_];
  return true;
}

bool SnapshotChannel::sync_tooth(VoxelGrid* grid, std::vector<std::size_t>* changed) {
  changed->clear();
  if (!tooth_ready_.load(std::memory_order_acquire)) return false;
  const std::size_t n = static_cast<std::size_t>(n_);
  if (!reader_has_tooth_) {
    *grid = VoxelGrid(n_, origin_, h_);
    for (std::size_t b = 0; b < seen_generation_.size(); ++b) {
      seen_generation_[b] = generation_[b].load(std::memory_order_acquire);
    }
    for (std::size_t i = 0; i < grid->voxels.size(); ++i) {
      grid->voxels[i] = shadow_[i].load(std::memory_order_relaxed);
    }
    reader_has_tooth_ = true;
    return true;
  }
  for (int b = 0; b < static_cast<int>(seen_generation_.size()); ++b) {
    const std::uint32_t g = generation_[b].load(std::memory_order_acquire);
    if (g == seen_generation_[b]) continue;
    seen_generation_[b] = g;
    const int bi = b % nb_, bj = (b / nb_) % nb_, bk = b / (nb_ * nb_);
    for (int k = bk * kBlock; k < std::min(n_, (bk + 1) * kBlock); ++k) {
      for (int j = bj * kBlock; j < std::min(n_, (bj + 1) * kBlock); ++j) {
        for (int i = bi * kBlock; i < std::min(n_, (bi + 1) * kBlock); ++i) {
          const std::size_t idx = i + n * (j + n * k);
          const std::uint8_t m = shadow_[idx].load(std::memory_order_relaxed);
          if (grid->voxels[idx] != m) {
            grid->voxels[idx] = m;
            changed->push_back(idx);
          }
        }
      }
    }
  }
  return true;
}

void SnapshotChannel::tick_time_stats(double* median_us, double* p99_us) const {
  std::uint64_t total = 0;
  for (int b = 0; b < kBins; ++b) total += histogram_[b].load(std::memory_order_relaxed);
  *median_us = *p99_us = 0.0;
  if (total == 0) return;
  std::uint64_t acc = 0;
  bool have_median = false;
  for (int b = 0; b < kBins; ++b) {
    acc += histogram_[b].load(std::memory_order_relaxed);
    if (!have_median && 2 * acc >= total) {
      *median_us = (b + 0.5) * kBinUs;
      have_median = true;
    }
    if (100 * acc >= 99 * total) {
      *p99_us = (b + 0.5) * kBinUs;
      return;
    }
  }
}

}  // namespace dentsim::view
