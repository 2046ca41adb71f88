// `dentsim crosscheck octree`: the full octree's sphere queries against brute force over the flat
// voxel array, on random and adversarial spheres (validation/crosscheck_octree.h). Prints and
// writes (--json) `queries` and `mismatches`; exit status 1 if any query mismatched. The JSON also
// holds the octree memory per resolution 32..512 (docs/tooth_octree.md).
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>

#include "cli/registry.h"
#include "reference/core/io.h"
#include "reference/tooth/octree.h"
#include "validation/crosscheck_octree.h"

namespace dentsim::cli {
namespace {

struct Options {
  std::string json;
  OctreeCrosscheckOptions check;
};

nlohmann::json memory_table() {
  nlohmann::json rows = nlohmann::json::array();
  for (int n = 32; n <= 512; n *= 2) {
    int levels = 0;
    while ((1 << levels) < n) ++levels;
    const std::size_t masks = FullOctree::internal_node_count(levels);
    const std::size_t total = FullOctree::memory_bytes_for(n);
    const std::size_t nn = static_cast<std::size_t>(n);
    rows.push_back({{"n", n},
                    {"levels", levels},
                    {"internal_nodes", masks},
                    {"mask_bytes", masks},
                    {"leaf_bytes", nn * nn * nn},
                    {"octree_bytes", total},
                    {"neighbor_code_bytes", nn * nn * nn},
                    {"drill_work_bytes", nn * nn * nn * sizeof(double)}});
  }
  return rows;
}

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
    check_output_paths({{"--json", opt->json}});
    const OctreeCrosscheckResult r = crosscheck_octree(opt->check);
    std::printf(
        "crosscheck octree: n=%d seed=%llu queries=%ld mismatches=%ld nonempty=%ld "
        "voxels_matched=%ld removals=%ld\n",
        opt->check.n, static_cast<unsigned long long>(opt->check.seed), r.queries, r.mismatches,
        r.nonempty_queries, r.voxels_matched, r.removals);
    if (!opt->json.empty()) {
      nlohmann::json by_placement = nlohmann::json::object();
      for (int p = 0; p < static_cast<int>(SpherePlacement::kCount); ++p) {
        by_placement[sphere_placement_name(static_cast<SpherePlacement>(p))] = r.by_placement[p];
      }
      nlohmann::json j = {{"n", opt->check.n},
                          {"seed", opt->check.seed},
                          {"remove_every", opt->check.remove_every},
                          {"queries", r.queries},
                          {"mismatches", r.mismatches},
                          {"nonempty_queries", r.nonempty_queries},
                          {"voxels_matched", r.voxels_matched},
                          {"removals", r.removals},
                          {"by_placement", by_placement},
                          {"first_mismatch", r.first_mismatch},
                          {"memory_per_resolution", memory_table()}};
      write_json(opt->json, j);
    }
    if (r.mismatches > 0) {
      throw std::runtime_error("crosscheck octree: " + std::to_string(r.mismatches) +
                               " mismatches; first: " + r.first_mismatch);
    }
  });
}
DENTSIM_REGISTER_COMMAND(setup_crosscheck_octree);

}  // namespace
}  // namespace dentsim::cli
