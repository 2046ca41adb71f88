#include "view/pictures.h"

#include <algorithm>

namespace dentsim::view {

RgbImage render_tooth_panels(const VoxelGrid& tooth, int panel_size, float elevation_deg,
                             const SampledField* field) {
  ViewOptions o;
  o.field = field;
  o.width = o.height = panel_size;
  o.overlay = false;
  o.tool = false;
  o.elevation_deg = elevation_deg;
  const RgbImage whole = render_offscreen(tooth, nullptr, o);
  o.cutaway = true;
  const RgbImage cut = render_offscreen(tooth, nullptr, o);
  RgbImage img;
  img.width = 2 * panel_size;
  img.height = panel_size;
  img.rgb.resize(static_cast<std::size_t>(img.width) * img.height * 3);
  const std::size_t row = static_cast<std::size_t>(panel_size) * 3;
  for (int y = 0; y < panel_size; ++y) {
    const std::size_t dst = static_cast<std::size_t>(y) * img.width * 3;
    std::copy_n(whole.rgb.begin() + y * row, row, img.rgb.begin() + dst);
    std::copy_n(cut.rgb.begin() + y * row, row, img.rgb.begin() + dst + row);
  }
  return img;
}

}  // namespace dentsim::view
