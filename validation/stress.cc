#include "fast/registry.h"
#include "validation/stress.h"

#include <span>
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <random>

#include "sim/scene.h"
#include "sim/simulator.h"
#include "reference/core/io.h"
#include "reference/tooth/sdf.h"

namespace dentsim {
namespace {

double log_uniform(std::mt19937_64& rng, double lo, double hi) {
  return std::exp(std::uniform_real_distribution<double>(std::log(lo), std::log(hi))(rng));
}

double uniform(std::mt19937_64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

template <typename T, std::size_t N>
const T& pick(std::mt19937_64& rng, const T (&choices)[N]) {
  return choices[std::uniform_int_distribution<std::size_t>(0, N - 1)(rng)];
}

struct Draw {
  std::string scene, pipeline;
  nlohmann::json patch;
};

// One random configuration: a patch of a built-in scene. The scene and the method are not drawn
// but stratified over the run index (every 6 consecutive runs cover each scene x method pair), so
// a short run reaches the surface-proxy contact of the probe under every method whatever the
// seed; the rest is drawn.
Draw draw(std::mt19937_64& rng, long run, long ticks_per_run) {
  static const char* const kScenes[] = {"probe", "drill"};
  static const char* const kMethods[] = {"explicit", "pmi", "pmi-pd"};
  static const double kRates[] = {500.0, 1000.0, 2000.0};
  static const int kResolutions[] = {64, 128};
  Draw d;
  d.scene = kScenes[run % 2];
  const std::span<const Implementation* const> impls = implementations();  // fast/registry.h
  d.pipeline = impls[std::uniform_int_distribution<std::size_t>(0, impls.size() - 1)(rng)]->name();
  const std::string method = kMethods[(run / 2) % 3];
  const double hz = pick(rng, kRates);
  const double duration = static_cast<double>(ticks_per_run) / hz;
  nlohmann::json script = nlohmann::json::array();
  const int keys = 4;
  for (int k = 0; k < keys; ++k) {
    const double t = duration * k / (keys - 1);
    const double z = k == 0 ? uniform(rng, 2.0, 6.0) : uniform(rng, -2.0, 2.0);
    script.push_back({{"t_s", t},
                      {"offset_mm", {uniform(rng, -2.0, 2.0), uniform(rng, -2.0, 2.0), z}},
                      {"force_n",
                       {uniform(rng, -1.0, 1.0), uniform(rng, -1.0, 1.0),
                        k == 0 ? 0.0 : -uniform(rng, 0.0, 5.0)}},
                      {"phase", "stress"}});
  }
  d.patch = {{"duration_s", duration},
             {"tick_hz", hz},
             {"tooth",
              {{"resolution", pick(rng, kResolutions)},
               {"k_tooth_n_per_m", log_uniform(rng, 1000.0, 40000.0)},
               {"b_tooth_n_s_per_m", uniform(rng, 0.0, 10.0)}}},
             {"device", {{"jitter_us", uniform(rng, 0.0, 0.4 * 0.5e6 / hz)}}},
             {"method",
              {{"name", method},
               {"k_vc_n_per_m", log_uniform(rng, 100.0, 8000.0)},
               {"b_vc_n_s_per_m", uniform(rng, 0.0, 12.0)},
               {"friction_mu", uniform(rng, 0.0, 0.6)}}},
             {"hand", {{"script", script}}}};
  if (method != "pmi-pd") d.patch["method"]["grip_detector"] = false;
  return d;
}

StressFaultedRun faulted_run(const Draw& d, const Scene& scene, long run, long tick,
                             const ClosedLoop& loop, const SceneRig& rig, const TickResult& r,
                             long saturated_run, unsigned reversals) {
  StressFaultedRun f;
  f.run = run;
  f.method = d.patch["method"]["name"].get<std::string>();
  f.scene = d.scene;
  f.pipeline = d.pipeline;
  f.tick_hz = scene.tick_hz;
  f.k_tooth = scene.tooth.k_tooth;
  f.b_tooth = scene.tooth.b_tooth;
  f.k_vc = scene.method.coupling.k_lin;
  f.b_vc = scene.method.coupling.b_lin;
  f.proxy_mass_kg = scene.method.proxy.mass;
  f.friction_mu = d.patch["method"]["friction_mu"].get<double>();
  f.jitter_us = scene.device.jitter_us;
  f.resolution = scene.tooth.resolution;
  f.fault = loop.fault_name();
  f.t_s = loop.fault_time();
  f.tick = tick;
  if (loop.supervisor_fault() != SupervisorFault::kNone) f.detail = rig.supervisor->describe();
  f.contact_n = r.F_contact.head<3>().norm();
  f.coupling_n = r.F_coupling.head<3>().norm();
  f.depth_m = r.max_depth;
  f.saturated_run = saturated_run;
  f.reversals_last20 = std::popcount(reversals);
  f.patch = d.patch.dump();
  return f;
}

}  // namespace

std::string describe_faulted_run(const StressFaultedRun& f) {
  char b[640];
  std::snprintf(b, sizeof b,
                "run %ld: %s %s %s %.0f Hz, K_tooth %.0f N/m b_tooth %.2f N s/m, K_vc %.0f N/m "
                "b_vc %.2f N s/m, proxy %.0f g, mu %.2f, jitter %.0f us, %d^3: %s at %.4f s "
                "(tick %ld)%s%s; contact %.2f N, coupling %.2f N, depth %.3f mm, saturated %ld "
                "ticks in a row, %d of the last 20 ticks reversed the proxy",
                f.run, f.method.c_str(), f.scene.c_str(), f.pipeline.c_str(), f.tick_hz, f.k_tooth,
                f.b_tooth, f.k_vc, f.b_vc, f.proxy_mass_kg * 1e3, f.friction_mu, f.jitter_us,
                f.resolution, f.fault.c_str(), f.t_s, f.tick, f.detail.empty() ? "" : ": ",
                f.detail.c_str(), f.contact_n, f.coupling_n, f.depth_m * 1e3, f.saturated_run,
                f.reversals_last20);
  return b;
}

StressResult run_stress(const StressConfig& c,
                        const std::function<void(const StressResult&, long)>& progress) {
  if (c.ticks < 1 || c.ticks_per_run < 10) {
    throw InputError("stress: expected ticks >= 1 and ticks_per_run >= 10");
  }
  StressResult res;
  std::mt19937_64 rng(c.seed);
  auto violate = [&res](const std::string& what) {
    if (res.violations++ == 0) res.first_violation = what;
  };
  nlohmann::json variant;
  if (!c.variant_patch.empty()) {
    variant = nlohmann::json::parse(c.variant_patch, nullptr, false);
    if (variant.is_discarded() || !variant.is_object()) {
      throw InputError("stress: the variant patch is not a JSON object: " + c.variant_patch);
    }
  }
  while (res.ticks < c.ticks) {
    Draw d = draw(rng, res.runs, c.ticks_per_run);
    if (!variant.is_null()) d.patch.merge_patch(variant);
    Scene scene;
    try {
      scene = load_scene_patched(d.scene, d.patch, "(stress run " + std::to_string(res.runs) + ")");
    } catch (const InputError&) {
      ++res.rejected_configs;
      continue;
    }
    if (res.runs < c.first_run ||
        (!c.only_method.empty() && d.patch["method"]["name"] != c.only_method) ||
        (!c.only_scene.empty() && d.scene != c.only_scene)) {
      ++res.skipped_runs;
      ++res.runs;
      res.ticks += std::min(c.ticks_per_run, c.ticks - res.ticks);
      continue;
    }
    SceneRigOptions o;
    o.pipeline = d.pipeline;
    const std::unique_ptr<SceneRig> rig = build_scene_rig(scene, o);
    ClosedLoop& loop = *rig->loop;
    const Device& device = *rig->loop_device;
    const VecX& tau_max = rig->device->limits().tau_max;
    const double rho = rig->tip.radius;
    const std::string where = "stress seed " + std::to_string(c.seed) + " run " +
                              std::to_string(res.runs) + " (" + d.scene + ", " + d.pipeline + ", " +
                              d.patch.dump() + ")";
    const std::string method = d.patch["method"]["name"].get<std::string>();
    ++res.runs_by_method[method];
    // The surface proxy on a tooth the tool does not drill: the rendered tip never enters it.
    const bool check_outside =
        scene.tooth.contact_model == "sdf" && !rig->contacts->drills() && rig->tooth != nullptr;
    const double skin = std::min(0.25 * rho, 0.5 * rig->tooth->grid().voxel_size);
    bool exploded = false;
    double run_force = 0.0, run_depth = 0.0;
    long saturated_run = 0;  // the device's ticks saturated in a row
    unsigned reversals = 0;  // bit j: the proxy's velocity reversed j ticks ago
    Vec3 v_prev = Vec3::Zero();
    loop.start();
    double t_prev = loop.sample().t;
    for (long k = 0; k < c.ticks_per_run && res.ticks < c.ticks && !loop.faulted(); ++k) {
      const TickResult& r = loop.step();
      ++res.ticks;
      const std::string at = where + " tick " + std::to_string(k);
      const VecX& applied = device.applied_torque();
      for (Eigen::Index i = 0; i < applied.size(); ++i) {
        const double ratio = std::abs(applied[i]) / tau_max[i];
        res.worst_torque_ratio = std::max(res.worst_torque_ratio, ratio);
        if (!(ratio <= 1.0 + 1e-12))
          violate("torque beyond the limit on joint " + std::to_string(i + 1) + " at " + at);
      }
      if (loop.faulted()) {
        if (!applied.isZero(0.0)) violate("non-zero torque after the fault at " + at);
        ++res.faults[loop.fault_name()];
        res.faulted_runs.push_back(
            faulted_run(d, scene, res.runs, k, loop, *rig, r, saturated_run, reversals));
        break;
      }
      saturated_run = r.saturated ? saturated_run + 1 : 0;
      const Vec3 v = r.V_hat.head<3>();
      reversals = ((reversals << 1) | (v.dot(v_prev) < 0.0 ? 1u : 0u)) & 0xFFFFFu;
      v_prev = v;
      if (!r.tau.allFinite() || !r.T1.allFinite() || !rig->pipeline->proxy().pose.x.allFinite() ||
          !rig->pipeline->proxy().pose.R.allFinite()) {
        violate("a non-finite output without a fault at " + at);
      }
      const double t = loop.sample().t;
      if (!(t > t_prev)) violate("the device clock did not advance at " + at);
      t_prev = t;
      if (!exploded && (rig->pipeline->proxy().pose.x - r.device.x).norm() > 1.0) {
        exploded = true;
        ++res.exploded[method];
        if (method != "explicit") violate("the proxy left the workspace under PMI at " + at);
      }
      if (check_outside && !r.contacts.empty()) {
        // g = x_o + rho n (reference/tooth/sdf.h): phi(g) >= rho - s by construction.
        const Contact& contact = r.contacts[0];
        const Vec3 g = contact.x_o + rho * contact.n;
        const double phi = signed_distance(*rig->tooth, g, 2.0 * rho).phi;
        ++res.surface_checks;
        res.min_clearance_over_radius = std::min(res.min_clearance_over_radius, (phi - rho) / rho);
        if (!(phi >= rho - skin - 1e-9)) {
          violate("the rendered tip entered the tooth (phi(g) = " + std::to_string(phi * 1e3) +
                  " mm, rho - s = " + std::to_string((rho - skin) * 1e3) + " mm) at " + at);
        }
      }
      run_force = std::max(run_force, r.F_contact.head<3>().norm());
      run_depth = std::max(run_depth, r.max_depth / rho);
    }
    if (!exploded) {
      res.worst_contact_force_n = std::max(res.worst_contact_force_n, run_force);
      res.worst_depth_over_radius = std::max(res.worst_depth_over_radius, run_depth);
      double& worst = res.worst_depth_by_method[method];
      if (run_depth > worst) {
        worst = run_depth;
        res.worst_depth_run[method] = where;
      }
    }
    ++res.runs;
    if (progress) progress(res, c.ticks);
  }
  return res;
}

}  // namespace dentsim
