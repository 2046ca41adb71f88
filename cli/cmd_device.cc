// `dentsim device show [MODEL]` and `dentsim device check MODEL`: the Phantom device model file
// (reference/phantom/phantom_params.h, format in docs/phantom.md).
// `dentsim device probe [--device hdapi] [--hd-library PATH]`: finds and starts the device through
// the OpenHaptics backend (device/hdapi/hdapi_device.h), prints what it reports and a few live
// encoder readings; on failure the error names what was tried and the usual causes (exit 1).
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>

#include "cli/registry.h"
#include "device/hdapi/hdapi_device.h"
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

struct ProbeOptions {
  std::string device = "hdapi";
  std::string hd_library;
  int readings = 5;
};

void probe(const ProbeOptions& o) {
  HdapiConfig c;
  c.library = o.hd_library;
  HdapiDevice dev(c);
  const HdDeviceInfo& i = dev.info();
  std::printf("library: %s\n", i.library.c_str());
  std::printf("model: %s\nserial: %s\n", i.model.c_str(), i.serial.c_str());
  std::printf("DoF: %d input, %d output\n", i.input_dof, i.output_dof);
  std::printf("update rate: %d Hz (dentsim asks for %.0f Hz)\n", i.update_rate_hz,
              1.0 / dev.capabilities().nominal_period);
  std::printf("nominal max force: %.3g N, continuous %.3g N; max stiffness %.3g N/mm\n",
              i.max_force_n, i.max_continuous_force_n, i.max_stiffness_n_per_mm);
  std::printf("nominal gimbal continuous torque: %.4g %.4g %.4g mN m\n",
              i.gimbal_max_continuous_mnm[0], i.gimbal_max_continuous_mnm[1],
              i.gimbal_max_continuous_mnm[2]);
  const VecX& tm = dev.limits().tau_max;
  std::printf("torque limits used [N m]: %.4g %.4g %.4g %.4g %.4g %.4g\n", tm[0], tm[1], tm[2],
              tm[3], tm[4], tm[5]);
  if (i.reports_motor_temperature) {
    const std::array<double, 6> t = dev.motor_temperature();
    std::printf("motor temperature (0..1): %.3f %.3f %.3f %.3f %.3f %.3f\n", t[0], t[1], t[2], t[3],
                t[4], t[5]);
  } else {
    std::printf("motor temperature: not reported\n");
  }
  std::printf("encoder readings, dentsim convention q1..q6 [rad]:\n");
  DeviceSample s = dev.make_sample();
  for (int k = 0; k < o.readings; ++k) {
    if (k > 0) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    dev.read(s);
    std::printf("  t = %8.4f s  q = %9.5f %9.5f %9.5f %9.5f %9.5f %9.5f\n", s.t, s.q[0], s.q[1],
                s.q[2], s.q[3], s.q[4], s.q[5]);
  }
  if (dev.faults() != kFaultNone) {
    throw HdapiError("device reported faults while probing: " + fault_string(dev.faults()));
  }
  std::printf("ok: device started, force output enabled, %ld servo ticks run\n", dev.ticks());
}

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

  auto probe_opts = std::make_shared<ProbeOptions>();
  CLI::App* pr = device->add_subcommand(
      "probe",
      "Find and start the haptic device (OpenHaptics HDAPI): print model, serial, DoF, nominal\n"
      "limits and live encoder readings; exit 1 with what was tried and the usual causes");
  pr->add_option("--device", probe_opts->device, "backend")
      ->check(CLI::IsMember({"hdapi"}))
      ->capture_default_str();
  pr->add_option("--hd-library", probe_opts->hd_library,
                 "HDAPI library (default: $DENTSIM_HD_LIBRARY, else libHD.so, libHD.so.3.0, ...)");
  pr->add_option("--readings", probe_opts->readings, "encoder readings to print, 100 ms apart")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  pr->callback([probe_opts] { probe(*probe_opts); });
}
DENTSIM_REGISTER_COMMAND(setup_device);

}  // namespace
}  // namespace dentsim::cli
