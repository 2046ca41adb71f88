// The field model's drilling at the fixed edit latency (issue #30, stop 46): the reference
// provider, which cuts each tick's cut set at the start of tick t + L's contacts()
// (reference/tooth/tooth_contacts.h set_field_edit_latency), against the fast provider, whose
// worker thread does the same drilling on its own copy of the grid and publishes it then
// (fast/tooth/field.h FieldEditWorker), each in a closed loop of the fast pipeline. A whole drill scene at 64^3 and 128^3, at stride 1
// and 2: every tick's contact wrench, torques, proxy and removed voxels bitwise equal, and at the
// end the drill log, the pulp's tick, the drill state's counts, the field edit's counts and the
// grids.
#include <gtest/gtest.h>

#include <cstdio>
#include <memory>
#include <string>

#include "fast/tooth/field.h"
#include "fast/tooth/sdf.h"
#include "reference/tooth/tooth_contacts.h"
#include "sim/scene.h"
#include "sim/simulator.h"

namespace dentsim {
namespace {

void drill_scene_pipelines_agree(int resolution, int stride, int ticks) {
  SCOPED_TRACE("resolution " + std::to_string(resolution) + ", stride " +
               std::to_string(stride));
  Scene scene = load_scene("drill");
  scene.tooth.contact_model = "field";
  scene.tooth.resolution = resolution;
  SceneRigOptions options;
  options.pipeline = "fast";
  if (stride > 1) {
    // H = (stride + 1/2) h: the field samples every stride-th voxel (scene.h field_spacing).
    const std::unique_ptr<SceneRig> probe = build_scene_rig(scene, options);
    scene.tooth.field_spacing = (stride + 0.5) * probe->tooth->grid().voxel_size;
  }
  // Two fast rigs: the first with its provider (the worker), the second driven by the reference
  // provider on its tooth and field (the pipelines' own arithmetic differs: fast/ is pinned
  // against reference/ stage by stage, not bitwise over a run), with the fast pipeline's
  // signed-distance query as the fast provider's.
  const std::unique_ptr<SceneRig> f = build_scene_rig(scene, options);
  const std::unique_ptr<SceneRig> r = build_scene_rig(scene, options);
  ASSERT_EQ(r->field->stride(), stride);
  DrillParams drill;
  drill.bur_speed_rad_s = scene.tool.bur_speed_rpm * 2.0 * 3.14159265358979323846 / 60.0;
  drill.cutting_coefficient = scene.tool.cutting_coefficient;
  ToothContactProvider reference(*r->tooth, r->tip, r->k_tooth, r->b_tooth, &drill,
                                 ContactModel::kField, &fast::signed_distance, r->field.get());
  reference.set_field_edit_latency(ToothContactProvider::kFieldEditLatency);
  ToothContactProvider* pr = &reference;
  auto* pf = dynamic_cast<fast::FieldContactProvider*>(f->contacts);
  ASSERT_NE(pf, nullptr);
  ASSERT_EQ(pf->field_edit_latency(), ToothContactProvider::kFieldEditLatency);
  ClosedLoop lf(*f->loop_device, *f->pipeline, *f->contacts);
  ClosedLoop lr(*r->loop_device, *r->pipeline, reference);
  lr.start();
  lf.start();
  long contact_ticks = 0, removed = 0;
  for (int k = 0; k < ticks; ++k) {
    const TickResult& a = lr.step();
    const TickResult& b = lf.step();
    ASSERT_EQ(a.F_contact, b.F_contact) << "tick " << k;
    ASSERT_EQ(a.tau, b.tau) << "tick " << k;
    ASSERT_EQ(a.removed_voxels, b.removed_voxels) << "tick " << k;
    ASSERT_EQ(pr->last_removed(), pf->last_removed()) << "tick " << k;
    ASSERT_EQ(pr->surface_proxy().g(), pf->surface_proxy().g()) << "tick " << k;
    contact_ticks += a.contacts.empty() ? 0 : 1;
    // The voxels this tick's publish removed (drill() returns them only in contact).
    removed += static_cast<long>(pr->last_removed().size());
  }
  const DrillState& sr = pr->drill_state();
  const DrillState& sf = pf->drill_state();
  double volume = 0.0;
  for (int m = kEnamel; m < kMaterialCount; ++m) volume += sr.removed_volume_m3(m);
  std::printf("drill scene, field, %d^3, stride %d: %d ticks, %ld in contact, %ld voxels "
              "removed (%.6f mm^3), %zu drill log records, pulp at tick %ld, %ld takeovers\n",
              resolution, stride, ticks, contact_ticks, removed, 1e9 * volume,
              pr->drill_log().size(), pr->pulp_exposed_tick(), pf->field_edit_servo_takeovers());
  EXPECT_EQ(sr.removed_voxels, sf.removed_voxels);
  EXPECT_EQ(sr.delivered_j, sf.delivered_j);
  EXPECT_EQ(sr.carry_j, sf.carry_j);
  EXPECT_EQ(sr.pulp_exposed, sf.pulp_exposed);
  EXPECT_EQ(pr->pulp_exposed_tick(), pf->pulp_exposed_tick());
  ASSERT_EQ(pr->drill_log().size(), pf->drill_log().size());
  for (std::size_t i = 0; i < pr->drill_log().size(); ++i) {
    const DrillRecord& x = pr->drill_log()[i];
    const DrillRecord& y = pf->drill_log()[i];
    EXPECT_EQ(x.tick, y.tick) << "record " << i;
    EXPECT_EQ(x.depth_m, y.depth_m) << "record " << i;
    EXPECT_EQ(x.force_n, y.force_n) << "record " << i;
    EXPECT_EQ(x.material, y.material) << "record " << i;
    EXPECT_EQ(x.removed, y.removed) << "record " << i;
  }
  // Each tick's record is of a tick in contact, logged L ticks later, in tick order.
  for (std::size_t i = 1; i < pr->drill_log().size(); ++i) {
    EXPECT_LT(pr->drill_log()[i - 1].tick, pr->drill_log()[i].tick);
  }
  const FieldEditStats& er = pr->field_edits();
  const FieldEditStats& ef = pf->field_edits();
  EXPECT_EQ(er.voxels, ef.voxels);
  EXPECT_EQ(er.samples_scanned, ef.samples_scanned);
  EXPECT_EQ(er.samples_raised, ef.samples_raised);
  EXPECT_EQ(er.work, ef.work);
  EXPECT_EQ(pr->field_edit_shortfalls(), 0);
  EXPECT_EQ(pf->field_edit_shortfalls(), 0);
  EXPECT_EQ(pf->field_edit_late_publishes(), 0);  // simulation: waited for
  EXPECT_EQ(r->tooth->grid().voxels, f->tooth->grid().voxels);
  // The field followed every removed voxel but those of the last L ticks' cuts, not yet done.
  EXPECT_EQ(er.voxels, removed);
  EXPECT_GT(contact_ticks, ticks / 4);
  EXPECT_GT(removed, 50);
}

TEST(FieldDrillingOnTheWorker, TheFastPipelineDrillsAsTheReferenceAt64) {
  drill_scene_pipelines_agree(64, 1, 3000);
}
TEST(FieldDrillingOnTheWorker, TheFastPipelineDrillsAsTheReferenceAt128) {
  drill_scene_pipelines_agree(128, 1, 3000);
}
TEST(FieldDrillingOnTheWorker, TheFastPipelineDrillsAsTheReferenceAt128Stride2) {
  drill_scene_pipelines_agree(128, 2, 3000);
}

}  // namespace
}  // namespace dentsim
