// The fast tooth provider (fast/tooth/tooth_contacts.h) against the reference provider
// (reference/tooth/tooth_contacts.h) through the tick's ContactProvider interface: the same set
// into the tick's fixed-capacity buffer, the same cut, and no heap allocation in contacts() or
// drill() once constructed (global operator new counted over 10^4 ticks of drilling).
#include "fast/tooth/tooth_contacts.h"

#include <gtest/gtest.h>

#include <random>

#include "reference/core/io.h"
#include "tooth_io/procedural_molar.h"
#include "reference/tooth/tooth_contacts.h"
#include "tests/fast/tooth_diff.h"
#include "tests/support/alloc_counter.h"
#include "tests/support/stress.h"

namespace dentsim {
namespace {

// Keeps the probe allocation from being optimised away.
void benchmark_guard(const void* p) { asm volatile("" : : "g"(p) : "memory"); }

using testing::g_allocs;
using testing::g_count_allocs;
using testing::kToothB;
using testing::kToothK;

TEST(FastToothContacts, ProviderEqualsReferenceTickByTick) {
  VoxelTooth ref_tooth(voxelize_procedural_molar(MolarParams{}, 64));
  fast::BrickTooth fast_tooth(ref_tooth);
  ToolTip tip;
  tip.radius = 0.5e-3;
  tip.offset_body = Vec3(0.0, 0.0, 0.2e-3);
  const DrillParams drill = testing::fast_cutting();
  ToothContactProvider ref(ref_tooth, tip, kToothK, kToothB, &drill);
  fast::ToothContactProvider fst(fast_tooth, tip, kToothK, kToothB, &drill);
  EXPECT_TRUE(fst.drills());
  std::vector<Contact> a, b;
  a.reserve(kContactCapacity);
  b.reserve(kContactCapacity);
  testing::DrillPath path(ref_tooth.grid(), tip.radius, 2e-3, 7);
  long removed = 0, touching = 0;
  for (int k = 0; k < 1000; ++k) {
    const Pose& pose = path.next(ref_tooth.grid(), tip.offset_body);
    const bool fa = ref.contacts(pose, a);
    const bool fb = fst.contacts(pose, b);
    ASSERT_EQ(fa, fb);
    testing::ContactSet sa{a, ref.contact_voxels(), fa}, sb{b, fst.contact_voxels(), fb};
    ASSERT_TRUE(testing::same_set(sa, sb, "tick " + std::to_string(k)));
    const int ra = ref.drill(a, 1e-3);
    ASSERT_EQ(ra, fst.drill(b, 1e-3)) << "tick " << k;
    removed += ra;
    if (!a.empty()) ++touching;
  }
  EXPECT_EQ(ref.drill_state().removed_voxels, fst.drill_state().removed_voxels);
  EXPECT_EQ(ref_tooth.codes.dense().code, fast_tooth.codes().code);
  EXPECT_GT(removed, 100);
  EXPECT_GT(touching, 500);
}

// A buffer of capacity 8: the fast provider fills it and reports false, as the reference.
TEST(FastToothContacts, FullBufferReportsFalse) {
  VoxelTooth ref_tooth(voxelize_procedural_molar(MolarParams{}, 64));
  fast::BrickTooth fast_tooth(ref_tooth);
  ToolTip tip;
  tip.radius = 1.0e-3;
  ToothContactProvider ref(ref_tooth, tip, kToothK, kToothB);
  fast::ToothContactProvider fst(fast_tooth, tip, kToothK, kToothB);
  EXPECT_FALSE(fst.drills());
  std::vector<Contact> a, b;
  a.reserve(8);
  b.reserve(8);
  testing::DrillPath path(ref_tooth.grid(), tip.radius, 2e-3, 8);
  const Pose& pose = path.next(ref_tooth.grid());
  EXPECT_FALSE(ref.contacts(pose, a));
  EXPECT_FALSE(fst.contacts(pose, b));
  ASSERT_EQ(b.size(), a.size());
  EXPECT_EQ(b.capacity(), a.capacity());
  EXPECT_EQ(fst.contact_voxels(), ref.contact_voxels());
}

TEST(FastToothContacts, RejectsBadTipAndDrillParams) {
  fast::BrickTooth tooth(voxelize_procedural_molar(MolarParams{}, 16));
  ToolTip tip;
  tip.radius = -1.0;
  EXPECT_THROW(fast::ToothContactProvider(tooth, tip, 1.0, 1.0), InputError);
  tip.radius = 1e-3;
  DrillParams drill;
  drill.cutting_coefficient = -0.5;
  EXPECT_THROW(fast::ToothContactProvider(tooth, tip, 1.0, 1.0, &drill), InputError);
}

// No allocation in contacts() and drill() over 10^4 ticks of a drilling bur (10^5 in the long
// form), with sets up to a few hundred members.
TEST(FastToothContactsStress, NoAllocationWhileQueryingAndDrilling) {
  fast::BrickTooth tooth(voxelize_procedural_molar(MolarParams{}, 128));
  ToolTip tip;
  tip.radius = 0.8e-3;
  const DrillParams drill = testing::fast_cutting();
  fast::ToothContactProvider provider(tooth, tip, kToothK, kToothB, &drill);
  std::vector<Contact> out;
  out.reserve(kContactCapacity);
  testing::DrillPath path(tooth.grid(), tip.radius, 2e-3, 9);
  const long ticks = testing::stress_count(10000, 100000);
  long removed = 0, contacts = 0;
  std::size_t largest = 0;
  g_allocs = 0;
  g_count_allocs = true;
  {
    std::vector<int> probe(3);  // the hook counts: one allocation here
    benchmark_guard(probe.data());
  }
  const long hook_check = g_allocs.exchange(0);
  for (long k = 0; k < ticks; ++k) {
    const bool ok = provider.contacts(path.next(tooth.grid()), out);
    removed += provider.drill(out, 1e-3);
    contacts += static_cast<long>(out.size());
    if (out.size() > largest) largest = out.size();
    if (!ok) break;
  }
  g_count_allocs = false;
  EXPECT_EQ(hook_check, 1);
  EXPECT_EQ(g_allocs.load(), 0);
  std::printf("%ld ticks: %ld contacts, largest set %zu, %ld voxels removed\n", ticks, contacts,
              largest, removed);
  EXPECT_GT(largest, 100u);  // signal: large sets and real cutting were exercised
  EXPECT_GT(removed, 1000);
}

}  // namespace
}  // namespace dentsim
