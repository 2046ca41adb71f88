#include "validation/wall_demo.h"

#include "reference/tools.h"

namespace dentsim {

WallLoopConfig wall_demo_config(const WallDemo& demo, Method method) {
  WallLoopConfig c;
  c.device.mass = 0.075;  // apparent tip mass of a Phantom Premium (< 75 g)
  c.device.inertia = Mat3::Identity() * 2e-4;
  c.device.damping_lin = 0.5;  // physical device damping b_d [N s/m]
  c.device.damping_ang = 0.002;
  c.pipeline.method = method;
  c.pipeline.proxy.mass = 0.02;
  c.pipeline.proxy.inertia = Mat3::Identity() * 2e-6;
  c.pipeline.coupling.k_lin = demo.k_vc;
  c.pipeline.coupling.b_lin = 0.05;
  c.pipeline.coupling.k_ang = 0.3;
  c.pipeline.coupling.b_ang = 1e-4;
  c.pipeline.tool = tool_preset("handpiece");
  c.pipeline.observer_gain = VecX::Constant(6, 100.0);
  c.wall_stiffness = demo.k_tooth;
  c.tick = demo.tick;
  c.duration = demo.duration_s;
  // The hand is a force source with a little damping: at rest the force fed back equals the push.
  c.hand.stiffness = 0.0;
  c.hand.damping = 2.0;
  c.hand.push = Vec3(0.0, 0.0, -demo.push_n);
  c.start = Vec3(0.0, 0.0, c.tip_radius + 2e-4);
  return c;
}

std::vector<WallDemoRun> run_wall_demo(const WallDemo& demo) {
  std::vector<WallDemoRun> runs;
  for (Method m : demo.methods) {
    WallDemoRun r;
    r.method = m;
    r.loop = run_wall_loop(wall_demo_config(demo, m));
    r.static_stiffness_n_per_m =
        r.loop.final_device_depth_m > 0 ? r.loop.final_force_n / r.loop.final_device_depth_m : 0.0;
    r.passive = r.loop.energy_virtual_j <= 1e-6;
    runs.push_back(r);
  }
  return runs;
}

nlohmann::json wall_demo_json(const WallDemo& demo, const std::vector<WallDemoRun>& runs) {
  nlohmann::json out;
  out["scenario"] = "rigid-body device, hand pushing into a flat wall";
  out["duration_s"] = demo.duration_s;
  out["tick_s"] = demo.tick;
  out["k_vc_n_per_m"] = demo.k_vc;
  out["k_tooth_n_per_m"] = demo.k_tooth;
  out["push_n"] = demo.push_n;
  for (const WallDemoRun& run : runs) {
    const WallLoopResult& r = run.loop;
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
    j["static_stiffness_n_per_m"] = run.static_stiffness_n_per_m;
    j["virtual_energy_generated_j"] = r.energy_virtual_j;
    out["methods"][method_name(run.method)] = j;
  }
  return out;
}

}  // namespace dentsim
