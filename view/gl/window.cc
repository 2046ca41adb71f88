// The live window (view/view.h run_viewer): GLFW 3, OpenGL 3.3 core, vsync (the display's rate,
// at most 60 frames per second where the swap does not wait).
// Each frame: take the newest tick snapshot and the tooth's changed blocks from the
// SnapshotChannel (lock-free, view/snapshot.h), re-mesh only the affected surface blocks
// (view/live_tooth.h: with the contact model "field" this thread's copy of the field is edited
// first, so the window shows the field's surface as the pictures do), upload them, draw
// (view/gl/renderer.h). The servo loop never waits for this thread.
#include <GLFW/glfw3.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <thread>

#include "reference/core/io.h"
#include "view/gl/gl.h"
#include "view/gl/renderer.h"
#include "view/live_tooth.h"
#include "view/view.h"

namespace dentsim::view {
namespace {

struct WindowState {
  OrbitCamera camera, home;
  bool have_camera = false;
  bool cut = false, cut_changed = false;
  bool frozen = false;
  bool follow = false;
  bool screenshot = false;
  bool dragging = false;
  double last_x = 0.0, last_y = 0.0;
};

void on_key(GLFWwindow* w, int key, int, int action, int) {
  if (action != GLFW_PRESS) return;
  auto* s = static_cast<WindowState*>(glfwGetWindowUserPointer(w));
  switch (key) {
    case GLFW_KEY_ESCAPE:
    case GLFW_KEY_Q:
      glfwSetWindowShouldClose(w, GLFW_TRUE);
      break;
    case GLFW_KEY_C:
      s->cut = !s->cut;
      s->cut_changed = true;
      break;
    case GLFW_KEY_P:
      s->frozen = !s->frozen;
      break;
    case GLFW_KEY_S:
      s->screenshot = true;
      break;
    case GLFW_KEY_R:
      s->camera = s->home;
      break;
    case GLFW_KEY_F:
      s->follow = !s->follow;
      break;
    default:
      break;
  }
}

void on_button(GLFWwindow* w, int button, int action, int) {
  auto* s = static_cast<WindowState*>(glfwGetWindowUserPointer(w));
  if (button != GLFW_MOUSE_BUTTON_LEFT) return;
  s->dragging = action == GLFW_PRESS;
  glfwGetCursorPos(w, &s->last_x, &s->last_y);
}

void on_cursor(GLFWwindow* w, double x, double y) {
  auto* s = static_cast<WindowState*>(glfwGetWindowUserPointer(w));
  if (!s->dragging) return;
  s->camera.azimuth_deg -= 0.4f * static_cast<float>(x - s->last_x);
  s->camera.elevation_deg =
      std::clamp(s->camera.elevation_deg + 0.4f * static_cast<float>(y - s->last_y), -89.0f, 89.0f);
  s->last_x = x;
  s->last_y = y;
}

void on_scroll(GLFWwindow* w, double, double dy) {
  auto* s = static_cast<WindowState*>(glfwGetWindowUserPointer(w));
  s->camera.distance *= dy > 0 ? 0.9f : 1.0f / 0.9f;
}

struct Glfw {
  Glfw() {
    if (!glfwInit()) {
      throw InputError(
          "--view: cannot open a window: no display (set DISPLAY, or use "
          "`dentsim render` for a picture without one)");
    }
  }
  ~Glfw() { glfwTerminate(); }
};

// What the field surface's updates cost this thread (stderr; docs/view.md "On the smooth
// tooth"). Nothing without the field model.
void report_updates(const LiveTooth& tooth) {
  const LiveToothStats& s = tooth.stats();
  if (tooth.field() == nullptr || s.frames_with_removal == 0) return;
  const double per_frame_ms =
      1e3 * (s.edit_s + s.mesh_s) / static_cast<double>(s.frames_with_removal);
  std::fprintf(stderr,
               "view: field surface: set up in %.0f ms of CPU; %ld voxels removed over %ld of "
               "%ld frames, %ld blocks re-meshed: %.2f ms of CPU per frame on the mean (field "
               "edit %.2f, re-mesh %.2f), %.2f ms at most\n",
               1e3 * s.setup_s, s.voxels, s.frames_with_removal, s.frames, s.blocks, per_frame_ms,
               1e3 * s.edit_s / static_cast<double>(s.frames_with_removal),
               1e3 * s.mesh_s / static_cast<double>(s.frames_with_removal), 1e3 * s.frame_max_s);
}

}  // namespace

bool window_available(std::string* why) {
  if (why != nullptr) why->clear();
  return true;
}

void run_viewer(SnapshotChannel& channel, const std::atomic<bool>& run_done,
                const ViewerOptions& options) {
  const Glfw glfw;
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  glfwWindowHint(GLFW_DEPTH_BITS, 24);
  glfwWindowHint(GLFW_RESIZABLE, GLFW_TRUE);
  GLFWwindow* window =
      glfwCreateWindow(options.view.width, options.view.height, "dentsim", nullptr, nullptr);
  if (window == nullptr) {
    throw InputError("--view: cannot create an OpenGL 3.3 core window on this display");
  }
  glfwMakeContextCurrent(window);
  glfwSwapInterval(1);
  WindowState state;
  state.cut = options.view.cutaway;
  state.follow = options.view.focus_tool;
  glfwSetWindowUserPointer(window, &state);
  glfwSetKeyCallback(window, on_key);
  glfwSetMouseButtonCallback(window, on_button);
  glfwSetCursorPosCallback(window, on_cursor);
  glfwSetScrollCallback(window, on_scroll);

  {
    GlRenderer renderer;
    LiveTooth tooth;
    TickSnapshot tick;
    int shot = 0;
    bool wrote_first = false, wrote_last = false;
    auto next_frame = std::chrono::steady_clock::now();
    auto save = [&](const std::string& name, int w, int h) {
      if (!options.save_png) return;
      const std::string path = options.screenshot_dir + "/" + name;
      options.save_png(path, GlRenderer::read_pixels(w, h));
      std::fprintf(stderr, "view: wrote %s\n", path.c_str());
    };
    while (!glfwWindowShouldClose(window)) {
      glfwPollEvents();
      const bool done = run_done.load(std::memory_order_acquire);
      if (!state.frozen) {
        channel.latest(&tick);
        const bool first = !tooth.ready();
        tooth.sync(channel, state.cut);
        if (first && tooth.ready()) {
          state.camera = state.home = camera_for(tooth.grid(), options.view);
          state.have_camera = true;
        }
      }
      SurfaceMesher* mesher = tooth.ready() ? &tooth.mesher() : nullptr;
      if (mesher && state.cut_changed) {
        mesher->set_cut(state.cut ? centre_cut(mesher->grid()) : CutAway{});
        state.cut_changed = false;
      }
      if (mesher) {
        state.camera.target =
            state.follow && tick.tick >= 0 ? tick.proxy.x.cast<float>() : state.home.target;
      }
      int w = 0, h = 0;
      glfwGetFramebufferSize(window, &w, &h);
      if (mesher) renderer.sync(*mesher);
      double median = 0.0, p99 = 0.0;
      channel.tick_time_stats(&median, &p99);
      const std::vector<std::string> lines =
          options.view.overlay && tick.tick >= 0
              ? overlay_lines(options.view.method, tick, median, p99)
              : std::vector<std::string>{};
      renderer.draw(state.camera, options.view.tool ? &tick : nullptr, lines, w, h);
      if (state.screenshot) {
        char name[64];
        std::snprintf(name, sizeof name, "screenshot_%03d.png", shot++);
        save(name, w, h);
        state.screenshot = false;
      }
      if (options.capture_first_last && mesher && !wrote_first) {
        save("first.png", w, h);
        wrote_first = true;
      }
      if (options.capture_first_last && mesher && done && !wrote_last && !state.frozen) {
        save("last.png", w, h);
        wrote_last = true;
      }
      glfwSwapBuffers(window);
      // At most 60 frames per second where the swap does not wait for a vertical blank (Xvfb,
      // drivers that ignore the swap interval): the renderer must not take the cores the servo
      // loop runs on.
      next_frame += std::chrono::microseconds(16667);
      const auto now = std::chrono::steady_clock::now();
      if (next_frame > now) {
        std::this_thread::sleep_until(next_frame);
      } else {
        next_frame = now;
      }
      if (done && options.close_when_done && (wrote_last || !options.capture_first_last)) break;
      if (options.stop != nullptr && options.stop->load(std::memory_order_relaxed)) break;
    }
    report_updates(tooth);
  }
  glfwDestroyWindow(window);
}

}  // namespace dentsim::view
