// The servo tick allocates nothing (docs/design.md "The tick as Model/Data stages"; issue "The tick
// as an engine"): every implementation in the registry (fast/registry.h), every method, with and
// without the grip detector (and with issue #29's encoder Kalman filter and loop-lag
// compensation, and the field contact model), over 10^4 ticks of the drill scene in contact and
// drilling, counted with a global operator new hook around the loop owner's step (read -> tick ->
// write -> advance on the simulated Phantom).
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "sim/scene.h"
#include "sim/simulator.h"
#include "sim/scene_stability.h"
#include "fast/registry.h"
#include "fast/tooth/field.h"
#include "tests/support/alloc_counter.h"

namespace dentsim {
namespace {

struct Variant {
  const char* name;
  Method method;
  bool grip_detector;
  bool encoder_kalman = false;
  bool lag_compensation = false;
  // tooth.contact_model; "field" drills by editing the tooth's field from its spare bricks (issue
  // #30; fast/ runs its twin, fast/tooth/field.h, on a worker thread at a fixed latency, with
  // copy-on-write bricks from its pool).
  const char* contact_model = "sdf";
  bool stick_slip = false;  // method.encoder_kalman_friction_model "stick_slip"
};

TEST(TickAllocation, DrillSceneTicksAllocateNothingForEveryImplementationAndMethod) {
  const Variant variants[] = {
      {"explicit", Method::kExplicitVc, false},
      {"pmi", Method::kPmiVc, false},
      {"pmi-pd", Method::kPmiPd, false},
      {"pmi-pd + grip detector", Method::kPmiPd, true},
      {"pmi-pd + grip detector + encoder kalman", Method::kPmiPd, true, true},
      {"pmi-pd + grip detector + lag compensation", Method::kPmiPd, true, false, true},
      {"pmi-pd, field model", Method::kPmiPd, false, false, false, "field"},
      {"pmi-pd + grip detector + encoder kalman, stick-slip friction", Method::kPmiPd, true, true,
       false, "sdf", true}};
  constexpr long kTicks = 10000;
  for (const StageTable* table : stage_tables()) {
    for (const Variant& v : variants) {
      SCOPED_TRACE(std::string(table->implementation) + " / " + v.name);
      Scene scene = load_scene("drill");
      scene.method.method = v.method;
      if (v.grip_detector) {
        scene.method.grasp_mass_scale = 1.0;
        scene.method.grip_detector = true;
      }
      scene.method.encoder_kalman = v.encoder_kalman;
      scene.method.lag_compensation = v.lag_compensation;
      scene.method.encoder_kalman_stick_slip = v.stick_slip;
      scene.tooth.contact_model = v.contact_model;
      SceneRigOptions options;
      options.pipeline = table->implementation;
      const std::unique_ptr<SceneRig> rig = build_scene_rig(scene, options);
      if (std::string(v.contact_model) == "field" && std::string(table->implementation) == "fast") {
        // The fast pipeline's field edit runs on its worker thread (fast/tooth/field.h), whose
        // allocations the global count includes.
        const auto* field = dynamic_cast<const fast::FieldContactProvider*>(rig->contacts);
        ASSERT_NE(field, nullptr);
        ASSERT_NE(field->worker(), nullptr);
      }
      ClosedLoop& loop = *rig->loop;
      loop.start();
      ASSERT_FALSE(loop.faulted());
      long contact_ticks = 0, removed = 0, allocs = 0;
      {
        testing::AllocationScope scope;
        for (long k = 0; k < kTicks; ++k) {
          const TickResult& r = loop.step();
          if (!r.contacts.empty()) ++contact_ticks;
          removed += r.removed_voxels;
        }
        allocs = scope.count();
      }
      std::printf("%s / %s: %ld ticks, %ld in contact, %ld voxels drilled, %ld allocations\n",
                  table->implementation, v.name, kTicks, contact_ticks, removed, allocs);
      if (scene_stability_problems(scene).empty()) {
        EXPECT_FALSE(loop.faulted()) << loop.fault_name();
      } else if (loop.faulted()) {
        // Explicit Euler on this scene is outside its bound (sim/scene_stability.h: `dentsim
        // run` refuses it): the supervisor may end it, and the ticks after the fault (zero
        // torque) allocate nothing either.
        EXPECT_NE(loop.supervisor_fault(), SupervisorFault::kNone) << loop.fault_name();
      }
      EXPECT_EQ(allocs, 0);
      // The count means something only if the tick did the work: in contact and drilling.
      EXPECT_GT(contact_ticks, kTicks / 10);
      EXPECT_GT(removed, 0);
    }
  }
}

// Issue #29's saturation-passive shape control (method.saturation_passive), on and engaged:
// the groove scene pressed at 3 N, beyond the Phantom's continuous force, on every implementation.
TEST(TickAllocation, SaturatedPressTicksAllocateNothingWithTheShapeControlEngaged) {
  constexpr long kTicks = 3000;
  for (const StageTable* table : stage_tables()) {
    SCOPED_TRACE(table->implementation);
    Scene scene = load_scene("probe-groove");
    scene.method.saturation_passive = true;
    for (SceneHandKey& k : scene.script) {
      if (k.force.norm() > 0.0) k.force = Vec3(0.0, 0.0, -3.0);
    }
    SceneRigOptions options;
    options.pipeline = table->implementation;
    const std::unique_ptr<SceneRig> rig = build_scene_rig(scene, options);
    ClosedLoop& loop = *rig->loop;
    loop.start();
    long engaged = 0, saturated = 0, allocs = 0;
    {
      testing::AllocationScope scope;
      for (long k = 0; k < kTicks; ++k) {
        const TickResult& r = loop.step();
        if (r.shape_sigma < 1.0 || r.coupling_force_cap > 0.0) ++engaged;
        if (r.saturated) ++saturated;
      }
      allocs = scope.count();
    }
    std::printf("%s / saturated groove press: %ld ticks, %ld saturated, %ld engaged, %ld "
                "allocations\n",
                table->implementation, kTicks, saturated, engaged, allocs);
    EXPECT_EQ(allocs, 0);
    EXPECT_GT(saturated, 0);
    EXPECT_GT(engaged, 10);
  }
}

}  // namespace
}  // namespace dentsim
