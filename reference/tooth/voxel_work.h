// The drilling work per voxel, stored only where it is non-zero (issue #30): an open-addressing
// hash table (flat voxel index -> accumulated work [J]) with linear probing and backward-shift
// deletion, allocated once at setup and never grown. It replaces a dense double per voxel of the
// whole grid (1 GB at 512^3): work lives only on the voxels the bur has touched and not yet removed.
//
// Capacity: set at setup (make_drill_state: from the tooth's surface voxel count, the voxels a bur
// can reach first; docs/derivations/drilling.md "Storage"). The table holds at most `capacity()`
// entries in 2^k >= 2 capacity slots (load <= 1/2, so a probe ends within a few slots). Nothing
// here allocates after reserve() and nothing throws; a full table is a status the caller reports
// (DrillState::work_table_full -> TickStatus::kDrillWorkTableFull, a named fault).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace dentsim {

class VoxelWorkTable {
 public:
  VoxelWorkTable() = default;
  // Room for `capacity` entries (allocates; setup only). Clears the table.
  void reserve(std::size_t capacity);

  // Work on voxel v [J]; 0 when v holds none.
  double get(std::size_t v) const;
  // Adds w to voxel v's work (v < 2^32 - 1). Returns false (adding nothing) when v holds no entry
  // and the table already holds capacity() entries.
  bool add(std::size_t v, double w);
  // Forgets voxel v's work (its entry, if any).
  void erase(std::size_t v);
  // Whether `count` new entries fit.
  bool has_room(std::size_t count) const { return size_ + count <= capacity_; }

  std::size_t size() const { return size_; }
  std::size_t capacity() const { return capacity_; }
  // Bytes of the table's storage.
  std::size_t bytes() const { return keys_.capacity() * (sizeof(Key) + sizeof(double)); }
  // Sum of the stored work [J] (tests and reports; walks every slot).
  double total() const;
  // Calls f(v, work) for every entry, in slot order.
  template <class F>
  void for_each(F&& f) const {
    for (std::size_t s = 0; s < keys_.size(); ++s) {
      if (keys_[s] != kEmptyKey) f(static_cast<std::size_t>(keys_[s]), work_[s]);
    }
  }

 private:
  // A flat voxel index in 32 bits (12 bytes a slot, not 16): a grid has at most 1024^3 = 2^30
  // voxels (FullOctree's limit), so every index fits below kEmptyKey.
  using Key = std::uint32_t;
  static constexpr Key kEmptyKey = ~Key{0};
  std::size_t slot_of(std::size_t v) const;  // home slot (a multiplicative hash)
  std::vector<Key> keys_;                    // flat voxel index, or kEmptyKey
  std::vector<double> work_;
  std::size_t mask_ = 0;
  std::size_t size_ = 0;
  std::size_t capacity_ = 0;
};

}  // namespace dentsim
