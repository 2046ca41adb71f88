// Built when CMake found no GLFW or OpenGL (view/view.h): the viewer reports what is missing.
#include "reference/core/io.h"
#include "view/view.h"

namespace dentsim::view {

namespace {
constexpr const char* kMissing =
    "this dentsim was built without GLFW/OpenGL (Debian: libglfw3-dev libgl-dev; "
    "scripts/setup.sh installs them, then rebuild)";
}

bool window_available(std::string* why) {
  if (why != nullptr) *why = kMissing;
  return false;
}

void run_viewer(SnapshotChannel&, const std::atomic<bool>&, const ViewerOptions&) {
  throw InputError(std::string("--view: ") + kMissing);
}

}  // namespace dentsim::view
