#include "reference/tooth/voxel_work.h"

#include <algorithm>

namespace dentsim {

void VoxelWorkTable::reserve(std::size_t capacity) {
  std::size_t slots = 16;
  while (slots < 2 * capacity) slots *= 2;
  keys_.assign(slots, kEmptyKey);
  work_.assign(slots, 0.0);
  mask_ = slots - 1;
  size_ = 0;
  capacity_ = std::min(capacity, slots / 2);
}

std::size_t VoxelWorkTable::slot_of(std::size_t v) const {
  // Fibonacci hashing: neighbouring voxels land in spread-out slots.
  const std::uint64_t x = static_cast<std::uint64_t>(v) * 0x9E3779B97F4A7C15ull;
  return static_cast<std::size_t>(x ^ (x >> 29)) & mask_;
}

double VoxelWorkTable::get(std::size_t v) const {
  if (keys_.empty()) return 0.0;
  const Key key = static_cast<Key>(v);
  for (std::size_t s = slot_of(v);; s = (s + 1) & mask_) {
    if (keys_[s] == key) return work_[s];
    if (keys_[s] == kEmptyKey) return 0.0;
  }
}

bool VoxelWorkTable::add(std::size_t v, double w) {
  if (keys_.empty()) return false;
  const Key key = static_cast<Key>(v);
  std::size_t s = slot_of(v);
  for (; keys_[s] != kEmptyKey; s = (s + 1) & mask_) {
    if (keys_[s] == key) {
      work_[s] += w;
      return true;
    }
  }
  if (size_ >= capacity_) return false;
  keys_[s] = key;
  work_[s] = 0.0 + w;  // the dense store's 0.0 + w, bit for bit
  ++size_;
  return true;
}

void VoxelWorkTable::erase(std::size_t v) {
  if (keys_.empty()) return;
  const Key key = static_cast<Key>(v);
  std::size_t s = slot_of(v);
  for (; keys_[s] != key; s = (s + 1) & mask_) {
    if (keys_[s] == kEmptyKey) return;
  }
  // Backward-shift deletion: move later members of the probe run into the hole when their home
  // slot does not lie cyclically in (hole, their slot].
  std::size_t hole = s;
  for (std::size_t t = (hole + 1) & mask_; keys_[t] != kEmptyKey; t = (t + 1) & mask_) {
    const std::size_t home = slot_of(keys_[t]);
    const bool stays = hole <= t ? (hole < home && home <= t) : (hole < home || home <= t);
    if (stays) continue;
    keys_[hole] = keys_[t];
    work_[hole] = work_[t];
    hole = t;
  }
  keys_[hole] = kEmptyKey;
  work_[hole] = 0.0;
  --size_;
}

double VoxelWorkTable::total() const {
  double sum = 0.0;
  for_each([&sum](std::size_t, double w) { sum += w; });
  return sum;
}

}  // namespace dentsim
