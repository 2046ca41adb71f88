#include "device/backend.h"

#include <array>

namespace dentsim {

namespace {

struct Named {
  DeviceBackend backend;
  const char* name;
};

constexpr std::array<Named, 2> kBackends = {
    {{DeviceBackend::kSimulatedPhantom, "simulated-phantom"}, {DeviceBackend::kHdapi, "hdapi"}}};

}  // namespace

std::optional<DeviceBackend> find_device_backend(std::string_view name) {
  for (const Named& b : kBackends) {
    if (name == b.name) return b.backend;
  }
  return std::nullopt;
}

const char* device_backend_name(DeviceBackend backend) {
  for (const Named& b : kBackends) {
    if (b.backend == backend) return b.name;
  }
  return "unknown";
}

std::vector<std::string> device_backend_names() {
  std::vector<std::string> names;
  for (const Named& b : kBackends) names.emplace_back(b.name);
  return names;
}

std::string device_backend_list(std::string_view quote) {
  std::string s;
  for (std::size_t i = 0; i < kBackends.size(); ++i) {
    if (i > 0) s += i + 1 == kBackends.size() ? " or " : ", ";
    s += std::string(quote) + kBackends[i].name + std::string(quote);
  }
  return s;
}

}  // namespace dentsim
