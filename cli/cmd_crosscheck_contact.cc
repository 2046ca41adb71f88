// `dentsim crosscheck contact`: the contact sweep of validation/crosscheck_contact.h (issue #16):
// probes pressed at 1, 4, 8.5 N into the procedural molar and the real meshes at 128, 256, 512,
// for the sdf (default) and faces models; pop-throughs, the rendered tip's largest penetration and
// the sliding ripple on a voxelised sphere. Prints one line per model and resolution, writes
// --json FILE; exit status 1 if the default model (sdf) popped through anywhere.
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>

#include "cli/registry.h"
#include "validation/crosscheck_contact.h"

namespace dentsim::cli {
namespace {

struct Options {
  std::string json;
  double tip_radius_mm = 0.4;
  ContactCrosscheckOptions check;
};

void setup_crosscheck_contact(CLI::App& app) {
  CLI::App* group_app = group(app, "crosscheck", "Cross-checks against an independent oracle");
  CLI::App* sub = group_app->add_subcommand(
      "contact", "Contact sweep: pop-throughs, penetration and sliding ripple per model");
  auto opt = std::make_shared<Options>();
  opt->check.data_dir = "../shared/data";
  sub->add_option("--json", opt->json, "Write the results (rows per model and resolution)");
  sub->add_option("--resolutions", opt->check.resolutions, "Voxels per axis (powers of two)")
      ->capture_default_str();
  sub->add_option("--forces", opt->check.forces_n, "Push forces [N]")->capture_default_str();
  sub->add_option("--models", opt->check.models, "Contact models (sdf, faces, field)")
      ->capture_default_str();
  sub->add_option("--probes", opt->check.probes,
                  "(point, direction) pairs per resolution over all teeth")
      ->capture_default_str();
  sub->add_option("--data-dir", opt->check.data_dir,
                  "Directory with molar-cc0.stl and chai3d-tooth.obj ('' = procedural molar only)")
      ->capture_default_str();
  sub->add_option("--tip-radius-mm", opt->tip_radius_mm, "Tip radius [mm]")->capture_default_str();
  sub->add_option("--k-tooth", opt->check.k_tooth, "K_tooth [N/m]")->capture_default_str();
  sub->add_option("--seed", opt->check.seed, "Random seed (std::mt19937_64)")
      ->capture_default_str();
  sub->callback([opt] {
    opt->check.tip_radius_m = 1e-3 * opt->tip_radius_mm;
    const ContactCrosscheckResult r = crosscheck_contact(opt->check);
    long default_pops = 0;
    for (const ContactSweepRow& row : r.rows) {
      std::printf(
          "crosscheck contact: model=%s n=%d h=%.4f mm probes=%ld runs=%ld pop_throughs=%ld "
          "max_penetration_over_radius=%.4f sliding_ripple_rms=%.4f\n",
          row.model.c_str(), row.resolution, 1e3 * row.voxel_size_m, row.probes, row.runs,
          row.pop_throughs, row.max_penetration_over_radius, row.sliding_ripple_rms);
      if (row.model == "sdf") default_pops += row.pop_throughs;
    }
    if (!opt->json.empty()) write_json(opt->json, crosscheck_contact_json(r));
    if (default_pops > 0) {
      throw std::runtime_error("crosscheck contact: the default model (sdf) popped through " +
                               std::to_string(default_pops) + " times");
    }
  });
}
DENTSIM_REGISTER_COMMAND(setup_crosscheck_contact);

}  // namespace
}  // namespace dentsim::cli
