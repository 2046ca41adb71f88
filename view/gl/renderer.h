// The drawing code of the 3-D view (issue #19; view/view.h), OpenGL 3.3 core profile. Needs a
// current context (a GLFW window or an EGL surfaceless context with a framebuffer object).
//
// Shading: Lambert + Blinn-Phong specular, a key light over the camera's shoulder plus ambient:
//   c = albedo (0.30 + 0.70 max(0, n.l)) + 0.15 max(0, n.h)^32
// albedo per material from reference/tooth/materials.cc (enamel ivory, dentin yellow, pulp red).
// The proxy is drawn last, translucent (alpha 0.35, no depth writes), and only when it is more than
// 0.02 mm from the device's tool. The tool's shank is drawn vertical at the home pose and turns
// with the device from there. The force arrow starts at the proxy's tip centre, points along the
// force on the proxy from the tooth, 10 mm per N, at most 8 mm, drawn over the scene (it runs
// along the shank, out of the cavity).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "tooth_io/render_png.h"
#include "view/camera.h"
#include "view/snapshot.h"
#include "view/surface_mesh.h"

namespace dentsim::view {

class GlRenderer {
 public:
  GlRenderer();  // compiles the shaders; throws std::runtime_error with the GL log on failure
  ~GlRenderer();
  GlRenderer(const GlRenderer&) = delete;
  GlRenderer& operator=(const GlRenderer&) = delete;

  // Uploads the blocks whose version changed since the last call.
  void sync(const SurfaceMesher& mesher);
  // Takes the meshes of a picture drawn once (SurfaceMesher::take_blocks; nothing to update
  // later): packs their triangles, in block order, into a few large buffers and frees each
  // block's arrays as soon as they are copied, so the mesh is held once, by the GL, and a
  // software GL keeps no objects per block (issue #30: the 512^3 tooth). They are drawn after
  // sync()'s blocks, in the same order as sync() would draw them, so the picture is the same.
  void upload_once(std::vector<BlockMesh> blocks);
  // Draws one frame into the bound framebuffer of width x height pixels. tick: null = tooth only;
  // overlay: lines of text (empty = no overlay).
  void draw(const OrbitCamera& camera, const TickSnapshot* tick,
            const std::vector<std::string>& overlay, int width, int height);
  // Reads the bound framebuffer back (rows top to bottom).
  static RgbImage read_pixels(int width, int height);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace dentsim::view
