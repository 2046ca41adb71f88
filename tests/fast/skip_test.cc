// The fast pipeline's skips are exact (issue #14 "Skip what a scene does not need ... checked
// equal to not skipping"; PipelineModel::skip_unneeded): every variant of
// validation/skip_variants.h (the list bench/skip_bench.cc times) runs in closed loop on the
// simulated Phantom twice, skips on and skips off (every unneeded stage run and its result
// discarded), and the torques sent to the device must be the same, tick by tick: bitwise (the
// friction skip too: fast/friction.h at mu = 0 is the PMI solve's own factor and solve).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "fast/tooth/tooth_contacts.h"
#include "validation/skip_variants.h"

namespace dentsim {
namespace {

TEST(FastSkips, SkippingChangesNoTorque) {
  ASSERT_GE(skip_variants().size(), 5u);
  for (const SkipVariant& v : skip_variants()) {
    auto a = build_skip_variant_rig(v, true);
    auto b = build_skip_variant_rig(v, false);
    a->loop->start();
    b->loop->start();
    long ticks = 0, contact_ticks = 0, differing = 0, removed = 0;
    double max_diff = 0.0, max_tau = 0.0;
    for (long k = 0; k < 3000; ++k) {
      const TickResult& ra = a->loop->step();
      const TickResult& rb = b->loop->step();
      ASSERT_FALSE(a->loop->faulted()) << v.name << " tick " << k << ": " << a->loop->fault_name();
      ASSERT_FALSE(b->loop->faulted()) << v.name << " tick " << k << ": " << b->loop->fault_name();
      ++ticks;
      if (!ra.contacts.empty()) ++contact_ticks;
      removed += ra.removed_voxels;
      // The torques, and what the report shows besides: the hand's estimate and the contact force.
      const double d = std::max({(ra.tau - rb.tau).cwiseAbs().maxCoeff(),
                                 (ra.F1_hat - rb.F1_hat).cwiseAbs().maxCoeff(),
                                 (ra.F_contact - rb.F_contact).cwiseAbs().maxCoeff()});
      if (d != 0.0 || ra.removed_voxels != rb.removed_voxels) ++differing;
      max_diff = std::max(max_diff, d);
      max_tau = std::max({max_tau, ra.tau.cwiseAbs().maxCoeff(), ra.F1_hat.cwiseAbs().maxCoeff(),
                          ra.F_contact.cwiseAbs().maxCoeff()});
    }
    std::printf(
        "%-22s %ld ticks, %ld in contact, %ld voxels removed; max |d(tau, F1_hat, F_contact)| %.3e "
        "of "
        "%.3f, %ld ticks differ  [%s]\n",
        v.name.c_str(), ticks, contact_ticks, removed, max_diff, max_tau, differing,
        v.skips.c_str());
    EXPECT_GT(contact_ticks, 500) << v.name << ": the variant must reach contact";
    EXPECT_GT(ticks - contact_ticks, 500) << v.name << ": and free space";
    EXPECT_EQ(differing, 0) << v.name;
    EXPECT_EQ(max_diff, 0.0) << v.name;
  }
}

// The face model's free-space early out alone, on a grid of queries far from and near the tooth:
// the same contact sets, member for member, with the box test and without it.
TEST(FastSkips, FreeSpaceEarlyOutFindsTheSameSets) {
  const SkipVariant& v = skip_variants().front();  // face model
  auto rig = build_skip_variant_rig(v, true);
  auto* brick_tooth = dynamic_cast<fast::BrickPipelineTooth*>(rig->pipeline_tooth.get());
  ASSERT_NE(brick_tooth, nullptr);
  std::vector<Contact> with, without;
  with.reserve(kContactCapacity);
  without.reserve(kContactCapacity);
  long nonempty = 0, empty = 0;
  for (int i = -8; i <= 8; ++i) {
    for (int k = -6; k <= 12; ++k) {
      Pose p = rig->home;
      p.x = rig->anchor + Vec3(0.75e-3 * i, 0.3e-3 * i, 0.5e-3 * k);
      brick_tooth->brick().set_free_space_early_out(true);
      ASSERT_TRUE(rig->contacts->contacts(p, with));
      brick_tooth->brick().set_free_space_early_out(false);
      ASSERT_TRUE(rig->contacts->contacts(p, without));
      ASSERT_EQ(with.size(), without.size()) << i << " " << k;
      for (std::size_t m = 0; m < with.size(); ++m) {
        EXPECT_EQ(with[m].x_o, without[m].x_o);
        EXPECT_EQ(with[m].n, without[m].n);
        EXPECT_EQ(with[m].r, without[m].r);
      }
      (with.empty() ? empty : nonempty) += 1;
    }
  }
  EXPECT_GT(nonempty, 20);
  EXPECT_GT(empty, 100);
}

}  // namespace
}  // namespace dentsim
