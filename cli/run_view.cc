#include "cli/run_view.h"

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <thread>

#include "cli/png_writer.h"
#include "reference/core/io.h"
#include "reference/tooth/grid_pages.h"
#include "tooth_io/render_png.h"
#include "view/pictures.h"
#include "view/view.h"

namespace dentsim::cli {

RunResult run_scene_with_view(const Scene& scene, RunOptions options, const RunViewOptions& v) {
  if (!v.view) {
    RunResult r = run_scene(scene, options);
    if (v.on_done) v.on_done(r);
    return r;
  }
  std::string why;
  if (!view::window_available(&why)) throw InputError("--view: " + why);
  const char* display = std::getenv("DISPLAY");
  const char* wayland = std::getenv("WAYLAND_DISPLAY");
  if ((display == nullptr || *display == '\0') && (wayland == nullptr || *wayland == '\0')) {
    throw InputError(
        "--view: no display (DISPLAY is not set); `dentsim render` draws the same "
        "picture without one");
  }
  if (!v.shots_dir.empty() && !std::filesystem::is_directory(v.shots_dir)) {
    throw InputError("--view-shots '" + v.shots_dir + "': not a directory");
  }
  view::SnapshotChannel channel(scene.tooth.resolution);
  options.realtime = true;
  options.observer = &channel;
  std::atomic<bool> done{false};
  RunResult result;
  std::exception_ptr run_error;
  std::thread servo([&] {
    try {
      result = run_scene(scene, options);
      if (v.on_done) v.on_done(result);  // the outputs, written while the window is open
    } catch (...) {
      run_error = std::current_exception();
    }
    done.store(true, std::memory_order_release);
  });
  view::ViewerOptions vo;
  vo.view.method = method_name(scene.method.method);
  vo.screenshot_dir = v.shots_dir.empty() ? "." : v.shots_dir;
  vo.capture_first_last = !v.shots_dir.empty();
  vo.close_when_done = v.close || !v.shots_dir.empty();
  vo.stop = options.stop;
  vo.save_png = [](const std::string& path, const RgbImage& img) { write_png(path, img); };
  std::exception_ptr view_error;
  try {
    view::run_viewer(channel, done, vo);
  } catch (...) {
    view_error = std::current_exception();
  }
  if (!done.load() && !(options.stop != nullptr && options.stop->load()))
    std::fprintf(stderr, "dentsim run: window closed; finishing the run\n");
  servo.join();
  if (run_error) std::rethrow_exception(run_error);
  if (view_error) std::rethrow_exception(view_error);
  return result;
}

void write_tooth_pictures(const RunResult& r, const std::string& dir) {
  // The run's rig was freed into the malloc arenas: its pages back before the meshes (issue #30).
  release_free_heap();
  std::string why;
  if (view::headless_available(&why)) {
    try {
      // One grid unpacked at a time (RunResult keeps them as runs).
      write_png(dir + "/tooth_before.png", view::render_tooth_panels(r.tooth_before.unpack(), 512,
                                                                     55.0f, r.field_before.get()));
      write_png(dir + "/tooth_after.png", view::render_tooth_panels(r.tooth_after.unpack(), 512,
                                                                    55.0f, r.field_after.get()));
      return;
    } catch (const InputError& e) {
      why = e.what();
    }
  }
  std::fprintf(stderr, "dentsim run: tooth pictures drawn as voxel sprites (%s)\n", why.c_str());
  // Seen from above the occlusal surface, where the tool works.
  RenderOptions view;
  view.elevation_deg = 55.0;
  write_png(dir + "/tooth_before.png", render_voxels(r.tooth_before.unpack(), view));
  write_png(dir + "/tooth_after.png", render_voxels(r.tooth_after.unpack(), view));
}

}  // namespace dentsim::cli
