// The device backends, named once: what a scene's device.type and a command's --device may say.
//   simulated-phantom  the MuJoCo-simulated Phantom Premium 1.5/6DoF (device/simulated_phantom.h),
//                      the embedded default
//   hdapi              a Phantom through OpenHaptics' HDAPI, or the project's emulator of that
//                      library (device/hdapi/hdapi_device.h; docs/hardware.md)
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace dentsim {

enum class DeviceBackend { kSimulatedPhantom, kHdapi };

// The backend named `name`, or nullopt.
std::optional<DeviceBackend> find_device_backend(std::string_view name);
const char* device_backend_name(DeviceBackend backend);
// Every name, in the order above (for a command-line option's allowed values).
std::vector<std::string> device_backend_names();
// "simulated-phantom or hdapi" (each name wrapped in `quote`), for messages.
std::string device_backend_list(std::string_view quote = "");

}  // namespace dentsim
