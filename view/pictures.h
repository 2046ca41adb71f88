// The tooth pictures of `dentsim run` (tooth_before.png, tooth_after.png; issue #19): the lit
// surface of view/surface_mesh.h drawn by the view's renderer, two panels side by side as the
// voxel pictures of tooth_io/render_png.h: left the whole tooth, right the cut-away (the
// +x +y quarter removed, so enamel, dentin and pulp show as layers). Throws InputError when this
// build or machine has no headless GL (view/view.h); the CLI then falls back to render_voxels.
#pragma once

#include "tooth_io/render_png.h"
#include "view/view.h"

namespace dentsim::view {

// `field`: the tooth's sampled field (contact model "field"), meshed instead of the voxels.
RgbImage render_tooth_panels(const VoxelGrid& tooth, int panel_size = 512,
                             float elevation_deg = 55.0f, const SampledField* field = nullptr);

}  // namespace dentsim::view
