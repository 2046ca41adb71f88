// `dentsim observer-report`: how well the momentum observer (thesis (3.7)-(3.8)) estimates the
// scripted hand's joint torques on the simulated Phantom, with the true device model and with a
// model whose inertia and damping are off by --model-error (validation/observer_report.h,
// docs/simulated_device.md). With --observer-model NAME=FILE (repeatable) the true model is
// compared with the named model files instead (e.g. a calibrated and an uncalibrated model,
// docs/calibration.md). Prints a table; --json writes the numbers.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "cli/outputs.h"
#include "fast/registry.h"
#include "cli/registry.h"
#include "reference/core/io.h"
#include "reference/phantom/phantom_model.h"
#include "reference/phantom/phantom_params.h"
#include "validation/observer_report.h"

namespace dentsim::cli {
namespace {

struct ObserverOptions {
  std::string json;
  std::string model;
  double model_error = 0.2;
  double gain = 100.0;
  bool no_friction = false;
  bool ideal_sensing = false;
  std::vector<std::string> observer_models;  // NAME=FILE
  std::string pipeline = "fast";
};

void setup_observer(CLI::App& app) {
  auto opt = std::make_shared<ObserverOptions>();
  CLI::App* sub = app.add_subcommand(
      "observer-report",
      "Run the momentum observer on the simulated Phantom held by the scripted hand (force step,\n"
      "then motion) and report its steady-state error and lag with the true device model and\n"
      "with inertia and damping off by --model-error");
  sub->add_option("--json", opt->json, "write the numbers to this JSON file");
  sub->add_option("--model,--device", opt->model,
                  "device model file of the simulated Phantom, also the true observer model\n"
                  "(default: the built-in Premium 1.5A model)");
  sub->add_option("--observer-model", opt->observer_models,
                  "NAME=FILE (repeatable): run the observer (and gravity compensation) with the\n"
                  "model file FILE under NAME, after the true model, instead of the scaled model;\n"
                  "FILE 'builtin' is the built-in Premium 1.5A model (used as given: with\n"
                  "--no-friction only the true model drops its Coulomb friction)");
  sub->add_option("--model-error", opt->model_error,
                  "relative error of the perturbed model's inertia and damping (default 0.2)");
  sub->add_option("--gain", opt->gain, "observer gain L [1/s] on every joint (default 100)");
  sub->add_flag("--no-friction", opt->no_friction,
                "simulate the device without Coulomb friction (stiction)");
  sub->add_option("--pipeline", opt->pipeline,
                  "the implementation evaluating the observer's device models: reference\n"
                  "(PhantomModel) or fast (fast::PhantomModel, the fast pipeline's)")
      ->capture_default_str();
  sub->add_flag("--ideal-sensing", opt->ideal_sensing,
                "exact joint angles and velocities (no quantisation, no estimator)");
  sub->callback([opt] {
    check_outputs({{"--json", opt->json}}, {}, {{"--model", opt->model}});
    if (!(std::isfinite(opt->model_error) && opt->model_error > -1.0)) {
      throw InputError("--model-error: expected a finite number > -1, got " +
                       std::to_string(opt->model_error));
    }
    if (!(std::isfinite(opt->gain) && opt->gain > 0.0 && opt->gain * 1e-3 < 2.0)) {
      throw InputError("--gain: expected 0 < L < 2000 1/s (stable at 1 kHz), got " +
                       std::to_string(opt->gain));
    }
    const PhantomParams params =
        opt->model.empty() ? default_phantom_params() : load_phantom_params(opt->model);
    ObserverReportConfig c;
    c.model_error = opt->model_error;
    c.gain_L = opt->gain;
    c.device_friction = !opt->no_friction;
    c.ideal_sensing = opt->ideal_sensing;
    if (find_implementation(opt->pipeline) == nullptr) {
      throw InputError("--pipeline '" + opt->pipeline + "': expected one of " +
                       stage_table_names());
    }
    c.pipeline = opt->pipeline;
    // Named observer models: parse and load them all before running anything.
    std::vector<std::string> names;
    std::vector<std::unique_ptr<DeviceModel>> models;
    for (const std::string& spec : opt->observer_models) {
      const std::size_t eq = spec.find('=');
      if (eq == std::string::npos || eq == 0 || eq + 1 == spec.size()) {
        throw InputError("--observer-model: expected NAME=FILE, got '" + spec + "'");
      }
      const std::string name = spec.substr(0, eq), file = spec.substr(eq + 1);
      if (name == "true" || std::find(names.begin(), names.end(), name) != names.end()) {
        throw InputError("--observer-model: name '" + name + "' is used twice ('true' is the " +
                         "true model's)");
      }
      names.push_back(name);
      models.push_back(observer_device_model(
          file == "builtin" ? default_phantom_params() : load_phantom_params(file), c.pipeline));
    }
    ObserverReport r;
    if (models.empty()) {
      r = run_observer_report(params, c);
    } else {
      const std::unique_ptr<DeviceModel> truth =
          observer_device_model(observer_true_params(params, c), c.pipeline);
      std::vector<NamedObserverModel> list{{"true", truth.get()}};
      for (std::size_t i = 0; i < models.size(); ++i) list.push_back({names[i], models[i].get()});
      r = run_observer_models(params, c, list);
    }
    std::fputs(observer_report_table(r).c_str(), stdout);
    if (!opt->json.empty()) write_file_atomic(opt->json, observer_report_json(r));
  });
}
DENTSIM_REGISTER_COMMAND(setup_observer);

}  // namespace
}  // namespace dentsim::cli
