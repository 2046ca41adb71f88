// `dentsim render SCENE --at S --png FILE` (issue #19; docs/view.md): runs the scene to simulated
// time S (as `dentsim run` does, through the same TickObserver hook the live view uses) and draws
// the view's picture headless (EGL surfaceless, view/view.h): the tooth as drilled so far, the
// tool, the proxy, the force arrow and the overlay.
#include <cstdio>
#include <filesystem>
#include <memory>

#include "cli/outputs.h"
#include "cli/png_writer.h"
#include "cli/progress.h"
#include "cli/registry.h"
#include "fast/registry.h"
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
  std::string pipeline = "fast";  // as `dentsim run`: the tick's implementation
};

void render(const RenderCliOptions& o) {
  if (!(o.at >= 0.0)) throw InputError("render: --at must be a time >= 0 [s]");
  if (find_stage_table(o.pipeline) == nullptr) {
    throw InputError("--pipeline '" + o.pipeline + "': expected one of " + stage_table_names());
  }
  if (o.png.empty()) throw InputError("render: --png FILE is required");
  check_outputs({{"--png", o.png}}, {}, {{"scene", o.scene}});
  if (!(o.zoom > 0.0f)) throw InputError("render: --zoom must be positive");
  std::string why;
  if (!view::headless_available(&why)) throw InputError("render: " + why);
  const Scene scene = load_scene(o.scene);

  view::ViewOptions vo;
  if (o.at == 0.0) {
    // The tooth before drilling, as the scene places it: no tick runs, no tool is drawn.
    SceneRigOptions rig_options;
    rig_options.pipeline = o.pipeline;
    const std::unique_ptr<SceneRig> rig = build_scene_rig(scene, rig_options);
    vo.width = o.width;
    vo.height = o.height;
    vo.cutaway = o.cutaway;
    vo.overlay = false;
    vo.tool = false;
    vo.azimuth_deg = o.azimuth;
    vo.elevation_deg = o.elevation;
    vo.zoom = o.zoom;
    vo.method = method_name(scene.method.method);
    vo.field = rig->field.get();
    write_png(o.png, view::render_offscreen(rig->tooth_before.unpack(), nullptr, vo));
    std::printf("render: scene %s at t = 0 s (before the first tick, %s pipeline): wrote %s\n",
                scene.name.c_str(), o.pipeline.c_str(), o.png.c_str());
    return;
  }

  view::SnapshotChannel channel(scene.tooth.resolution);
  ProgressBar bar("simulating");
  RunOptions ro;
  ro.pipeline = o.pipeline;
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
  vo.width = o.width;
  vo.height = o.height;
  vo.cutaway = o.cutaway;
  vo.overlay = !o.no_overlay;
  vo.azimuth_deg = o.azimuth;
  vo.elevation_deg = o.elevation;
  vo.zoom = o.zoom;
  vo.focus_tool = o.focus_tool;
  vo.method = method_name(scene.method.method);
  vo.field = r.field_after.get();
  write_png(o.png, view::render_offscreen(tooth, &tick, vo, median, p99));
  std::printf(
      "render: scene %s at t = %.3f s (%ld ticks, %s pipeline, removed %.4f mm^3): wrote %s\n",
      scene.name.c_str(), tick.t, r.ticks, r.pipeline.c_str(), r.removed_volume_total_mm3,
      o.png.c_str());
  if (!r.faults.empty())
    throw std::runtime_error("the device faulted (safe stop): " + r.faults.front());
}

void setup_render(CLI::App& app) {
  auto o = std::make_shared<RenderCliOptions>();
  CLI::App* sub = app.add_subcommand(
      "render", "Run a scene to time S and draw the 3-D view headless into a PNG (docs/view.md)");
  sub->add_option("scene", o->scene, "Built-in scene name or scene file")->required();
  sub->add_option("--at", o->at,
                  "Simulated time to render at [s] (0: the tooth before the first tick)")
      ->required();
  sub->add_option("--pipeline", o->pipeline,
                  "The tick's implementation (as `dentsim run`): " + stage_table_names())
      ->capture_default_str();
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
