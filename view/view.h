// The 3-D view of the simulation (issue #19; docs/view.md): the voxel tooth's smooth surface in
// its materials' colours (view/surface_mesh.h), the device's tool (solid) and the proxy (a ghost
// where the two differ), the contact force as an arrow, and a text overlay (method, tick time
// median/p99, force, removed volume per material, faults). One drawing code (view/gl/renderer.h,
// OpenGL 3.3 core) serves three front ends:
//  - run_viewer: a GLFW window, live, fed by a SnapshotChannel (view/snapshot.h);
//  - render_offscreen: headless, EGL on Mesa's surfaceless platform (no display needed);
//  - the before/after tooth pictures of `dentsim run` (render_offscreen without a tool).
// The library builds without GL (CMake finds no GLFW/EGL): then gl_available() is false and the
// functions below throw InputError naming the missing packages (the CLI exits with status 2).
#pragma once

#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include "tooth_io/render_png.h"
#include "reference/tooth/voxel_grid.h"
#include "view/camera.h"
#include "view/snapshot.h"
#include "view/surface_mesh.h"

namespace dentsim::view {

struct ViewOptions {
  int width = 960, height = 720;  // pixels
  bool cutaway = false;           // remove the +x +y quarter (surface_mesh.h CutAway)
  bool overlay = true;            // draw the text overlay
  bool tool = true;               // draw the tool, proxy and force arrow (needs a snapshot)
  float azimuth_deg = 45.0f, elevation_deg = 55.0f;  // camera (camera.h)
  float zoom = 1.0f;                                 // > 1: closer
  bool focus_tool = false;  // aim the camera at the proxy's tip instead of the tooth's centre
  std::string method;       // shown in the overlay
  // The tooth's sampled field (contact model "field"): mesh its zero level, the surface the tool
  // touches, instead of the voxels (surface_mesh.h). Not owned; null: the voxels.
  const SampledField* field = nullptr;
};

// The overlay's text lines for one tick (GL-free, so it is tested on its own).
std::vector<std::string> overlay_lines(const std::string& method, const TickSnapshot& s,
                                       double median_us, double p99_us);
// The overlay occupies this rectangle at the top-left corner of the picture [pixels].
inline constexpr int kOverlayWidth = 460, kOverlayHeight = 140;

// Whether this build has the headless renderer (EGL) / the window (GLFW); if not, *why says what
// is missing.
bool headless_available(std::string* why);
bool window_available(std::string* why);

// Renders one picture offscreen. `tick` may be null (tooth only). The camera is camera_for(tooth)
// turned and zoomed by the options. Throws InputError if GL is unavailable or cannot start.
RgbImage render_offscreen(const VoxelGrid& tooth, const TickSnapshot* tick,
                          const ViewOptions& options, double median_us = 0.0, double p99_us = 0.0);

struct ViewerOptions {
  ViewOptions view;
  std::string screenshot_dir = ".";  // key S writes screenshot_NNN.png here
  // Test/automation: write first.png (first frame showing the tooth) and last.png (first frame
  // after the run finished) into screenshot_dir, then close the window when the run is done.
  bool capture_first_last = false;
  bool close_when_done = false;
  // Set (Ctrl-C, SIGTERM; cli/interrupt.h): close the window at the next frame. Null: none.
  const std::atomic<bool>* stop = nullptr;
  // Writes a PNG (the CLI passes cli/png_writer.h's write_png; the library does not link libpng).
  std::function<void(const std::string&, const RgbImage&)> save_png;
};

// Opens the window and draws at the display's rate (vsync) until the user closes it (Esc, Q or
// the window's close button) or, with close_when_done, until `run_done` is set. Must be called on
// the main thread. Keys: C cut-away, P freeze the picture (the simulation goes on), S screenshot,
// F aim at the tool (toggle), R reset the camera; left drag orbits, wheel zooms. Throws InputError
// if there is no display or no GLFW in this build.
void run_viewer(SnapshotChannel& channel, const std::atomic<bool>& run_done,
                const ViewerOptions& options);

}  // namespace dentsim::view
