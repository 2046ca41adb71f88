// Built when CMake found no OpenGL/EGL (view/view.h): the headless renderer reports what is
// missing.
#include "reference/core/io.h"
#include "view/view.h"

namespace dentsim::view {

namespace {
constexpr const char* kMissing =
    "this dentsim was built without OpenGL/EGL (Debian: libgl-dev libegl-dev libegl-mesa0 "
    "libgl1-mesa-dri; scripts/setup.sh installs them, then rebuild)";
}

bool headless_available(std::string* why) {
  if (why != nullptr) *why = kMissing;
  return false;
}

RgbImage render_offscreen(const VoxelGrid&, const TickSnapshot*, const ViewOptions&, double,
                          double) {
  throw InputError(std::string("render: ") + kMissing);
}

}  // namespace dentsim::view
