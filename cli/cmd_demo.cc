// `dentsim demo`: a short run of the reference pipeline — an ideal rigid-body device held by a
// scripted hand pressing the tool tip into a stiff flat wall, once per method (explicit, pmi,
// pmi-pd) — printing and (with --json) writing what each rendered. The experiment is
// validation/wall_demo.h; this file parses the flags, prints the table and writes the JSON.
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "cli/outputs.h"
#include "cli/registry.h"
#include "reference/core/io.h"
#include "validation/wall_demo.h"

namespace dentsim::cli {
namespace {

struct DemoOptions {
  std::string json;
  double duration = 1.0;
  double k_vc = 400.0;
  double k_tooth = 1500.0;
  double tick_ms = 1.0;
  double push_n = 2.0;
  std::vector<std::string> methods{"explicit", "pmi", "pmi-pd"};
};

void run_demo(const DemoOptions& o) {
  if (!(o.duration > 0.0)) throw InputError("--duration must be positive");
  if (!(o.tick_ms > 0.0)) throw InputError("--tick-ms must be positive");
  if (!(o.k_vc > 0.0) || !(o.k_tooth > 0.0))
    throw InputError("--k-vc and --k-tooth must be positive");
  check_outputs({{"--json", o.json}});
  WallDemo demo;
  demo.duration_s = o.duration;
  demo.k_vc = o.k_vc;
  demo.k_tooth = o.k_tooth;
  demo.tick = o.tick_ms * 1e-3;
  demo.push_n = o.push_n;
  demo.methods.clear();
  for (const std::string& name : o.methods) demo.methods.push_back(parse_method(name));
  const std::vector<WallDemoRun> runs = run_wall_demo(demo);
  std::printf("%-9s %10s %14s %14s %16s %12s\n", "method", "force[N]", "dev.depth[mm]",
              "stiffness[N/m]", "E_virtual[mJ]", "stable");
  for (const WallDemoRun& run : runs) {
    const WallLoopResult& r = run.loop;
    std::printf("%-9s %10.3f %14.4f %14.1f %16.4f %12s\n", method_name(run.method), r.final_force_n,
                r.final_device_depth_m * 1e3, run.static_stiffness_n_per_m,
                r.energy_virtual_j * 1e3,
                r.finite ? (run.passive ? "passive" : "active") : "diverged");
  }
  if (!o.json.empty()) write_json(o.json, wall_demo_json(demo, runs));
}

void setup_demo(CLI::App& app) {
  auto o = std::make_shared<DemoOptions>();
  CLI::App* sub = app.add_subcommand(
      "demo", "Short reference-pipeline demo: a hand pushes a rigid-body device into a stiff wall");
  sub->add_option("--json", o->json, "Write the results as JSON to FILE");
  sub->add_option("--duration", o->duration, "Simulated time per method [s]")
      ->capture_default_str()
      ->check(finite_range(1e-3, 600.0));
  sub->add_option("--k-vc", o->k_vc, "Virtual coupling stiffness [N/m]")
      ->capture_default_str()
      ->check(finite_range(1e-6, 1e7));
  sub->add_option("--k-tooth", o->k_tooth, "Wall stiffness [N/m]")
      ->capture_default_str()
      ->check(finite_range(1e-6, 1e7));
  sub->add_option("--tick-ms", o->tick_ms, "Servo tick [ms]")
      ->capture_default_str()
      ->check(finite_range(0.05, 100.0));
  sub->add_option("--push", o->push_n, "Hand push into the wall [N]")
      ->capture_default_str()
      ->check(finite_range(0.0, 20.0));
  sub->add_option("--method", o->methods, "Methods to run (explicit, pmi, pmi-pd)")
      ->check(CLI::IsMember({"explicit", "pmi", "pmi-pd"}));
  sub->callback([o] { run_demo(*o); });
}
DENTSIM_REGISTER_COMMAND(setup_demo);

}  // namespace
}  // namespace dentsim::cli
