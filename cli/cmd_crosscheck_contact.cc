// `dentsim crosscheck contact`: the contact sweep of validation/crosscheck_contact.h (issue #16):
// probes pressed at 1, 4, 8.5 N into the procedural molar and the real meshes at 128, 256, 512,
// for the sdf (default) and faces models; pop-throughs, the rendered tip's largest penetration and
// the sliding ripple on a voxelised sphere. Prints one line per model and resolution, writes
// --json FILE. The verdict (cli/verdict.h) judges the default model (sdf) only: no pop-through in
// any run, and the rendered sphere's overlap within the skin min(rho/4, h/2) it is built to keep
// (docs/derivations/sdf_contact.md §2); exit status 1 on FAIL. The faces model is printed for
// comparison (it pops through by design), and the sliding ripple against the aim of 5 %
// RMS is reported, not judged: docs/results/contact_sweep.md measures it above the aim for both
// models (a deliberate choice: the aim needs a sub-voxel surface). Ctrl-C / SIGTERM: the rows so
// far (the resolution in progress marked partial) are printed and written, exit 130 / 143.
#include <algorithm>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>

#include "cli/interrupt.h"
#include "cli/outputs.h"
#include "cli/registry.h"
#include "cli/verdict.h"
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
    check_outputs({{"--json", opt->json}});
    opt->check.tip_radius_m = 1e-3 * opt->tip_radius_mm;
    // Ctrl-C / SIGTERM (cli/interrupt.h): the sweep stops before its next probe; the rows so far
    // are printed, judged and written to --json marked partial, exit 130 / 143.
    const StopOnSignal stop;
    opt->check.stop_request = &stop.flag();
    std::fprintf(stderr,
                 "crosscheck contact: %zu resolution(s) x %zu model(s), %d probes x %zu forces "
                 "each (minutes at 256^3 and 512^3; Ctrl-C writes the rows so far)\n",
                 opt->check.resolutions.size(), opt->check.models.size(), opt->check.probes,
                 opt->check.forces_n.size());
    const ContactCrosscheckResult r = crosscheck_contact(opt->check);
    opt->check.stop_request = nullptr;
    constexpr double kRippleAim = 0.05;  // the aim (#16), reported only
    for (const ContactSweepRow& row : r.rows) {
      std::printf(
          "crosscheck contact: model=%s n=%d h=%.4f mm probes=%ld runs=%ld pop_throughs=%ld (runs "
          "whose tip went into the tooth) max_penetration_over_radius=%.4f (x tip radius) "
          "sliding_ripple_rms=%.4f (RMS force error / push force; aim %.2f: %s)\n",
          row.model.c_str(), row.resolution, 1e3 * row.voxel_size_m, row.probes, row.runs,
          row.pop_throughs, row.max_penetration_over_radius, row.sliding_ripple_rms, kRippleAim,
          row.partial                             ? "not measured: interrupted"
          : row.sliding_ripple_rms <= kRippleAim ? "met"
                                                 : "not met, reported only");
      if (!row.partial) {
        std::printf(
            "crosscheck contact: model=%s n=%d closed loop (rigid device, pmi-pd, F/K <= R/3): "
            "closed_loop_ripple_rms=%.4f (what the hand feels) geometric_ripple_rms=%.4f (the "
            "model's shape error along the loop's path) dynamic_ripple_rms=%.4f (felt minus "
            "shape, tick by tick) exact_sphere_ripple_rms=%.4f (the same loop on the exact "
            "sphere), largest over the forces\n",
            row.model.c_str(), row.resolution, row.closed_loop_ripple_rms,
            row.geometric_ripple_rms, row.dynamic_ripple_rms, row.exact_sphere_ripple_rms);
      }
    }
    std::printf("verdict (the default model, sdf):\n");
    Verdict v("crosscheck contact");
    long sdf_runs = 0;
    for (const ContactSweepRow& row : r.rows) {
      if (row.model != "sdf") continue;
      sdf_runs += row.runs;
      const std::string at = "sdf n=" + std::to_string(row.resolution);
      v.check(at + " pop_throughs [runs]", static_cast<double>(row.pop_throughs), 0.0);
      // The skin s = min(rho/4, h/2) (docs/derivations/sdf_contact.md §2), over rho.
      const double skin = std::min(0.25, 0.5 * row.voxel_size_m / opt->check.tip_radius_m);
      v.check(at + " max_penetration_over_radius", row.max_penetration_over_radius, skin, "x rho");
    }
    v.require("sdf runs compared", sdf_runs > 0, std::to_string(sdf_runs) + " runs");
    nlohmann::json j = crosscheck_contact_json(r);
    j["verdict"] = v.ok() ? "PASS" : "FAIL";
    j["failed_checks"] = v.failed();
    j["sliding_ripple_aim"] = kRippleAim;
    if (r.stopped) {
      const std::string why = "stopped by " + stop.signal_name() + " at " + r.stopped_at;
      j["partial"] = true;
      j["partial_reason"] = why;
      if (!opt->json.empty()) write_json(opt->json, j);
      throw Interrupted("crosscheck contact " + why + " (the checks above are over the runs so "
                            "far)" +
                            (opt->json.empty() ? std::string("; no --json given, nothing written")
                                               : "; partial results in " + opt->json +
                                                     " (\"partial\": true)"),
                        stop.exit_status());
    }
    if (!opt->json.empty()) write_json(opt->json, j);
    v.finish();
  });
}
DENTSIM_REGISTER_COMMAND(setup_crosscheck_contact);

}  // namespace
}  // namespace dentsim::cli
