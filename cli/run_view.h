// The parts of `dentsim run` that use the 3-D view (issue #19; docs/view.md): running a scene with
// the live window (--view) and drawing the before/after tooth pictures with the view's renderer.
#pragma once

#include <functional>
#include <string>

#include "sim/scene.h"
#include "sim/simulator.h"

namespace dentsim::cli {

struct RunViewOptions {
  bool view = false;      // --view: open the window, pace the device at real time
  bool close = false;     // --view-close: close the window when the run ends
  std::string shots_dir;  // --view-shots DIR: write DIR/first.png and DIR/last.png (implies close)
  // Called with the result as soon as the run ends (on the servo thread with --view, so the
  // outputs are written while the window is still open); null: none.
  std::function<void(const RunResult&)> on_done;
};

// Runs the scene; with v.view the simulation runs on its own thread at real time (the servo loop)
// while this (main) thread draws the window from the lock-free SnapshotChannel. Throws InputError
// before running if the window cannot work here (no GLFW in this build, no DISPLAY). When
// options.stop is set (Ctrl-C, SIGTERM) the run stops at a tick boundary and the window closes.
// v.on_done runs once with the result before this returns (not when the run threw).
RunResult run_scene_with_view(const Scene& scene, RunOptions options, const RunViewOptions& v);

// Writes dir/tooth_before.png and dir/tooth_after.png: the lit surface from the view's renderer,
// or, when this build or machine has no headless GL, the voxel pictures of render_voxels (and says
// so on stderr).
void write_tooth_pictures(const RunResult& r, const std::string& dir);

}  // namespace dentsim::cli
