#include "view/gl/renderer.h"

#include <cairo.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "reference/tooth/grid_pages.h"
#include "reference/tooth/materials.h"
#include "view/gl/gl.h"
#include "view/view.h"

namespace dentsim::view {
namespace {

const char* kMeshVs = R"(#version 330 core
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in float a_material;
uniform mat4 u_model;
uniform mat4 u_view_proj;
out vec3 v_normal;
out vec3 v_world;
flat out int v_material;
void main() {
  vec4 w = u_model * vec4(a_pos, 1.0);
  v_world = w.xyz;
  v_normal = mat3(u_model) * a_normal;
  v_material = int(a_material + 0.5);
  gl_Position = u_view_proj * w;
}
)";

const char* kMeshFs = R"(#version 330 core
in vec3 v_normal;
in vec3 v_world;
flat in int v_material;
uniform vec3 u_palette[8];
uniform int u_use_color;
uniform vec4 u_color;
uniform vec3 u_eye;
uniform vec3 u_light;
out vec4 frag;
void main() {
  vec3 n = normalize(v_normal);
  if (!gl_FrontFacing) n = -n;
  vec3 albedo = u_use_color != 0 ? u_color.rgb : u_palette[clamp(v_material, 0, 7)];
  vec3 v = normalize(u_eye - v_world);
  vec3 h = normalize(u_light + v);
  float d = max(dot(n, u_light), 0.0);
  float s = pow(max(dot(n, h), 0.0), 32.0);
  frag = vec4(albedo * (0.30 + 0.70 * d) + vec3(0.15 * s), u_use_color != 0 ? u_color.a : 1.0);
}
)";

const char* kOverlayVs = R"(#version 330 core
layout(location = 0) in vec2 a_xy;
uniform vec4 u_rect;
out vec2 v_uv;
void main() {
  v_uv = vec2(a_xy.x, 1.0 - a_xy.y);
  gl_Position = vec4(mix(u_rect.xy, u_rect.zw, a_xy), 0.0, 1.0);
}
)";

const char* kOverlayFs = R"(#version 330 core
in vec2 v_uv;
uniform sampler2D u_tex;
out vec4 frag;
void main() { frag = texture(u_tex, v_uv).bgra; }
)";

GLuint compile(GLenum type, const char* src) {
  const GLuint s = glCreateShader(type);
  glShaderSource(s, 1, &src, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[2048];
    glGetShaderInfoLog(s, sizeof log, nullptr, log);
    throw std::runtime_error(std::string("view: shader compilation failed: ") + log);
  }
  return s;
}

GLuint link(const char* vs, const char* fs) {
  const GLuint p = glCreateProgram();
  const GLuint v = compile(GL_VERTEX_SHADER, vs), f = compile(GL_FRAGMENT_SHADER, fs);
  glAttachShader(p, v);
  glAttachShader(p, f);
  glLinkProgram(p);
  glDeleteShader(v);
  glDeleteShader(f);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[2048];
    glGetProgramInfoLog(p, sizeof log, nullptr, log);
    throw std::runtime_error(std::string("view: shader link failed: ") + log);
  }
  return p;
}

struct GlMesh {
  GLuint vao = 0, vbo = 0, ibo = 0;
  GLsizei count = 0;
  std::uint64_t version = 0;

  void upload(const std::vector<MeshVertex>& v, const std::vector<std::uint32_t>& idx) {
    // An empty block that never held triangles gets no GL objects: most blocks of a tooth's grid
    // are empty, and a software GL (llvmpipe) spends kilobytes on each vertex array and buffer
    // (issue #30: 262144 blocks at 512^3). It draws nothing either way.
    if (vao == 0 && idx.empty()) {
      count = 0;
      return;
    }
    if (vao == 0) {
      glGenVertexArrays(1, &vao);
      glGenBuffers(1, &vbo);
      glGenBuffers(1, &ibo);
      glBindVertexArray(vao);
      glBindBuffer(GL_ARRAY_BUFFER, vbo);
      glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo);
      const GLsizei stride = sizeof(MeshVertex);
      glEnableVertexAttribArray(0);
      glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, stride,
                            reinterpret_cast<void*>(offsetof(MeshVertex, p)));
      glEnableVertexAttribArray(1);
      glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, stride,
                            reinterpret_cast<void*>(offsetof(MeshVertex, n)));
      glEnableVertexAttribArray(2);
      glVertexAttribPointer(2, 1, GL_FLOAT, GL_FALSE, stride,
                            reinterpret_cast<void*>(offsetof(MeshVertex, material)));
    }
    glBindVertexArray(vao);
    glBindBuffer(GL_ARRAY_BUFFER, vbo);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(v.size() * sizeof(MeshVertex)), v.data(),
                 GL_STATIC_DRAW);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER,
                 static_cast<GLsizeiptr>(idx.size() * sizeof(std::uint32_t)), idx.data(),
                 GL_STATIC_DRAW);
    count = static_cast<GLsizei>(idx.size());
  }
  void draw() const {
    if (count == 0) return;
    glBindVertexArray(vao);
    glDrawElements(GL_TRIANGLES, count, GL_UNSIGNED_INT, nullptr);
  }
  void release() {
    if (vao == 0) return;
    glDeleteBuffers(1, &vbo);
    glDeleteBuffers(1, &ibo);
    glDeleteVertexArrays(1, &vao);
    vao = vbo = ibo = 0;
  }
};

MeshVertex vertex(const Eigen::Vector3f& p, const Eigen::Vector3f& n) {
  return MeshVertex{{p.x(), p.y(), p.z()}, {n.x(), n.y(), n.z()}, 0.0f};
}

// Unit sphere, centred at the origin.
void make_sphere(std::vector<MeshVertex>* v, std::vector<std::uint32_t>* idx) {
  constexpr int kLon = 32, kLat = 16;
  const float pi = std::numbers::pi_v<float>;
  for (int a = 0; a <= kLat; ++a) {
    const float th = pi * a / kLat;
    for (int b = 0; b <= kLon; ++b) {
      const float ph = 2 * pi * b / kLon;
      const Eigen::Vector3f p(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph),
                              std::cos(th));
      v->push_back(vertex(p, p));
    }
  }
  for (int a = 0; a < kLat; ++a) {
    for (int b = 0; b < kLon; ++b) {
      const std::uint32_t i0 = a * (kLon + 1) + b, i1 = i0 + kLon + 1;
      idx->insert(idx->end(), {i0, i1, i0 + 1, i0 + 1, i1, i1 + 1});
    }
  }
}

// Radius 1 around +z from z = 0 to 1; cone = true tapers to a point at z = 1.
void make_cylinder(bool cone, std::vector<MeshVertex>* v, std::vector<std::uint32_t>* idx) {
  constexpr int kSeg = 24;
  const float pi = std::numbers::pi_v<float>;
  for (int b = 0; b <= kSeg; ++b) {
    const float ph = 2 * pi * b / kSeg;
    const Eigen::Vector3f r(std::cos(ph), std::sin(ph), 0.0f);
    const Eigen::Vector3f n = cone ? Eigen::Vector3f(r + Eigen::Vector3f::UnitZ()).normalized() : r;
    v->push_back(vertex(r, n));
    v->push_back(
        vertex(cone ? Eigen::Vector3f::UnitZ() : Eigen::Vector3f(r + Eigen::Vector3f::UnitZ()), n));
  }
  for (int b = 0; b < kSeg; ++b) {
    const std::uint32_t i = 2 * b;
    idx->insert(idx->end(), {i, i + 2, i + 1, i + 1, i + 2, i + 3});
  }
  // Bottom cap.
  const std::uint32_t c = static_cast<std::uint32_t>(v->size());
  v->push_back(vertex(Eigen::Vector3f::Zero(), -Eigen::Vector3f::UnitZ()));
  for (int b = 0; b <= kSeg; ++b) {
    const float ph = 2 * pi * b / kSeg;
    v->push_back(
        vertex(Eigen::Vector3f(std::cos(ph), std::sin(ph), 0.0f), -Eigen::Vector3f::UnitZ()));
  }
  for (int b = 0; b < kSeg; ++b) {
    idx->insert(idx->end(),
                {c, c + 2 + static_cast<std::uint32_t>(b), c + 1 + static_cast<std::uint32_t>(b)});
  }
}

// Model matrix: translate to `at`, rotate +z onto `dir` (unit), scale (sx, sx, sz).
Eigen::Matrix4f along(const Eigen::Vector3f& at, const Eigen::Vector3f& dir, float sx, float sz) {
  const Eigen::Matrix3f R =
      Eigen::Quaternionf::FromTwoVectors(Eigen::Vector3f::UnitZ(), dir).toRotationMatrix();
  Eigen::Matrix4f m = Eigen::Matrix4f::Identity();
  m.block<3, 3>(0, 0) = R * Eigen::Vector3f(sx, sx, sz).asDiagonal();
  m.block<3, 1>(0, 3) = at;
  return m;
}

Eigen::Matrix4f sphere_at(const Eigen::Vector3f& at, float r) {
  Eigen::Matrix4f m = Eigen::Matrix4f::Identity();
  m.block<3, 3>(0, 0) *= r;
  m.block<3, 1>(0, 3) = at;
  return m;
}

constexpr float kToolRgb[3] = {0.55f, 0.58f, 0.63f};
constexpr float kProxyRgba[4] = {0.25f, 0.55f, 0.95f, 0.35f};
constexpr float kArrowRgb[3] = {0.85f, 0.15f, 0.75f};
constexpr float kShaftLength = 0.008f;    // drawn length of the tool's shaft [m]
constexpr float kArrowMPerN = 0.010f;     // arrow length per newton [m/N]
constexpr float kArrowMaxM = 0.008f;      // longest arrow [m]
constexpr float kProxyGhostMinM = 2e-5f;  // draw the proxy when it is farther than this [m]

}  // namespace

struct GlRenderer::Impl {
  GLuint mesh_prog = 0, overlay_prog = 0;
  std::vector<GlMesh> blocks;
  std::vector<GlMesh> packed;  // upload_once's buffers, in block order
  GlMesh sphere, cylinder, cone;
  GLuint quad_vao = 0, quad_vbo = 0, overlay_tex = 0;
  std::vector<std::uint8_t> text_pixels;
};

GlRenderer::GlRenderer() : impl_(std::make_unique<Impl>()) {
  impl_->mesh_prog = link(kMeshVs, kMeshFs);
  impl_->overlay_prog = link(kOverlayVs, kOverlayFs);
  std::vector<MeshVertex> v;
  std::vector<std::uint32_t> idx;
  make_sphere(&v, &idx);
  impl_->sphere.upload(v, idx);
  v.clear();
  idx.clear();
  make_cylinder(false, &v, &idx);
  impl_->cylinder.upload(v, idx);
  v.clear();
  idx.clear();
  make_cylinder(true, &v, &idx);
  impl_->cone.upload(v, idx);
  const float quad[8] = {0, 0, 1, 0, 0, 1, 1, 1};
  glGenVertexArrays(1, &impl_->quad_vao);
  glGenBuffers(1, &impl_->quad_vbo);
  glBindVertexArray(impl_->quad_vao);
  glBindBuffer(GL_ARRAY_BUFFER, impl_->quad_vbo);
  glBufferData(GL_ARRAY_BUFFER, sizeof quad, quad, GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 0, nullptr);
  glGenTextures(1, &impl_->overlay_tex);
  glBindTexture(GL_TEXTURE_2D, impl_->overlay_tex);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, kOverlayWidth, kOverlayHeight, 0, GL_RGBA,
               GL_UNSIGNED_BYTE, nullptr);
}

GlRenderer::~GlRenderer() {
  for (GlMesh& m : impl_->blocks) m.release();
  for (GlMesh& m : impl_->packed) m.release();
  impl_->sphere.release();
  impl_->cylinder.release();
  impl_->cone.release();
  glDeleteBuffers(1, &impl_->quad_vbo);
  glDeleteVertexArrays(1, &impl_->quad_vao);
  glDeleteTextures(1, &impl_->overlay_tex);
  glDeleteProgram(impl_->mesh_prog);
  glDeleteProgram(impl_->overlay_prog);
}

void GlRenderer::sync(const SurfaceMesher& mesher) {
  const auto& blocks = mesher.blocks();
  if (impl_->blocks.size() != blocks.size()) {
    for (GlMesh& m : impl_->blocks) m.release();
    impl_->blocks.assign(blocks.size(), GlMesh{});
  }
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    GlMesh& m = impl_->blocks[b];
    if (m.version == blocks[b].version && m.vao != 0) continue;
    m.upload(blocks[b].vertices, blocks[b].indices);
    m.version = blocks[b].version;
  }
}

void GlRenderer::upload_once(std::vector<BlockMesh> blocks) {
  // Buffers of about 2 MiB of vertices: few GL objects, and little staging beside them.
  constexpr std::size_t kPackVertices = std::size_t{1} << 16;
  std::vector<MeshVertex> v;
  std::vector<std::uint32_t> idx;
  auto flush = [&] {
    if (idx.empty()) return;
    impl_->packed.emplace_back();
    impl_->packed.back().upload(v, idx);
    v.clear();
    idx.clear();
    // The blocks copied so far were meshed on the setup's threads, so their freed arrays sit in
    // those threads' malloc arenas, where the GL's buffers (allocated on this thread) cannot
    // reuse them: hand their pages back as the buffers grow, or the picture holds the whole mesh
    // twice (issue #30: the 512^3 field run's pictures peaked at ~430 MB).
    release_free_heap();
  };
  for (BlockMesh& b : blocks) {
    if (!v.empty() && v.size() + b.vertices.size() > kPackVertices) flush();
    const auto base = static_cast<std::uint32_t>(v.size());
    v.insert(v.end(), b.vertices.begin(), b.vertices.end());
    for (const std::uint32_t i : b.indices) idx.push_back(base + i);
    b = BlockMesh{};  // frees the block's arrays
  }
  flush();
}

void GlRenderer::draw(const OrbitCamera& camera, const TickSnapshot* tick,
                      const std::vector<std::string>& overlay, int width, int height) {
  Impl& d = *impl_;
  glViewport(0, 0, width, height);
  glClearColor(kBackgroundRgb[0] / 255.0f, kBackgroundRgb[1] / 255.0f, kBackgroundRgb[2] / 255.0f,
               1.0f);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  glDisable(GL_BLEND);
  glDepthMask(GL_TRUE);

  const Eigen::Matrix4f view_proj =
      camera.projection(static_cast<float>(width) / static_cast<float>(std::max(1, height))) *
      camera.view();
  const Eigen::Vector3f eye = camera.eye();
  const Eigen::Vector3f to_eye = (eye - camera.target).normalized();
  const Eigen::Vector3f right = to_eye.cross(Eigen::Vector3f::UnitZ()).normalized();
  const Eigen::Vector3f light =
      (to_eye + 0.6f * Eigen::Vector3f::UnitZ() - 0.4f * right).normalized();

  glUseProgram(d.mesh_prog);
  auto loc = [&](const char* name) { return glGetUniformLocation(d.mesh_prog, name); };
  glUniformMatrix4fv(loc("u_view_proj"), 1, GL_FALSE, view_proj.data());
  glUniform3fv(loc("u_eye"), 1, eye.data());
  glUniform3fv(loc("u_light"), 1, light.data());
  // One colour per material id (the shader's u_palette holds up to 8: enamel, dentin, pulp,
  // caries, ...).
  static_assert(kMaterialCount <= 8, "u_palette in the shader holds 8 materials");
  float palette[3 * 8] = {};
  for (int m = 1; m < kMaterialCount; ++m) {
    for (int c = 0; c < 3; ++c) palette[3 * m + c] = material_properties(m).rgb[c] / 255.0f;
  }
  glUniform3fv(loc("u_palette"), 8, palette);
  const GLint u_model = loc("u_model"), u_use = loc("u_use_color"), u_color = loc("u_color");
  const Eigen::Matrix4f identity = Eigen::Matrix4f::Identity();
  glUniformMatrix4fv(u_model, 1, GL_FALSE, identity.data());
  glUniform1i(u_use, 0);
  for (const GlMesh& m : d.blocks) m.draw();
  for (const GlMesh& m : d.packed) {
    m.draw();
    // A software GL (llvmpipe) bins the triangles of everything drawn since the last flush: one
    // buffer's worth at a time keeps its draw-time memory small (issue #30; the pixels are the
    // same, as the flushed parts are drawn in order).
    glFlush();
  }

  if (tick != nullptr && tick->tick >= 0) {
    const float rho = static_cast<float>(tick->tool_radius_m);
    const Eigen::Vector3f x1 = tick->device.x.cast<float>(), x2 = tick->proxy.x.cast<float>();
    // The shank: vertical at the home pose, turning with the device from there (the Phantom
    // stylus's own axis R1 e_z points sideways at home, through the tooth in the scenes).
    const Eigen::Vector3f axis =
        (tick->device.R * tick->device_R0.transpose() * Vec3::UnitZ()).cast<float>().normalized();
    auto solid = [&](const GlMesh& mesh, const Eigen::Matrix4f& model, const float* rgb) {
      glUniformMatrix4fv(u_model, 1, GL_FALSE, model.data());
      glUniform1i(u_use, 1);
      glUniform4f(u_color, rgb[0], rgb[1], rgb[2], 1.0f);
      mesh.draw();
    };
    // The device's tool: the tip sphere and its shank.
    solid(d.sphere, sphere_at(x1, rho), kToolRgb);
    solid(d.cylinder, along(x1, axis, 0.45f * rho, kShaftLength), kToolRgb);
    // The force on the proxy from the tooth.
    const Eigen::Vector3f f = tick->contact_force_n.cast<float>();
    const float fn = f.norm();
    if (fn > 1e-3f) {
      const float len = std::min(kArrowMaxM, kArrowMPerN * fn);
      const Eigen::Vector3f dir = f / fn;
      const float head = std::min(0.4f * len, 2.5f * rho);
      // Drawn over everything (it runs along the shank and out of the cavity).
      glDisable(GL_DEPTH_TEST);
      solid(d.cylinder, along(x2, dir, 0.25f * rho, len - head), kArrowRgb);
      solid(d.cone, along(x2 + (len - head) * dir, dir, 0.7f * rho, head), kArrowRgb);
      glEnable(GL_DEPTH_TEST);
    }
    if ((x2 - x1).norm() > kProxyGhostMinM) {
      glEnable(GL_BLEND);
      glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
      glDepthMask(GL_FALSE);
      glUniformMatrix4fv(u_model, 1, GL_FALSE, sphere_at(x2, rho).data());
      glUniform1i(u_use, 1);
      glUniform4fv(u_color, 1, kProxyRgba);
      d.sphere.draw();
      glDepthMask(GL_TRUE);
      glDisable(GL_BLEND);
    }
  }

  if (!overlay.empty()) {
    // Text by cairo (its toy font API, fontconfig's default sans) into a premultiplied ARGB
    // texture on a translucent white panel.
    const int stride = cairo_format_stride_for_width(CAIRO_FORMAT_ARGB32, kOverlayWidth);
    d.text_pixels.assign(static_cast<std::size_t>(stride) * kOverlayHeight, 0);
    cairo_surface_t* surf = cairo_image_surface_create_for_data(
        d.text_pixels.data(), CAIRO_FORMAT_ARGB32, kOverlayWidth, kOverlayHeight, stride);
    cairo_t* cr = cairo_create(surf);
    cairo_set_source_rgba(cr, 1, 1, 1, 0.8);
    cairo_paint(cr);
    cairo_select_font_face(cr, "DejaVu Sans Mono", CAIRO_FONT_SLANT_NORMAL,
                           CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(cr, 12.0);
    cairo_set_source_rgba(cr, 0.1, 0.1, 0.12, 1.0);
    double y = 22.0;
    for (const std::string& line : overlay) {
      cairo_move_to(cr, 10.0, y);
      cairo_show_text(cr, line.c_str());
      y += 25.0;
    }
    cairo_destroy(cr);
    cairo_surface_flush(surf);
    cairo_surface_destroy(surf);
    glBindTexture(GL_TEXTURE_2D, d.overlay_tex);
    glPixelStorei(GL_UNPACK_ROW_LENGTH, stride / 4);
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, kOverlayWidth, kOverlayHeight, GL_RGBA,
                    GL_UNSIGNED_BYTE, d.text_pixels.data());
    glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
    glDisable(GL_DEPTH_TEST);
    glEnable(GL_BLEND);
    glBlendFunc(GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
    glUseProgram(d.overlay_prog);
    const float x0 = -1.0f, y1 = 1.0f;
    const float x1 = -1.0f + 2.0f * kOverlayWidth / static_cast<float>(width);
    const float y0 = 1.0f - 2.0f * kOverlayHeight / static_cast<float>(height);
    glUniform4f(glGetUniformLocation(d.overlay_prog, "u_rect"), x0, y0, x1, y1);
    glUniform1i(glGetUniformLocation(d.overlay_prog, "u_tex"), 0);
    glActiveTexture(GL_TEXTURE0);
    glBindVertexArray(d.quad_vao);
    glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
    glDisable(GL_BLEND);
    glEnable(GL_DEPTH_TEST);
  }
  glBindVertexArray(0);
  glUseProgram(0);
}

RgbImage GlRenderer::read_pixels(int width, int height) {
  std::vector<std::uint8_t> rgba(static_cast<std::size_t>(width) * height * 4);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  RgbImage img;
  img.width = width;
  img.height = height;
  img.rgb.resize(static_cast<std::size_t>(width) * height * 3);
  for (int y = 0; y < height; ++y) {
    const std::size_t src = static_cast<std::size_t>(height - 1 - y) * width * 4;
    const std::size_t dst = static_cast<std::size_t>(y) * width * 3;
    for (int x = 0; x < width; ++x) {
      for (int c = 0; c < 3; ++c) img.rgb[dst + 3 * x + c] = rgba[src + 4 * x + c];
    }
  }
  return img;
}

}  // namespace dentsim::view
