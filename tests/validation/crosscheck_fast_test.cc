// Every row of `dentsim crosscheck fast` can fail (issue #31): a wrapper stage table runs the fast
// pipeline's stages and plants a relative error of 1e-9 into one output of one stage (the
// removed-voxel count + 1 for drill); the crosscheck (validation/crosscheck_fast.h), run on it
// exactly as on the registered fast pipeline, must report that stage: in its own row, and in the
// chain row for every stage after device_terms (for the stages fast shares with the reference,
// observe and command, the chain row alone) — while every other stage's own row still agrees
// (the error is found where it is planted).
#include "validation/crosscheck_fast.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "fast/tick.h"

namespace dentsim {
namespace {

constexpr double kPlanted = 1e-9;

// The fast stage S, then one of its outputs perturbed.
template <int S>
TickStatus planted(const PipelineModel& m, PipelineData& d) {
  const TickStatus st = fast::fast_stage_table().stage[S](m, d);
  constexpr double f = 1.0 + kPlanted;
  switch (S) {
    case kStageDeviceTerms:
      d.dev.M *= f;
      break;
    case kStageObserve:
      d.r.F1_hat *= f;
      break;
    case kStageCollide:
      for (Contact& c : d.r.contacts) c.stiffness *= f;
      break;
    case kStageAssemble:
      d.coupling.G *= f;
      break;
    case kStageSolve:
      d.proxy.pose.x *= f;
      break;
    case kStageCommand:
      d.r.tau *= f;
      break;
    case kStageDrill:
      d.r.removed_voxels += 1;
      break;
    default:
      break;
  }
  return st;
}

constexpr StageFn kPlantedStages[kStageCount] = {
    planted<kStageDeviceTerms>, planted<kStageObserve>, planted<kStageCollide>,
    planted<kStageAssemble>,    planted<kStageSolve>,   planted<kStageCommand>,
    planted<kStageDrill>};

// The drill scene with the face model, PMI-PD and the grip detector (every stage has work: the
// observers, contact from about 0.95 s on, drilling), 1100 ticks.
FastCrosscheckOptions options(const CheckedImplementation& impl) {
  FastCrosscheckOptions o;
  StageConfig c;
  c.scene = "drill";
  c.contact_model = "faces";
  o.stage_configs = {c};
  o.stage_ticks = 1100;
  o.adversarial = false;
  o.scenes.clear();
  o.implementations = {impl};
  return o;
}

const StageCrosscheck* row(const FastCrosscheckResult& r, const std::string& stage) {
  for (const StageCrosscheck& s : r.stages) {
    if (s.stage == stage) return &s;
  }
  return nullptr;
}

bool reported(const StageCrosscheck& s, double bound) {
  return !(s.max_rel <= bound) || s.count_mismatches != 0;
}

TEST(CrosscheckFast, APlantedErrorInAnyStageIsReported) {
  const std::vector<CheckedImplementation> registered = registered_implementations();
  ASSERT_FALSE(registered.empty());
  CheckedImplementation fast_impl;
  for (const CheckedImplementation& c : registered) {
    if (c.table == &fast::fast_stage_table()) fast_impl = c;
  }
  ASSERT_NE(fast_impl.table, nullptr);
  // The signal guard: unplanted, the same run passes, with contact.
  {
    const FastCrosscheckOptions o = options(fast_impl);
    const FastCrosscheckResult r = crosscheck_fast(o);
    for (const std::string& f : r.failures) ADD_FAILURE() << f;
    ASSERT_TRUE(r.ok);
    ASSERT_NE(row(r, "chain"), nullptr);
    EXPECT_GT(row(r, "chain")->contact_samples, 100);
  }
  for (int planted_stage = 0; planted_stage < kStageCount; ++planted_stage) {
    StageTable table = fast::fast_stage_table();
    table.implementation = "planted";
    table.stage[planted_stage] = kPlantedStages[planted_stage];
    CheckedImplementation impl = fast_impl;  // same environment, same shared stages
    impl.table = &table;
    impl.environment = "fast";
    const FastCrosscheckOptions o = options(impl);
    const FastCrosscheckResult r = crosscheck_fast(o);
    const std::string name = tick_stage_name(planted_stage);
    EXPECT_FALSE(r.ok) << name;
    const StageCrosscheck* chain = row(r, "chain");
    ASSERT_NE(chain, nullptr);
    if (planted_stage != kStageDeviceTerms) {
      EXPECT_TRUE(reported(*chain, o.max_rel_bound)) << name << ": chain row " << chain->max_rel;
    }
    bool shared = false;
    for (int i : impl.shared_stages) shared = shared || i == planted_stage;
    const StageCrosscheck* own = row(r, name);
    if (shared) {
      EXPECT_EQ(own, nullptr) << name;
    } else {
      ASSERT_NE(own, nullptr) << name;
      EXPECT_TRUE(reported(*own, o.max_rel_bound)) << name << ": own row " << own->max_rel;
      // A relative error, not a blow-up: the row measures the planted size.
      if (planted_stage != kStageDrill) {
        EXPECT_LT(own->max_rel, 10 * kPlanted) << name;
      }
    }
    for (const StageCrosscheck& s : r.stages) {
      if (s.stage == name || s.stage == "chain") continue;
      EXPECT_FALSE(reported(s, o.max_rel_bound))
          << "planted in " << name << ", " << s.stage << " reports " << s.max_rel;
    }
    std::printf(
        "planted in %-13s own row max_rel %.3e (%ld count mismatches), chain row %.3e (%ld)\n",
        name.c_str(), own != nullptr ? own->max_rel : -1.0,
        own != nullptr ? own->count_mismatches : -1L, chain->max_rel, chain->count_mismatches);
  }
}

}  // namespace
}  // namespace dentsim
