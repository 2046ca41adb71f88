// The drill log's storage is written before the run (ToothProviderBase::prefault_drill_log), so
// that the ticks that append records take no first-touch page fault (issue #30: one fault every
// 85 records, 10-20 us each on a virtual machine, was the drill stage's tail at 8 kHz).
#include <gtest/gtest.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <utility>
#include <vector>

#include "reference/tooth/tooth_contacts.h"

namespace dentsim {
namespace {

constexpr int kN = 32;
constexpr double kH = 0.1e-3;    // voxel edge [m]
constexpr double kRho = 0.4e-3;  // bur radius [m]
constexpr double kTop = 2.0e-3;  // the slab's top face [m]

// A slab of enamel below z = kTop.
VoxelTooth slab() {
  VoxelGrid g(kN, Vec3::Zero(), kH);
  for (int k = 0; k < kN; ++k) {
    for (int j = 0; j < kN; ++j) {
      for (int i = 0; i < kN; ++i) {
        if (g.center(i, j, k).z() < kTop) g.set(i, j, k, kEnamel);
      }
    }
  }
  return VoxelTooth(std::move(g));
}

// How many of the pages that hold [p, p + bytes) are resident (mincore), and how many there are.
std::pair<std::size_t, std::size_t> resident_pages(const void* p, std::size_t bytes) {
  const auto page = static_cast<std::uintptr_t>(sysconf(_SC_PAGESIZE));
  const auto first = reinterpret_cast<std::uintptr_t>(p) / page * page;
  const auto end = reinterpret_cast<std::uintptr_t>(p) + bytes;
  const std::size_t pages = (end - first + page - 1) / page;
  std::vector<unsigned char> in_core(pages);
  EXPECT_EQ(mincore(reinterpret_cast<void*>(first), end - first, in_core.data()), 0);
  std::size_t resident = 0;
  for (const unsigned char c : in_core) resident += c & 1u;
  return {resident, pages};
}

// The drill log of `ticks` ticks of a fast bur led down into the slab, the log prefaulted for
// `prefault` records first (0: not) and, with `prefault_after`, again after the ticks.
std::vector<DrillRecord> drill_into_slab(int ticks, std::size_t prefault, bool prefault_after) {
  VoxelTooth tooth = slab();
  DrillParams drill;
  drill.bur_speed_rad_s *= 20.0;
  ToothContactProvider provider(tooth, ToolTip{kRho, Vec3::Zero()}, 3000.0, 0.0, &drill,
                                ContactModel::kSurfaceProxy);
  if (prefault > 0) provider.prefault_drill_log(prefault);
  std::vector<Contact> out;
  out.reserve(kContactCapacity);
  Pose pose;
  for (int tick = 0; tick < ticks; ++tick) {
    pose.x = Vec3(1.6e-3, 1.6e-3, kTop + kRho - 2e-6 * tick);
    EXPECT_TRUE(provider.contacts(pose, out));
    if (!out.empty()) provider.drill(out, 1e-3);
  }
  if (prefault_after) provider.prefault_drill_log(kDrillLogCapacity);
  return provider.drill_log();
}

TEST(DrillLog, PrefaultWritesTheRecordsARunCanAppendWithoutGrowingOrFillingTheLog) {
  VoxelTooth tooth = slab();
  DrillParams drill;
  ToothContactProvider provider(tooth, ToolTip{kRho, Vec3::Zero()}, 3000.0, 0.0, &drill,
                                ContactModel::kSurfaceProxy);
  const std::vector<DrillRecord>& log = provider.drill_log();
  const DrillRecord* storage = log.data();
  const std::size_t capacity = log.capacity();
  ASSERT_EQ(capacity, kDrillLogCapacity);
  constexpr std::size_t kRecords = 40000;  // a 5 s run at 8 kHz
  provider.prefault_drill_log(kRecords);
  EXPECT_TRUE(log.empty());
  EXPECT_EQ(log.data(), storage);  // no allocation: the same storage
  EXPECT_EQ(log.capacity(), capacity);
  const auto [resident, pages] = resident_pages(storage, kRecords * sizeof(DrillRecord));
  EXPECT_EQ(resident, pages);
  // More than the log holds: the capacity, never beyond it.
  provider.prefault_drill_log(2 * kDrillLogCapacity);
  EXPECT_EQ(log.data(), storage);
  EXPECT_EQ(log.capacity(), capacity);
  const auto [resident_all, pages_all] = resident_pages(storage, capacity * sizeof(DrillRecord));
  EXPECT_EQ(resident_all, pages_all);
}

TEST(DrillLog, PrefaultChangesNoRecordAndLeavesAFilledLogAlone) {
  constexpr int kTicks = 400;
  const std::vector<DrillRecord> plain = drill_into_slab(kTicks, 0, false);
  ASSERT_GT(plain.size(), 100u);  // the bur cut on most ticks
  int removed = 0;
  for (const DrillRecord& r : plain) removed += r.removed[kEnamel];
  EXPECT_GT(removed, 0);
  for (const bool after : {false, true}) {
    const std::vector<DrillRecord> other = drill_into_slab(kTicks, after ? 0 : kTicks, after);
    ASSERT_EQ(other.size(), plain.size());
    for (std::size_t i = 0; i < plain.size(); ++i) {
      EXPECT_EQ(other[i].tick, plain[i].tick);
      EXPECT_EQ(other[i].depth_m, plain[i].depth_m);
      EXPECT_EQ(other[i].force_n, plain[i].force_n);
      EXPECT_EQ(other[i].material, plain[i].material);
      EXPECT_EQ(other[i].removed, plain[i].removed);
    }
  }
}

}  // namespace
}  // namespace dentsim
