// `dentsim crosscheck device [--model FILE] [--json FILE]`: the analytic Phantom model against
// its MuJoCo model (validation/crosscheck_device.h); JSON keys are a contract (issue #3).
#include <cstdio>
#include <memory>
#include <string>

#include "cli/outputs.h"
#include "cli/registry.h"
#include "cli/verdict.h"
#include "reference/core/io.h"
#include "reference/phantom/phantom_params.h"
#include "validation/crosscheck_device.h"

namespace dentsim::cli {
namespace {

// The bounds of the verdict (docs/phantom.md §5 "Tolerance policy").
constexpr double kMaxRel = 1e-9, kTrajectoryRad = 1e-6, kMinRangeRad = 0.01;

struct CrosscheckDeviceOptions {
  std::string model;
  std::string json;
  int samples = 1000;
  std::uint64_t seed = 20021;
  double duration_s = 1.0;
};

void setup_crosscheck_device(CLI::App& app) {
  CLI::App* cc = group(app, "crosscheck", "Differential checks against independent oracles");
  auto o = std::make_shared<CrosscheckDeviceOptions>();
  CLI::App* sub = cc->add_subcommand(
      "device",
      "Analytic Phantom model vs MuJoCo 2.2.2: M, C qd, g, tip pose and Jacobian on\n"
      "random states within the joint limits, and a trajectory under random torques (--duration);\n"
      "PASS / FAIL against the stated bounds, exit 1 on FAIL");
  sub->add_option("--model", o->model, "device model file (default: built-in Premium 1.5A)");
  sub->add_option("--json", o->json, "write the error report as JSON to FILE");
  sub->add_option("--samples", o->samples, "random states (>= 1)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000000));
  sub->add_option("--seed", o->seed, "random seed, 0..2^64-1")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--duration", o->duration_s, "trajectory length [s] (> 0)")
      ->capture_default_str()
      ->check(CLI::Range(1e-6, 1e6));
  sub->callback([o] {
    check_outputs({{"--json", o->json}}, {}, {{"--model", o->model}});
    const PhantomParams params =
        o->model.empty() ? default_phantom_params() : load_phantom_params(o->model);
    DeviceCrosscheckOptions opt;
    opt.samples = o->samples;
    opt.seed = o->seed;
    opt.trajectory_s = o->duration_s;
    const DeviceCrosscheckResult r = crosscheck_device(params, opt);
    nlohmann::json j = crosscheck_device_json(r);
    std::printf("crosscheck device: %d samples, seed %llu\n", r.samples,
                static_cast<unsigned long long>(r.seed));
    for (const char* key : {"mass_matrix", "bias", "gravity", "pose", "jacobian"}) {
      std::printf("  %-12s max_abs %.3e  max_rel %.3e\n", key, j[key]["max_abs"].get<double>(),
                  j[key]["max_rel"].get<double>());
    }
    std::printf("  trajectory   max_abs_rad %.3e over %.3f s (moved %.3f rad)\n",
                r.trajectory_max_abs_rad, r.trajectory_s, r.trajectory_range_rad);
    // The verdict against docs/phantom.md §5's bounds: each static quantity to 1e-9 relative on a
    // reference that is not zero, the trajectory to 1e-6 rad (closure too) while the device moved
    // at least 0.01 rad (a trajectory that did not move compared nothing).
    Verdict v("crosscheck device");
    const std::pair<const char*, const QuantityError*> quantities[] = {
        {"mass_matrix", &r.mass_matrix},
        {"bias", &r.bias},
        {"gravity", &r.gravity},
        {"pose", &r.pose},
        {"jacobian", &r.jacobian}};
    for (const auto& [key, e] : quantities) {
      v.check(std::string(key) + ".max_rel", e->max_rel, kMaxRel);
      char ref[32];
      std::snprintf(ref, sizeof ref, "largest %.3g", e->max_ref);
      v.require(std::string(key) + " reference is not zero", e->max_ref > 0.0, ref);
    }
    v.check("trajectory.max_abs_rad", r.trajectory_max_abs_rad, kTrajectoryRad, "rad");
    v.check("trajectory closure", r.trajectory_max_closure_rad, kTrajectoryRad, "rad");
    v.check("trajectory range (the device moved)", r.trajectory_range_rad, kMinRangeRad, "rad",
            true);
    j["verdict"] = v.ok() ? "PASS" : "FAIL";
    j["failed_checks"] = v.failed();
    j["bounds"] = {{"max_rel", kMaxRel},
                   {"trajectory_max_abs_rad", kTrajectoryRad},
                   {"trajectory_min_range_rad", kMinRangeRad}};
    if (!o->json.empty()) write_json(o->json, j);
    v.finish();
  });
}
DENTSIM_REGISTER_COMMAND(setup_crosscheck_device);

}  // namespace
}  // namespace dentsim::cli
