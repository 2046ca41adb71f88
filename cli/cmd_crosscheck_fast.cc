// `dentsim crosscheck fast`: the fast pipeline against the reference, per stage on the drill
// scene's states and in closed loop on the built-in scenes (validation/crosscheck_fast.h).
// Prints and writes (--json) per stage `max_rel`, per scene `max_force_diff_n` and `ticks`; exit
// status 1 when a bound is broken.
#include <algorithm>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>

#include "cli/outputs.h"
#include "cli/registry.h"
#include "cli/verdict.h"
#include "reference/core/io.h"
#include "reference/tooth/materials.h"
#include "validation/crosscheck_fast.h"

namespace dentsim::cli {
namespace {

struct Options {
  std::string json;
  FastCrosscheckOptions check;
};

void run(const Options& o) {
  if (o.check.stage_ticks < 1 || o.check.stage_ticks > 1000000) {
    throw InputError("--stage-ticks must be in [1, 1000000]");
  }
  if (!(o.check.scene_duration_s > 0.0) || o.check.scene_duration_s > 3600.0) {
    throw InputError("--duration must be in (0, 3600] s");
  }
  check_outputs({{"--json", o.json}});
  const FastCrosscheckResult r = crosscheck_fast(o.check);
  nlohmann::json stages = nlohmann::json::object();
  for (const StageCrosscheck& s : r.stages) {
    std::printf("  %-6s %-13s max_rel %.3e over %ld samples, count mismatches %ld\n",
                s.implementation.c_str(), s.stage.c_str(), s.max_rel, s.samples,
                s.count_mismatches);
    stages[s.stage] = {{"implementation", s.implementation},
                       {"max_rel", s.max_rel},
                       {"samples", s.samples},
                       {"contact_samples", s.contact_samples},
                       {"count_mismatches", s.count_mismatches}};
  }
  // Adversarial states: per perturbation, the worst stage and every stage's max_rel.
  nlohmann::json adversarial = nlohmann::json::object();
  for (const AdversarialCrosscheck& a : r.adversarial) {
    nlohmann::json& p = adversarial[a.perturbation];
    if (p.is_null()) {
      p = {{"implementation", a.implementation},
           {"samples", a.samples},
           {"contact_samples", a.contact_samples},
           {"saturated_samples", a.saturated_samples},
           {"max_rel", 0.0},
           {"count_mismatches", 0},
           {"stages", nlohmann::json::object()}};
    }
    p["stages"][a.stage] = a.max_rel;
    p["max_rel"] = std::max(p["max_rel"].get<double>(), a.max_rel);
    p["count_mismatches"] = p["count_mismatches"].get<long>() + a.count_mismatches;
    if (a.stage == "command") {
      p["saturated_samples"] = a.saturated_samples;
      std::printf(
          "  %-6s adversarial %-17s max_rel %.3e over %ld samples (%ld in contact, %ld "
          "saturated)\n",
          a.implementation.c_str(), a.perturbation.c_str(), p["max_rel"].get<double>(), a.samples,
          a.contact_samples, a.saturated_samples);
    }
  }
  nlohmann::json materials = nlohmann::json::object();
  std::printf("  contact members seen stage by stage, per material:");
  for (int m = 1; m < kMaterialCount; ++m) {
    const long n = r.contact_members_per_material[static_cast<std::size_t>(m)];
    materials[material_properties(static_cast<std::uint8_t>(m)).name] = n;
    std::printf(" %s %ld", material_properties(static_cast<std::uint8_t>(m)).name, n);
  }
  std::printf("\n");
  nlohmann::json scenes = nlohmann::json::object();
  for (const SceneCrosscheck& c : r.scenes) {
    std::printf(
        "  %-6s %-6s %ld ticks (%ld in contact): max |force diff| %.3e N (largest force "
        "%.3f N); before contact %.3e N; diverged past 1e-9 N at %.3f s, 1e-6 N at %.3f "
        "s, 1e-3 N at %.3f s (-1: never)\n",
        c.implementation.c_str(), c.scene.c_str(), c.ticks, c.contact_ticks, c.max_force_diff_n,
        c.max_force_n, c.max_force_diff_before_contact_n, c.diverged_1e9_s, c.diverged_1e6_s,
        c.diverged_1e3_s);
    scenes[c.scene] = {{"implementation", c.implementation},
                       {"ticks", c.ticks},
                       {"contact_ticks", c.contact_ticks},
                       {"max_force_diff_n", c.max_force_diff_n},
                       {"max_force_diff_before_contact_n", c.max_force_diff_before_contact_n},
                       {"max_force_n", c.max_force_n},
                       {"first_contact_s", c.first_contact_s},
                       {"diverged_past_1e-9_n_at_s", c.diverged_1e9_s},
                       {"diverged_past_1e-6_n_at_s", c.diverged_1e6_s},
                       {"diverged_past_1e-3_n_at_s", c.diverged_1e3_s}};
  }
  // The verdict: every bound printed with its value; a check that saw no contact compared the
  // contact stages on nothing and fails saying so (e.g. --stage-ticks 500 ends before the bur
  // touches the tooth).
  std::printf("verdict:\n");
  Verdict v("crosscheck fast");
  long stage_contacts = 0;
  for (const StageCrosscheck& s : r.stages) {
    v.check(s.implementation + " " + s.stage + " max_rel", s.max_rel, o.check.max_rel_bound);
    if (s.count_mismatches != 0) {
      v.check(s.implementation + " " + s.stage + " count mismatches",
              static_cast<double>(s.count_mismatches), 0.0);
    }
    stage_contacts = std::max(stage_contacts, s.contact_samples);
  }
  v.require("stage check saw contact", stage_contacts > 0,
            std::to_string(stage_contacts) + " contact samples");
  for (const SceneCrosscheck& c : r.scenes) {
    v.check(c.scene + " force diff before contact", c.max_force_diff_before_contact_n, 1e-9, "N");
    v.check(c.scene + " force diff vs largest force", c.max_force_diff_n, c.max_force_n, "N");
    v.require(c.scene + " saw contact", c.contact_ticks > 0,
              std::to_string(c.contact_ticks) + " contact ticks");
  }
  v.require("adversarial states, loops (every other bound)", r.ok,
            r.ok ? "all held" : std::to_string(r.failures.size()) + " failed");
  if (!o.json.empty()) {
    write_json(o.json, {{"stages", stages},
                        {"scenes", scenes},
                        {"adversarial", adversarial},
                        {"contact_members_per_material", materials},
                        {"max_rel_bound", o.check.max_rel_bound},
                        {"ok", r.ok && v.ok()},
                        {"verdict", v.ok() && r.ok ? "PASS" : "FAIL"},
                        {"failed_checks", v.failed()},
                        {"failures", r.failures}});
  }
  for (const std::string& f : r.failures) std::printf("  failure: %s\n", f.c_str());
  v.finish();
}

void setup_crosscheck_fast(CLI::App& app) {
  CLI::App* group_app = group(app, "crosscheck", "Cross-checks against an independent oracle");
  CLI::App* sub = group_app->add_subcommand(
      "fast", "The fast pipeline vs the reference: per stage (max_rel) and in closed loop");
  auto opt = std::make_shared<Options>();
  sub->add_option("--json", opt->json, "Write the results (stages, scenes, ...) to FILE");
  sub->add_option("--stage-ticks", opt->check.stage_ticks,
                  "Ticks of the drill scene checked stage by stage")
      ->capture_default_str();
  sub->add_option("--duration", opt->check.scene_duration_s, "Closed-loop run per scene [s]")
      ->capture_default_str();
  sub->callback([opt] { run(*opt); });
}
DENTSIM_REGISTER_COMMAND(setup_crosscheck_fast);

}  // namespace
}  // namespace dentsim::cli
