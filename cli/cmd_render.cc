// `dentsim render SCENE --at S --png FILE` (issue #19; docs/view.md): runs the scene to simulated
// time S (as `dentsim run` does, through the same TickObserver hook the live view uses) and draws
// the view's picture headless (EGL surfaceless, view/view.h): the tooth as drilled so far, the
// tool, the proxy, the force arrow and the overlay.
#include <cstdio>
#include <filesystem>
#include <memory>

#include "cli/png_writer.h"
#include "cli/progress.h"
#include "cli/registry.h"
#include "sim/scene.h"
#include "sim/simulator.h"
#include "reference/core/io.h"
#include "view/view.h"

namespace dentsim::cli {
namespace {

struct RenderCliOptions {
  std::string scene;
  double at = 0.0;
  std::string png;
  int width = 960, height = 720;
  bool cutaway = false;
  bool no_overlay = false;
  float azimuth = 45.0f, elevation = 55.0f, zoom = 1.0f;
  bool focus_tool = false;
};

void render(const RenderCliOptions& o) {
  if (!(o.at > 0.0)) throw InputError("render: --at must be a positive time [s]");
  if (o.png.empty()) throw InputError("render: --png FILE is required");
  const std::filesystem::path dir = std::filesystem::path(o.png).parent_path();
  if (!dir.empty() && !std::filesystem::is_directory(dir)) {
    throw InputError("render: --png '" + o.png + "': the directory '" + dir.string() +
                     "' does not exist");
  }
  if (!(o.zoom > 0.0f)) throw InputError("render: --zoom must be positive");
  std::string why;
  if (!view::headless_available(&why)) throw InputError("render: " + why);
  const Scene scene = load_scene(o.scene);

  view::SnapshotChannel channel(scene.tooth.resolution);
  ProgressBar bar("simulating");
  RunOptions ro;
  ro.duration_override = o.at;
  ro.observer = &channel;
  ro.progress = [&bar](double f) { bar.update(f); };
  const RunResult r = run_scene(scene, ro);
  bar.finish();

  view::TickSnapshot tick;
  channel.latest(&tick);
  VoxelGrid tooth;
  std::vector<std::size_t> changed;
  if (!channel.sync_tooth(&tooth, &changed)) throw std::runtime_error("render: no tick was run");
  double median = 0.0, p99 = 0.0;
  channel.tick_time_stats(&median, &p99);
  view::ViewOptions vo;
  vo.width = o.width;
  vo.height = o.height;
  vo.cutaway = o.cutaway;
  vo.overlay = !o.no_overlay;
  vo.azimuth_deg = o.azimuth;
  vo.elevation_deg = o.elevation;
  vo.zoom = o.zoom;
  vo.focus_tool = o.focus_tool;
  vo.method = method_name(scene.method.method);
  write_png(o.png, view::render_offscreen(tooth, &tick, vo, median, p99));
  std::printf("render: scene %s at t = %.3f s (%ld ticks, removed %.4f mm^3): wrote %s\n",
              scene.name.c_str(), tick.t, r.ticks, r.removed_volume_total_mm3, o.png.c_str());
  if (!r.faults.empty())
    throw std::runtime_error("the device faulted (safe stop): " + r.faults.front());
}

void setup_render(CLI::App& app) {
  auto o = std::make_shared<RenderCliOptions>();
  CLI::App* sub = app.add_subcommand(
      "render", "Run a scene to time S and draw the 3-D view headless into a PNG (docs/view.md)");
  sub->add_option("scene", o->scene, "Built-in scene name or scene file")->required();
  sub->add_option("--at", o->at, "Simulated time to render at [s]")->required();
  sub->add_option("--png", o->png, "Output PNG file")->required();
  sub->add_option("--width", o->width, "Picture width [pixels]")->capture_default_str();
  sub->add_option("--height", o->height, "Picture height [pixels]")->capture_default_str();
  sub->add_flag("--cutaway", o->cutaway, "Remove the +x +y quarter of the tooth (show the layers)");
  sub->add_flag("--no-overlay", o->no_overlay, "Leave out the text overlay");
  sub->add_option("--azimuth", o->azimuth, "Camera azimuth [deg]")->capture_default_str();
  sub->add_option("--elevation", o->elevation, "Camera elevation [deg]")->capture_default_str();
  sub->add_option("--zoom", o->zoom, "Zoom factor (> 1: closer)")->capture_default_str();
  sub->add_flag("--focus-tool", o->focus_tool, "Aim the camera at the tool instead of the tooth");
  sub->callback([o] { render(*o); });
}
DENTSIM_REGISTER_COMMAND(setup_render);

}  // namespace
}  // namespace dentsim::cli
