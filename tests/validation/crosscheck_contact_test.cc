// The contact sweep (validation/crosscheck_contact.h), short form for CI: 128^3, 60 probes over
// the procedural molar and the two real meshes, at 1, 4 and 8.5 N, both models. The default
// model (sdf) never pops through and its rendered tip stays outside the solid; the thesis's face
// model is caught popping through at the device's peak force (the oracle can fail). The long
// form is `dentsim crosscheck contact` (docs/results/contact_sweep.md).
#include "validation/crosscheck_contact.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>

#include "reference/core/io.h"

namespace dentsim {
namespace {

const std::string kData = std::string(DENTSIM_SOURCE_DIR) + "/../shared/data";

TEST(CrosscheckContact, ShortSweepSdfNeverPopsThroughFacesDo) {
  ContactCrosscheckOptions o;
  o.resolutions = {128};
  o.probes = 60;
  o.settle_ticks = 100;
  o.slide_ticks = 100;
  o.data_dir = kData;
  const ContactCrosscheckResult r = crosscheck_contact(o);
  std::printf("%s\n", crosscheck_contact_json(r).dump(2).c_str());
  ASSERT_EQ(r.rows.size(), 2u);
  ASSERT_EQ(r.teeth.size(), 3u);
  const ContactSweepRow& sdf = r.rows[0];
  const ContactSweepRow& faces = r.rows[1];
  ASSERT_EQ(sdf.model, "sdf");
  EXPECT_EQ(sdf.probes, 60);
  EXPECT_EQ(sdf.runs, 180);
  EXPECT_EQ(sdf.pop_throughs, 0);
  // The surface proxy never leaves A_skin = {phi >= rho - s}, s = min(rho / 4, h / 2) (the swept
  // test; push-out only moves it outwards): the rendered sphere sinks by at most s.
  EXPECT_LE(sdf.max_penetration_over_radius, std::min(0.25, 0.5 * sdf.voxel_size_m / 0.4e-3));
  // Faces: the force saturates at about K rho = 1.2 N, so 8.5 N pushes the tip through.
  EXPECT_GT(faces.pop_throughs_per_force[2], 0);
  // The face model's tip sinks by F / K while the set holds (0.83 rho at 1 N), more when it
  // tunnels.
  EXPECT_GT(faces.max_penetration_over_radius, 0.8);
}

TEST(CrosscheckContact, BadOptionsNameTheOption) {
  ContactCrosscheckOptions o;
  o.resolutions = {100};
  try {
    crosscheck_contact(o);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--resolutions"), std::string::npos);
  }
  o.resolutions = {32};
  o.data_dir = "/nonexistent";
  EXPECT_THROW(crosscheck_contact(o), InputError);
  o.data_dir = "";
  o.models = {"voxels"};
  EXPECT_THROW(crosscheck_contact(o), InputError);
}

}  // namespace
}  // namespace dentsim
