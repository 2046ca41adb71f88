// `dentsim device show [MODEL]` and `dentsim device check MODEL`: the Phantom device model file
// (reference/phantom/phantom_params.h, format in docs/phantom.md).
#include <cstdio>
#include <memory>
#include <string>

#include "cli/registry.h"
#include "device/phantom_device.h"
#include "device/simulated_phantom.h"
#include "reference/core/io.h"
#include "reference/phantom/phantom_params.h"

namespace dentsim::cli {
namespace {

struct DeviceOptions {
  std::string model;
  int workspace_samples = 256;
};

void setup_device(CLI::App& app) {
  CLI::App* device = group(app, "device", "Device model files (Phantom Premium 1.5/6DoF)");

  auto show_opts = std::make_shared<DeviceOptions>();
  CLI::App* show = device->add_subcommand(
      "show",
      "Print a device model file (the built-in Premium 1.5A default when none is given),\n"
      "validated, so a new device can start from it");
  show->add_option("MODEL", show_opts->model, "device model file (JSON)");
  show->callback([show_opts] {
    const std::string text = show_opts->model.empty()
                                 ? default_phantom_model_file()
                                 : phantom_params_to_text(load_phantom_params(show_opts->model));
    std::fputs(text.c_str(), stdout);
  });

  auto check_opts = std::make_shared<DeviceOptions>();
  CLI::App* check = device->add_subcommand(
      "check",
      "Validate a device model file: every field, M(q) positive definite over the\n"
      "joint-limit box, and the simulated device `run` builds from it; exit 0 if valid,\n"
      "2 with a message naming the field otherwise");
  check->add_option("MODEL", check_opts->model, "device model file (JSON)")->required();
  check
      ->add_option("--workspace-samples", check_opts->workspace_samples,
                   "random joint-limit-box points (besides its centre and 64 corners) at which\n"
                   "M(q) must be positive definite")
      ->check(CLI::Range(0, 100000000));
  check->callback([check_opts] {
    const PhantomParams p = load_phantom_params(check_opts->model);  // validates with 256 points
    const std::string origin = "device model file '" + check_opts->model + "'";
    validate_phantom_params(p, origin, check_opts->workspace_samples);
    // Valid means `run` can run it: build the simulated device exactly as run_scene does
    // (MuJoCo plant from the generated MJCF, driver configuration, home pose).
    try {
      const MujocoPlant plant = phantom_plant(p);
      const SimulatedPhantom sim(plant, phantom_device_config(p), phantom_home_q(p));
    } catch (const InputError& e) {
      throw InputError(origin + ": the simulated device cannot be built from it: " +
                       printable(e.what(), 300));
    }
    std::printf("%s: valid device model \"%s\"\n", check_opts->model.c_str(), p.name.c_str());
  });
}
DENTSIM_REGISTER_COMMAND(setup_device);

}  // namespace
}  // namespace dentsim::cli
