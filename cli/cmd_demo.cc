// `dentsim demo`: a short run of the reference pipeline — an ideal rigid-body device held by a
// scripted hand pressing the tool tip into a stiff flat wall, once per method (explicit, pmi,
// pmi-pd) — printing and (with --json) writing what each rendered.
#include <cstdio>
#include <memory>

#include "cli/registry.h"
#include "reference/core/io.h"
#include "reference/tools.h"
#include "validation/wall_loop.h"

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

WallLoopConfig demo_config(const DemoOptions& o, Method m) {
  WallLoopConfig c;
  c.device.mass = 0.075;                  // apparent tip mass of a Phantom Premium (< 75 g)
  c.device.inertia = Mat3::Identity() * 2e-4;
  c.device.damping_lin = 0.5;             // physical device damping b_d [N s/m]
  c.device.damping_ang = 0.002;
  c.pipeline.method = m;
  c.pipeline.proxy.mass = 0.02;
  c.pipeline.proxy.inertia = Mat3::Identity() * 2e-6;
  c.pipeline.coupling.k_lin = o.k_vc;
  c.pipeline.coupling.b_lin = 0.05;
  c.pipeline.coupling.k_ang = 0.3;
  c.pipeline.coupling.b_ang = 1e-4;
  c.pipeline.tool = tool_preset("handpiece");
  c.pipeline.observer_gain = VecX::Constant(6, 100.0);
  c.wall_stiffness = o.k_tooth;
  c.tick = o.tick_ms * 1e-3;
  c.duration = o.duration;
  // The hand is a force source with a little damping: at rest the force fed back equals the push.
  c.hand.stiffness = 0.0;
  c.hand.damping = 2.0;
  c.hand.push = Vec3(0.0, 0.0, -o.push_n);
  c.start = Vec3(0.0, 0.0, c.tip_radius + 2e-4);
  return c;
}

void run_demo(const DemoOptions& o) {
  if (!(o.duration > 0.0)) throw InputError("--duration must be positive");
  if (!(o.tick_ms > 0.0)) throw InputError("--tick-ms must be positive");
  if (!(o.k_vc > 0.0) || !(o.k_tooth > 0.0)) throw InputError("--k-vc and --k-tooth must be positive");
  check_output_paths({{"--json", o.json}});
  nlohmann::json out;
  out["scenario"] = "rigid-body device, hand pushing into a flat wall";
  out["duration_s"] = o.duration;
  out["tick_s"] = o.tick_ms * 1e-3;
  out["k_vc_n_per_m"] = o.k_vc;
  out["k_tooth_n_per_m"] = o.k_tooth;
  out["push_n"] = o.push_n;
  std::printf("%-9s %10s %14s %14s %16s %12s\n", "method", "force[N]", "dev.depth[mm]",
              "stiffness[N/m]", "E_virtual[mJ]", "stable");
  for (const std::string& name : o.methods) {
    const Method m = parse_method(name);
    const WallLoopResult r = run_wall_loop(demo_config(o, m));
    const bool passive = r.energy_virtual_j <= 1e-6;
    std::printf("%-9s %10.3f %14.4f %14.1f %16.4f %12s\n", name.c_str(), r.final_force_n,
                r.final_device_depth_m * 1e3,
                r.final_device_depth_m > 0 ? r.final_force_n / r.final_device_depth_m : 0.0,
                r.energy_virtual_j * 1e3, r.finite ? (passive ? "passive" : "active") : "diverged");
    nlohmann::json j;
    j["ticks"] = r.ticks;
    j["contact_ticks"] = r.contact_ticks;
    j["finite"] = r.finite;
    j["max_force_n"] = r.max_force_n;
    j["max_device_depth_m"] = r.max_device_depth_m;
    j["max_proxy_depth_m"] = r.max_proxy_depth_m;
    j["final_force_n"] = r.final_force_n;
    j["final_device_depth_m"] = r.final_device_depth_m;
    j["rendered_stiffness_n_per_m"] = r.rendered_stiffness();
    j["static_stiffness_n_per_m"] =
        r.final_device_depth_m > 0 ? r.final_force_n / r.final_device_depth_m : 0.0;
    j["virtual_energy_generated_j"] = r.energy_virtual_j;
    out["methods"][name] = j;
  }
  if (!o.json.empty()) write_json(o.json, out);
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
