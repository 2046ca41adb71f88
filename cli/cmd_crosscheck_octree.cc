// `dentsim crosscheck octree`: the full octree's sphere queries against brute force over the flat
// voxel array, on random and adversarial spheres (validation/crosscheck_octree.h). Prints and
// writes (--json) `queries` and `mismatches`; exit status 1 if any query mismatched. The JSON also
// holds the octree memory per resolution 32..512 (docs/tooth_octree.md). The check, the memory
// table and the JSON are validation/crosscheck_octree.h; this file parses the flags and prints.
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>

#include "cli/outputs.h"
#include "cli/registry.h"
#include "cli/verdict.h"
#include "reference/core/io.h"
#include "reference/tooth/octree.h"
#include "validation/crosscheck_octree.h"

namespace dentsim::cli {
namespace {

struct Options {
  std::string json;
  OctreeCrosscheckOptions check;
};

void setup_crosscheck_octree(CLI::App& app) {
  CLI::App* group_app = group(app, "crosscheck", "Cross-checks against an independent oracle");
  CLI::App* sub = group_app->add_subcommand(
      "octree", "Full-octree sphere queries vs brute force over the voxel array (exact sets)");
  auto opt = std::make_shared<Options>();
  sub->add_option("--json", opt->json, "Write the results (queries, mismatches, ...) to FILE");
  sub->add_option("--n", opt->check.n, "Grid resolution N (power of two, 2..128)")
      ->capture_default_str();
  sub->add_option("--spheres", opt->check.spheres, "Number of random sphere queries")
      ->capture_default_str();
  sub->add_option("--seed", opt->check.seed, "Random seed (std::mt19937_64), 0..2^64-1")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--remove-every", opt->check.remove_every,
                  "Remove a random voxel every K queries (0: never)")
      ->capture_default_str();
  sub->callback([opt] {
    check_outputs({{"--json", opt->json}});
    const OctreeCrosscheckResult r = crosscheck_octree(opt->check);
    std::printf(
        "crosscheck octree: n=%d seed=%llu queries=%ld mismatches=%ld nonempty=%ld "
        "voxels_matched=%ld removals=%ld\n",
        opt->check.n, static_cast<unsigned long long>(opt->check.seed), r.queries, r.mismatches,
        r.nonempty_queries, r.voxels_matched, r.removals);
    Verdict v("crosscheck octree");
    v.check("mismatches against brute force", static_cast<double>(r.mismatches), 0.0);
    v.require("queries that found voxels", r.nonempty_queries > 0,
              std::to_string(r.nonempty_queries) + " of " + std::to_string(r.queries));
    if (r.mismatches > 0) std::printf("  first mismatch: %s\n", r.first_mismatch.c_str());
    nlohmann::json j = crosscheck_octree_json(opt->check, r);
    j["verdict"] = v.ok() ? "PASS" : "FAIL";
    j["failed_checks"] = v.failed();
    if (!opt->json.empty()) write_json(opt->json, j);
    v.finish();
  });
}
DENTSIM_REGISTER_COMMAND(setup_crosscheck_octree);

}  // namespace
}  // namespace dentsim::cli
