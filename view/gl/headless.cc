// Headless rendering (view/view.h render_offscreen): an EGL context on Mesa's surfaceless platform
// (EGL_MESA_platform_surfaceless: no display, no window system), OpenGL 3.3 core, drawing into a
// framebuffer object (RGBA8 colour + 24-bit depth renderbuffers) that is read back.
#define EGL_EGLEXT_PROTOTYPES 1
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <stdlib.h>

#include "reference/core/io.h"
#include "reference/tooth/grid_pages.h"
#include "view/gl/gl.h"
#include "view/gl/renderer.h"
#include "view/view.h"

namespace dentsim::view {
namespace {

// One EGL display + context for the process, made current on the calling thread.
class EglContext {
 public:
  EglContext() {
    // Mesa's llvmpipe rasterises on worker threads by default, keeping a second scene's bins
    // alive while the first is drawn: at 512^3 the drill scene's pictures (the mesher's ~2 MiB
    // buffers, flushed one at a time) peaked 40-80 MB higher that way (dentsim run's max RSS
    // 382-420 MB against 337-345 MB with LP_NUM_THREADS=0, the same wall time and the same PNGs
    // byte for byte; docs/benchmarks.md, stop 44). Drawn on this thread unless the user set it.
    setenv("LP_NUM_THREADS", "0", /*overwrite=*/0);
    display_ = eglGetPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (display_ == EGL_NO_DISPLAY || !eglInitialize(display_, nullptr, nullptr)) {
      throw InputError(
          "render: cannot open an EGL surfaceless display (Mesa's libegl-mesa0 and "
          "libgl1-mesa-dri are needed; scripts/setup.sh installs them)");
    }
    if (!eglBindAPI(EGL_OPENGL_API)) throw InputError("render: EGL has no desktop OpenGL API");
    const EGLint ctx_attr[] = {EGL_CONTEXT_MAJOR_VERSION,
                               3,
                               EGL_CONTEXT_MINOR_VERSION,
                               3,
                               EGL_CONTEXT_OPENGL_PROFILE_MASK,
                               EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                               EGL_NONE};
    context_ = eglCreateContext(display_, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, ctx_attr);
    if (context_ == EGL_NO_CONTEXT) {
      throw InputError("render: EGL cannot create an OpenGL 3.3 core context (error 0x" +
                       std::to_string(eglGetError()) + ")");
    }
  }
  ~EglContext() {
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(display_, context_);
    eglTerminate(display_);
  }
  void make_current() const {
    if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_)) {
      throw InputError("render: eglMakeCurrent failed");
    }
  }

 private:
  EGLDisplay display_ = EGL_NO_DISPLAY;
  EGLContext context_ = EGL_NO_CONTEXT;
};

class Framebuffer {
 public:
  Framebuffer(int w, int h) {
    glGenFramebuffers(1, &fbo_);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glGenRenderbuffers(2, rb_);
    glBindRenderbuffer(GL_RENDERBUFFER, rb_[0]);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, w, h);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb_[0]);
    glBindRenderbuffer(GL_RENDERBUFFER, rb_[1]);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, w, h);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb_[1]);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
      throw InputError("render: the offscreen framebuffer is incomplete");
    }
  }
  ~Framebuffer() {
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDeleteRenderbuffers(2, rb_);
    glDeleteFramebuffers(1, &fbo_);
  }

 private:
  GLuint fbo_ = 0, rb_[2] = {0, 0};
};

}  // namespace

bool headless_available(std::string* why) {
  if (why != nullptr) why->clear();
  return true;
}

RgbImage render_offscreen(const VoxelGrid& tooth, const TickSnapshot* tick,
                          const ViewOptions& options, double median_us, double p99_us) {
  if (options.width < 16 || options.height < 16 || options.width > 8192 || options.height > 8192) {
    throw InputError("render: picture size must be 16..8192 pixels per side");
  }
  // One context per process, never destroyed (tearing EGL down in exit handlers races Mesa's own);
  // the renderer's GL objects are per call.
  static EglContext* context = new EglContext();
  context->make_current();
  RgbImage img;
  {
    const Framebuffer fb(options.width, options.height);
    GlRenderer renderer;
    {
      // Reads the caller's grid (no copy), and each block's mesh goes once the GL holds it:
      // issue #30's 512^3 tooth (128 MiB of grid, ~100 MiB of meshes).
      SurfaceMesher mesher =
          SurfaceMesher::borrowing(tooth, options.field, SurfaceMesher::kDefaultBlockSize,
                                   options.cutaway ? centre_cut(tooth) : CutAway{});
      // Meshing read every voxel, which on a system without a shared zero page (this project's
      // VMs) takes the grid's released empty pages back (VoxelRuns::unpack): they go again.
      release_empty_pages(tooth);
      renderer.upload_once(mesher.take_blocks());
    }
    // The mesher's scratch, freed in the setup's threads' arenas, back before the draw (the
    // blocks' arrays went back during the upload, GlRenderer::upload_once).
    release_free_heap();
    OrbitCamera cam = camera_for(tooth, options);
    if (options.focus_tool && tick != nullptr && tick->tick >= 0) {
      cam.target = tick->proxy.x.cast<float>();
    }
    std::vector<std::string> lines;
    if (options.overlay && tick != nullptr) {
      lines = overlay_lines(options.method, *tick, median_us, p99_us);
    }
    renderer.draw(cam, options.tool ? tick : nullptr, lines, options.width, options.height);
    glFinish();
    img = GlRenderer::read_pixels(options.width, options.height);
  }
  // The GL's buffers and the draw's memory, freed with the renderer: their pages back before the
  // next picture meshes (issue #30: the next cut-away picture's meshes came on top of ~100 MB).
  release_free_heap();
  return img;
}

}  // namespace dentsim::view
