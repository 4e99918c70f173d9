#include "vitreo/render/renderer.hpp"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <unordered_map>

#include "bitmap_font.hpp"
#include "shaders.hpp"
#include "vitreo/render/camera.hpp"

namespace vitreo::render {

Appearance default_appearance(MaterialKind kind, bool detached) {
  switch (kind) {
    case MaterialKind::Retina:
      // Attached retina is nearly transparent (the choroid shows through); detached retina turns
      // grey and translucent (oedema, with the yellowish subretinal fluid under it), as surgeons
      // see a bullous detachment.
      return detached ? Appearance{{0.62f, 0.61f, 0.57f}, 0.78f, 0.35f, 40.0f, true}
                      : Appearance{{0.95f, 0.80f, 0.70f}, 0.10f, 0.25f, 40.0f, false};
    case MaterialKind::Choroid: return {{0.80f, 0.32f, 0.16f}, 1.0f, 0.10f, 20.0f, false};
    case MaterialKind::Static: return {{0.92f, 0.90f, 0.86f}, 1.0f, 0.15f, 20.0f, false};
    // White-grey and glistening (a sharp, strong highlight), translucent enough to show what is under it.
    case MaterialKind::Membrane: return {{0.80f, 0.80f, 0.78f}, 0.66f, 0.75f, 90.0f, true};
    case MaterialKind::Gel: return {{0.86f, 0.88f, 0.90f}, 0.05f, 0.0f, 10.0f, false};
    case MaterialKind::Instrument: return {{0.62f, 0.63f, 0.66f}, 1.0f, 0.9f, 60.0f, true};
    case MaterialKind::Guide: return {{1.00f, 0.86f, 0.25f}, 0.85f, 0.0f, 1.0f, false};
    case MaterialKind::Glow: return {{1.0f, 1.0f, 1.0f}, 1.0f, 0.0f, 1.0f, false};
  }
  return {{1, 1, 1}, 1.0f, 0.0f, 1.0f, false};
}

Image StereoFrame::side_by_side() const { return Image{width(), eye_height, rgba}; }

Image StereoFrame::eye(int index) const {
  Image img{eye_width, eye_height, {}};
  img.rgba.resize(static_cast<std::size_t>(eye_width) * eye_height * 4);
  const std::size_t row = static_cast<std::size_t>(eye_width) * 4;
  for (int y = 0; y < eye_height; ++y) {
    std::memcpy(img.rgba.data() + y * row, rgba.data() + (static_cast<std::size_t>(y) * 2 + index) * row, row);
  }
  return img;
}

namespace {

GLuint compile(GLenum type, const char* src) {
  GLuint s = glCreateShader(type);
  glShaderSource(s, 1, &src, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[2048] = {};
    glGetShaderInfoLog(s, sizeof log, nullptr, log);
    glDeleteShader(s);
    throw RenderError(std::string("shader compile failed: ") + log);
  }
  return s;
}

GLuint link(const char* vs, const char* fs) {
  GLuint v = compile(GL_VERTEX_SHADER, vs);
  GLuint f = compile(GL_FRAGMENT_SHADER, fs);
  GLuint p = glCreateProgram();
  glAttachShader(p, v);
  glAttachShader(p, f);
  glLinkProgram(p);
  glDeleteShader(v);
  glDeleteShader(f);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[2048] = {};
    glGetProgramInfoLog(p, sizeof log, nullptr, log);
    glDeleteProgram(p);
    throw RenderError(std::string("program link failed: ") + log);
  }
  return p;
}

void check_gl(const char* where) {
  const GLenum e = glGetError();
  if (e != GL_NO_ERROR) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "OpenGL error 0x%04X %s", e, where);
    throw RenderError(buf);
  }
}

// Closest point on triangle abc to p (Ericson, Real-Time Collision Detection, 5.1.5), as barycentrics.
std::array<float, 3> closest_barycentric(Vec3 p, Vec3 a, Vec3 b, Vec3 c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const float d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return {1, 0, 0};
  const Vec3 bp = p - b;
  const float d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return {0, 1, 0};
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const float v = d1 / (d1 - d3);
    return {1 - v, v, 0};
  }
  const Vec3 cp = p - c;
  const float d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return {0, 0, 1};
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const float w = d2 / (d2 - d6);
    return {1 - w, 0, w};
  }
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const float w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0, 1 - w, w};
  }
  const float denom = 1.0f / (va + vb + vc);
  const float v = vb * denom, w = vc * denom;
  return {1 - v - w, v, w};
}

// Inverse of a rigid transform (rotation + translation).
Mat4 rigid_inverse(const Mat4& m) {
  Mat4 r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r.at(i, j) = m.at(j, i);
  const Vec3 t{m.at(0, 3), m.at(1, 3), m.at(2, 3)};
  for (int i = 0; i < 3; ++i) r.at(i, 3) = -(r.at(i, 0) * t.x + r.at(i, 1) * t.y + r.at(i, 2) * t.z);
  return r;
}

struct Texture {
  ImagePtr image;  // keeps the image alive so its address cannot be reused while cached
  GLuint id = 0;
  std::uint64_t last_used = 0;
};

struct BurnSpot {
  Vec2 uv;
  float g00 = 0, g01 = 0, g11 = 0;  // surface metric at the hit
  bool found = false;
};

struct GpuMesh {
  GLuint vao = 0, vbo = 0, ibo = 0;
  std::size_t vbo_bytes = 0, ibo_bytes = 0;
  GLsizei index_count = 0;
  MeshGeometryPtr geometry;  // last uploaded (kept alive: see Texture::image)
  std::uint64_t geometry_version = std::numeric_limits<std::uint64_t>::max();
  std::uint64_t topology_version = std::numeric_limits<std::uint64_t>::max();
  bool uploaded = false;
  Vec3 bbox_min, bbox_max;
  GLuint burn_texture = 0, burn_fbo = 0;
  std::vector<BurnSpot> burn_spots;  // per burn of the mesh, located once
  std::size_t burns_mature = 0;      // burns [0, this) are fully white and never painted again
  std::uint64_t last_used = 0;
};

struct DrawItem {
  const Mesh* mesh;
  GpuMesh* gpu;
  Appearance look;
  float sort_distance;
};

// The composite pass's circle of confusion is coc_px = scale·|1/z − 1/focus| (kCompositeFragment).
// A thin lens of aperture A blurs by the angle A·|1/z − 1/focus|, so scale = A · pixels per radian.
// Given a total depth of field T instead, the scale puts the first visible blur (1 px) at the near
// edge of the sharp zone, z = focus − T/2: scale = focus·(focus − T/2)/(T/2); the far edge, where
// 1/z changes more slowly, is then a little under 1 px.
float coc_scale(const Microscope& m, float focus_mm, float px_per_rad) {
  if (m.depth_of_field_mm > 0.0f && focus_mm > 0.0f) {
    const float half = std::min(0.5f * m.depth_of_field_mm, 0.9f * focus_mm);
    return focus_mm * (focus_mm - half) / half;
  }
  return m.aperture_mm * px_per_rad;
}

}  // namespace

struct StereoRenderer::Impl {
  RenderSettings s;
  // Shader variant key: the material in the low 4 bits, then one bit per feature define.
  static constexpr std::uint32_t kLight = 1u << 4, kShadows = 1u << 5, kGas = 1u << 6, kTexture = 1u << 7,
                                 kBurns = 1u << 8, kFlat = 1u << 9, kLight2 = 1u << 10;
  static constexpr int kDiscMaterial = 8;  // the fluid–gas interface (the renderer's own geometry)
  std::unordered_map<std::uint32_t, GLuint> scene_programs;  // shader variant by feature key
  std::unordered_map<GLuint, std::uint64_t> globals_stamp;    // eye_stamp when its globals were set
  std::uint64_t eye_stamp = 0;
  GLuint shadow_program = 0, burn_program = 0, text_program = 0;

  GLuint scene_program(std::uint32_t key) {
    auto it = scene_programs.find(key);
    if (it != scene_programs.end()) return it->second;
    shaders::FragmentVariant v;
    v.material = static_cast<int>(key & 15u);
    v.light = (key & kLight) != 0;
    v.shadows = (key & kShadows) != 0;
    v.light2 = (key & kLight2) != 0;
    v.gas = (key & kGas) != 0;
    v.texture = (key & kTexture) != 0;
    v.burns = (key & kBurns) != 0;
    v.flat = (key & kFlat) != 0;
    const GLuint p = link(shaders::kSceneVertex, shaders::scene_fragment_source(v).c_str());
    scene_programs.emplace(key, p);
    return p;
  }
  // Labels: the glyph atlas and a stream of quads rebuilt per eye.
  GLuint atlas_tex = 0, text_vao = 0, text_vbo = 0;
  std::size_t text_vbo_bytes = 0;
  struct TextVertex {
    float x, y, u, v, r, g, b, a;
  };
  std::vector<TextVertex> text_quads;
  std::vector<float> label_offsets;
  std::vector<std::array<float, 4>> label_boxes;
  GLuint fbo = 0, colour_rb = 0, depth_rb = 0;
  GLuint shadow_fbo = 0, shadow_tex = 0;
  // Depth of field: the eyes are drawn into textures, then composited into `fbo` (made on first use).
  GLuint dof_fbo = 0, dof_colour = 0, dof_depth = 0, composite_program = 0, empty_vao = 0;
  int dof_levels = 0;

  void make_dof_targets() {
    const int w = 2 * s.eye_width, h = s.eye_height;
    dof_levels = 1 + static_cast<int>(std::floor(std::log2(std::max(w, h))));
    glGenTextures(1, &dof_colour);
    glBindTexture(GL_TEXTURE_2D, dof_colour);
    glTexStorage2D(GL_TEXTURE_2D, dof_levels, GL_RGBA8, w, h);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glGenTextures(1, &dof_depth);
    glBindTexture(GL_TEXTURE_2D, dof_depth);
    glTexStorage2D(GL_TEXTURE_2D, 1, GL_DEPTH_COMPONENT24, w, h);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glGenFramebuffers(1, &dof_fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, dof_fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, dof_colour, 0);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, dof_depth, 0);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw RenderError("render: depth-of-field framebuffer incomplete");
    composite_program = link(shaders::kCompositeVertex, shaders::kCompositeFragment);
    glGenVertexArrays(1, &empty_vao);
  }
  GLuint burn_vao = 0, burn_vbo = 0;
  GpuMesh disc;  // the fluid–gas interface, rebuilt each frame it is shown
  std::unordered_map<std::uint32_t, GpuMesh> meshes;
  std::unordered_map<const Image*, Texture> textures;
  std::vector<std::uint8_t> premultiplied;  // upload scratch
  std::uint64_t frame = 0;
  std::vector<DrawItem> opaque, translucent, glows;
  // Uniform locations by program and name; the names are string literals, so their addresses
  // are stable keys and a lookup costs no string work.
  std::unordered_map<GLuint, std::unordered_map<const char*, GLint>> uniform_cache;

  GLint loc(GLuint program, const char* name) {
    auto& per_program = uniform_cache[program];
    auto it = per_program.find(name);
    if (it != per_program.end()) return it->second;
    const GLint l = glGetUniformLocation(program, name);
    per_program.emplace(name, l);
    return l;
  }
  void set(GLuint p, const char* n, const Mat4& m) { glUniformMatrix4fv(loc(p, n), 1, GL_FALSE, m.m.data()); }
  void set(GLuint p, const char* n, Vec3 v) { glUniform3f(loc(p, n), v.x, v.y, v.z); }
  void set(GLuint p, const char* n, float f) { glUniform1f(loc(p, n), f); }
  void set(GLuint p, const char* n, int i) { glUniform1i(loc(p, n), i); }
  void set(GLuint p, const char* n, bool b) { glUniform1i(loc(p, n), b ? 1 : 0); }

  explicit Impl(const RenderSettings& settings) : s(settings) {
    if (s.eye_width <= 0 || s.eye_height <= 0) throw RenderError("render: eye size must be positive");
    // The common variants up front, so the first frames do not stall on shader compilation.
    for (std::uint32_t m = 0; m < 6; ++m) {
      scene_program(m | kLight | kShadows | kTexture);
      scene_program(m | kLight | kShadows);
    }
    scene_program(static_cast<std::uint32_t>(MaterialKind::Guide));
    scene_program(static_cast<std::uint32_t>(MaterialKind::Glow));
    shadow_program = link(shaders::kShadowVertex, shaders::kShadowFragment);
    burn_program = link(shaders::kBurnVertex, shaders::kBurnFragment);
    text_program = link(shaders::kTextVertex, shaders::kTextFragment);
    {
      const Image a = font::atlas();
      glGenTextures(1, &atlas_tex);
      glBindTexture(GL_TEXTURE_2D, atlas_tex);
      glTexStorage2D(GL_TEXTURE_2D, 1, GL_RGBA8, a.width, a.height);
      glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
      glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, a.width, a.height, GL_RGBA, GL_UNSIGNED_BYTE, a.rgba.data());
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);  // crisp pixels at integer scales
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
      glGenVertexArrays(1, &text_vao);
      glBindVertexArray(text_vao);
      glGenBuffers(1, &text_vbo);
      glBindBuffer(GL_ARRAY_BUFFER, text_vbo);
      glEnableVertexAttribArray(0);
      glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, sizeof(TextVertex), reinterpret_cast<void*>(offsetof(TextVertex, x)));
      glEnableVertexAttribArray(1);
      glVertexAttribPointer(1, 2, GL_FLOAT, GL_FALSE, sizeof(TextVertex), reinterpret_cast<void*>(offsetof(TextVertex, u)));
      glEnableVertexAttribArray(2);
      glVertexAttribPointer(2, 4, GL_FLOAT, GL_FALSE, sizeof(TextVertex), reinterpret_cast<void*>(offsetof(TextVertex, r)));
      glBindVertexArray(0);
    }

    // Both eyes share one framebuffer, side by side, so one glReadPixels returns the stereo pair.
    glGenFramebuffers(1, &fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glGenRenderbuffers(1, &colour_rb);
    glBindRenderbuffer(GL_RENDERBUFFER, colour_rb);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, 2 * s.eye_width, s.eye_height);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, colour_rb);
    glGenRenderbuffers(1, &depth_rb);
    glBindRenderbuffer(GL_RENDERBUFFER, depth_rb);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, 2 * s.eye_width, s.eye_height);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_rb);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw RenderError("render: stereo framebuffer incomplete");

    glGenTextures(1, &shadow_tex);
    glBindTexture(GL_TEXTURE_2D, shadow_tex);
    glTexStorage2D(GL_TEXTURE_2D, 1, GL_DEPTH_COMPONENT24, s.shadow_map_size, s.shadow_map_size);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
    glGenFramebuffers(1, &shadow_fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, shadow_fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, shadow_tex, 0);
    glDrawBuffer(GL_NONE);
    glReadBuffer(GL_NONE);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw RenderError("render: shadow framebuffer incomplete");

    const float corners[] = {-1, -1, 1, -1, -1, 1, 1, 1};
    glGenVertexArrays(1, &burn_vao);
    glBindVertexArray(burn_vao);
    glGenBuffers(1, &burn_vbo);
    glBindBuffer(GL_ARRAY_BUFFER, burn_vbo);
    glBufferData(GL_ARRAY_BUFFER, sizeof corners, corners, GL_STATIC_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 0, nullptr);
    glBindVertexArray(0);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    check_gl("creating the renderer");
  }

  static void release(GpuMesh& g) {
    if (g.vao) glDeleteVertexArrays(1, &g.vao);
    if (g.vbo) glDeleteBuffers(1, &g.vbo);
    if (g.ibo) glDeleteBuffers(1, &g.ibo);
    if (g.burn_fbo) glDeleteFramebuffers(1, &g.burn_fbo);
    if (g.burn_texture) glDeleteTextures(1, &g.burn_texture);
    g = GpuMesh{};
  }

  ~Impl() {
    for (auto& [id, g] : meshes) release(g);
    release(disc);
    for (auto& [ptr, t] : textures) glDeleteTextures(1, &t.id);
    for (auto& [key, prog] : scene_programs) glDeleteProgram(prog);
    glDeleteProgram(shadow_program);
    glDeleteProgram(burn_program);
    glDeleteProgram(text_program);
    glDeleteTextures(1, &atlas_tex);
    glDeleteVertexArrays(1, &text_vao);
    glDeleteBuffers(1, &text_vbo);
    glDeleteFramebuffers(1, &fbo);
    glDeleteRenderbuffers(1, &colour_rb);
    glDeleteRenderbuffers(1, &depth_rb);
    glDeleteFramebuffers(1, &shadow_fbo);
    glDeleteTextures(1, &shadow_tex);
    if (dof_fbo) {
      glDeleteFramebuffers(1, &dof_fbo);
      glDeleteTextures(1, &dof_colour);
      glDeleteTextures(1, &dof_depth);
      glDeleteProgram(composite_program);
      glDeleteVertexArrays(1, &empty_vao);
    }
    glDeleteVertexArrays(1, &burn_vao);
    glDeleteBuffers(1, &burn_vbo);
  }

  // Uploads vertices (interleaved Vertex) and indices, reusing the buffers when they are big enough.
  void upload(GpuMesh& g, const MeshGeometry& geo, bool vertices, bool indices, RenderStats& stats) {
    if (g.vao == 0) {
      glGenVertexArrays(1, &g.vao);
      glGenBuffers(1, &g.vbo);
      glGenBuffers(1, &g.ibo);
      glBindVertexArray(g.vao);
      glBindBuffer(GL_ARRAY_BUFFER, g.vbo);
      glEnableVertexAttribArray(0);
      glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex), reinterpret_cast<void*>(offsetof(Vertex, position_mm)));
      glEnableVertexAttribArray(1);
      glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex), reinterpret_cast<void*>(offsetof(Vertex, normal)));
      glEnableVertexAttribArray(2);
      glVertexAttribPointer(2, 2, GL_FLOAT, GL_FALSE, sizeof(Vertex), reinterpret_cast<void*>(offsetof(Vertex, uv)));
      glEnableVertexAttribArray(3);
      glVertexAttribPointer(3, 1, GL_FLOAT, GL_FALSE, sizeof(Vertex), reinterpret_cast<void*>(offsetof(Vertex, detachment)));
      glEnableVertexAttribArray(4);
      glVertexAttribPointer(4, 1, GL_FLOAT, GL_FALSE, sizeof(Vertex), reinterpret_cast<void*>(offsetof(Vertex, highlight)));
      glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g.ibo);
      glBindVertexArray(0);
    }
    if (vertices) {
      const std::size_t bytes = geo.vertices.size() * sizeof(Vertex);
      glBindBuffer(GL_ARRAY_BUFFER, g.vbo);
      if (bytes > g.vbo_bytes) {
        glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(bytes), geo.vertices.data(), GL_DYNAMIC_DRAW);
        g.vbo_bytes = bytes;
      } else if (bytes > 0) {
        glBufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(bytes), geo.vertices.data());
      }
      Vec3 lo{std::numeric_limits<float>::max(), std::numeric_limits<float>::max(), std::numeric_limits<float>::max()};
      Vec3 hi = -lo;
      for (const Vertex& v : geo.vertices) {
        lo = {std::min(lo.x, v.position_mm.x), std::min(lo.y, v.position_mm.y), std::min(lo.z, v.position_mm.z)};
        hi = {std::max(hi.x, v.position_mm.x), std::max(hi.y, v.position_mm.y), std::max(hi.z, v.position_mm.z)};
      }
      g.bbox_min = lo;
      g.bbox_max = hi;
      ++stats.vertex_uploads;
    }
    if (indices) {
      const std::size_t bytes = geo.indices.size() * sizeof(std::uint32_t);
      glBindVertexArray(g.vao);  // the element buffer binding is VAO state
      glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g.ibo);
      if (bytes > g.ibo_bytes) {
        glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(bytes), geo.indices.data(), GL_DYNAMIC_DRAW);
        g.ibo_bytes = bytes;
      } else if (bytes > 0) {
        glBufferSubData(GL_ELEMENT_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(bytes), geo.indices.data());
      }
      glBindVertexArray(0);
      g.index_count = static_cast<GLsizei>(geo.indices.size());
      ++stats.index_uploads;
    }
  }

  GLuint texture_for(const ImagePtr& img, RenderStats& stats) {
    auto it = textures.find(img.get());
    if (it == textures.end()) {
      if (img->width <= 0 || img->height <= 0 ||
          img->rgba.size() != static_cast<std::size_t>(img->width) * img->height * 4)
        throw RenderError("render: texture size does not match its pixel data");
      Texture t;
      t.image = img;
      glGenTextures(1, &t.id);
      glBindTexture(GL_TEXTURE_2D, t.id);
      const int levels = 1 + static_cast<int>(std::floor(std::log2(std::max(img->width, img->height))));
      glTexStorage2D(GL_TEXTURE_2D, levels, GL_RGBA8, img->width, img->height);
      glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
      // Premultiplied alpha: mipmaps of straight-alpha coverage maps (vessels on a transparent
      // sheet) average the invisible texels' colour in and wash thin vessels out to pink.
      premultiplied.resize(img->rgba.size());
      for (std::size_t i = 0; i < img->rgba.size(); i += 4) {
        const unsigned a = img->rgba[i + 3];
        for (int k = 0; k < 3; ++k) premultiplied[i + k] = static_cast<std::uint8_t>((img->rgba[i + k] * a + 127) / 255);
        premultiplied[i + 3] = static_cast<std::uint8_t>(a);
      }
      glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, img->width, img->height, GL_RGBA, GL_UNSIGNED_BYTE, premultiplied.data());
      glGenerateMipmap(GL_TEXTURE_2D);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
      it = textures.emplace(img.get(), std::move(t)).first;
      ++stats.texture_uploads;
    }
    it->second.last_used = frame;
    return it->second.id;
  }

  // Where a burn lies in the mesh's uv space: the triangle under the hit, its uv there and the
  // surface metric JᵀJ (mm² per uv²). Found once per burn (uv is where the tissue lies at rest).
  BurnSpot locate_burn(const Mesh& mesh, const LaserBurn& burn) {
    const MeshGeometry& geo = *mesh.geometry;
    const Mat4 inv_model = rigid_inverse(mesh.model);
    // The triangle under the hit, its uv there and the surface metric JᵀJ (mm² per uv²).
    Vec2 uv{};
    float g00 = 0, g01 = 0, g11 = 0;
    bool found = false;
    const std::size_t tris = geo.indices.size() / 3;
    const auto on_triangle = [&](const Vertex& va, const Vertex& vb, const Vertex& vc, const std::array<float, 3>& bc) {
      uv = {va.uv.x * bc[0] + vb.uv.x * bc[1] + vc.uv.x * bc[2], va.uv.y * bc[0] + vb.uv.y * bc[1] + vc.uv.y * bc[2]};
      // J = E · T⁻¹ with E = [b−a, c−a] (3×2) and T = [uv_b−uv_a, uv_c−uv_a] (2×2).
      const Vec3 e1 = vb.position_mm - va.position_mm, e2 = vc.position_mm - va.position_mm;
      const float t00 = vb.uv.x - va.uv.x, t10 = vb.uv.y - va.uv.y;
      const float t01 = vc.uv.x - va.uv.x, t11 = vc.uv.y - va.uv.y;
      const float det = t00 * t11 - t01 * t10;
      if (std::fabs(det) <= 1e-12f) return;
      const float i00 = t11 / det, i01 = -t01 / det, i10 = -t10 / det, i11 = t00 / det;
      const Vec3 j0 = e1 * i00 + e2 * i10;  // d position / du
      const Vec3 j1 = e1 * i01 + e2 * i11;  // d position / dv
      g00 = dot(j0, j0);
      g01 = dot(j0, j1);
      g11 = dot(j1, j1);
      found = true;
    };
    if (burn.hit_point) {
      // Surface coordinates from the simulation: the triangle and the point in it, no search.
      const auto& c = burn.hit_point->corners;
      if (c[0] < geo.vertices.size() && c[1] < geo.vertices.size() && c[2] < geo.vertices.size()) {
        on_triangle(geo.vertices[c[0]], geo.vertices[c[1]], geo.vertices[c[2]], burn.hit_point->barycentric);
      }
    } else if (burn.hit_position_mm) {
      // Only a point: the nearest triangle of the current surface.
      const Vec3 p = inv_model.transform_point(*burn.hit_position_mm);
      float best = std::numeric_limits<float>::max();
      std::size_t best_t = 0;
      std::array<float, 3> best_bc{};
      for (std::size_t t = 0; t < tris; ++t) {
        const Vec3 a = geo.vertices[geo.indices[3 * t]].position_mm;
        const Vec3 bb = geo.vertices[geo.indices[3 * t + 1]].position_mm;
        const Vec3 c = geo.vertices[geo.indices[3 * t + 2]].position_mm;
        const auto bc = closest_barycentric(p, a, bb, c);
        const Vec3 q = a * bc[0] + bb * bc[1] + c * bc[2];
        const float d = dot(q - p, q - p);
        if (d < best) { best = d; best_t = t; best_bc = bc; }
      }
      if (tris > 0 && best <= 0.25f) {
        on_triangle(geo.vertices[geo.indices[3 * best_t]], geo.vertices[geo.indices[3 * best_t + 1]],
                    geo.vertices[geo.indices[3 * best_t + 2]], best_bc);
      }
    } else if (burn.hit_uv) {
      uv = *burn.hit_uv;
      // Without a hit triangle, use the metric of the triangle whose uv footprint contains it.
      for (std::size_t t = 0; t < tris && !found; ++t) {
        const Vertex& va = geo.vertices[geo.indices[3 * t]];
        const Vertex& vb = geo.vertices[geo.indices[3 * t + 1]];
        const Vertex& vc = geo.vertices[geo.indices[3 * t + 2]];
        const float t00 = vb.uv.x - va.uv.x, t10 = vb.uv.y - va.uv.y;
        const float t01 = vc.uv.x - va.uv.x, t11 = vc.uv.y - va.uv.y;
        const float det = t00 * t11 - t01 * t10;
        if (std::fabs(det) <= 1e-12f) continue;
        const float du = uv.x - va.uv.x, dv = uv.y - va.uv.y;
        const float l1 = (t11 * du - t01 * dv) / det, l2 = (-t10 * du + t00 * dv) / det;
        if (l1 < -1e-4f || l2 < -1e-4f || l1 + l2 > 1.0001f) continue;
        const Vec2 keep = uv;
        on_triangle(va, vb, vc, {1.0f - l1 - l2, l1, l2});
        uv = keep;
      }
    }
    return BurnSpot{uv, g00, g01, g11, found && burn.radius_mm > 0 && g00 * g11 - g01 * g01 > 0};
  }

  // Paints the burns of `mesh` that are still whitening (and new ones) into its burn texture, each
  // as white as its age makes it (the texture keeps the maximum, so whitening only adds).
  void paint_burns(const Mesh& mesh, GpuMesh& g, float whitening_s, RenderStats& stats) {
    if (mesh.burns.size() < g.burn_spots.size()) {  // the list shrank: a new case; start clean
      g.burns_mature = 0;
      g.burn_spots.clear();
      if (g.burn_fbo) {
        glBindFramebuffer(GL_FRAMEBUFFER, g.burn_fbo);
        glClearColor(0, 0, 0, 0);
        glClear(GL_COLOR_BUFFER_BIT);
      }
    }
    if (mesh.burns.size() == g.burns_mature) return;
    const int size = s.burn_texture_size;
    if (g.burn_texture == 0) {
      glGenTextures(1, &g.burn_texture);
      glBindTexture(GL_TEXTURE_2D, g.burn_texture);
      glTexStorage2D(GL_TEXTURE_2D, 1, GL_R8, size, size);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
      glGenFramebuffers(1, &g.burn_fbo);
      glBindFramebuffer(GL_FRAMEBUFFER, g.burn_fbo);
      glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, g.burn_texture, 0);
      glClearColor(0, 0, 0, 0);
      glClear(GL_COLOR_BUFFER_BIT);
    }
    glBindFramebuffer(GL_FRAMEBUFFER, g.burn_fbo);
    glViewport(0, 0, size, size);
    glDisable(GL_DEPTH_TEST);
    glEnable(GL_BLEND);
    glBlendEquation(GL_MAX);  // overlapping burns do not add up beyond white; a whitening burn only brightens
    glUseProgram(burn_program);
    glBindVertexArray(burn_vao);
    const float tau = std::max(whitening_s, 1e-3f);
    for (std::size_t b = g.burns_mature; b < mesh.burns.size(); ++b) {
      const LaserBurn& burn = mesh.burns[b];
      if (b == g.burn_spots.size()) {
        g.burn_spots.push_back(locate_burn(mesh, burn));
        ++(g.burn_spots.back().found ? stats.burns_painted : stats.burns_missed);
      }
      const BurnSpot& spot = g.burn_spots[b];
      if (!spot.found) continue;
      // Coagulation greys the retina over a few hundred milliseconds: 95 % white at whitening_s.
      const float whiteness = burn.age_s >= tau ? 1.0f : 1.0f - std::exp(-3.0f * std::max(burn.age_s, 0.0f) / tau);
      // Footprint of {d : dᵀGd ≤ r²}: half extents r·sqrt(diag(G⁻¹)), plus a texel of margin.
      const float det_g = spot.g00 * spot.g11 - spot.g01 * spot.g01;
      const float r = burn.radius_mm;
      const float margin = 2.0f / static_cast<float>(size);
      const float hx = r * std::sqrt(spot.g11 / det_g) + margin, hy = r * std::sqrt(spot.g00 / det_g) + margin;
      glUniform2f(loc(burn_program, "u_centre_uv"), spot.uv.x, spot.uv.y);
      glUniform2f(loc(burn_program, "u_half_extent_uv"), hx, hy);
      const float metric[4] = {spot.g00, spot.g01, spot.g01, spot.g11};
      glUniformMatrix2fv(loc(burn_program, "u_metric"), 1, GL_FALSE, metric);
      set(burn_program, "u_radius_mm", r);
      set(burn_program, "u_whiteness", whiteness);
      glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
    }
    // Burns that are fully white (or missed) are done for good.
    while (g.burns_mature < mesh.burns.size() && g.burns_mature < g.burn_spots.size() &&
           (!g.burn_spots[g.burns_mature].found || mesh.burns[g.burns_mature].age_s >= tau)) {
      ++g.burns_mature;
    }
    glBlendEquation(GL_FUNC_ADD);
    glDisable(GL_BLEND);
    glBindVertexArray(0);
  }

  void build_disc(const FrameScene& scene, RenderStats& stats) {
    const FluidGas& fg = *scene.fluid_gas;
    const Vec3 up = normalize(fg.up);
    const float R = scene.globe_radius_mm;
    const float h = std::clamp(fg.level_mm, -R, R);
    const float rad = std::sqrt(std::max(R * R - h * h, 0.0f));
    Vec3 a = std::fabs(up.x) < 0.9f ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
    const Vec3 t1 = normalize(cross(up, a));
    const Vec3 t2 = cross(up, t1);
    static thread_local MeshGeometry geo;
    geo.vertices.clear();
    geo.indices.clear();
    constexpr int kSegments = 96;
    const Vec3 centre = up * h;
    geo.vertices.push_back({centre, up, {0.5f, 0.5f}});
    for (int i = 0; i <= kSegments; ++i) {
      const float ang = 6.2831853f * static_cast<float>(i) / kSegments;
      const Vec3 p = centre + (t1 * std::cos(ang) + t2 * std::sin(ang)) * rad;
      geo.vertices.push_back({p, up, {0.5f + 0.5f * std::cos(ang), 0.5f + 0.5f * std::sin(ang)}});
      if (i > 0) {
        geo.indices.push_back(0);
        geo.indices.push_back(static_cast<std::uint32_t>(i));
        geo.indices.push_back(static_cast<std::uint32_t>(i + 1));
      }
    }
    upload(disc, geo, true, true, stats);
    --stats.vertex_uploads;  // the interface is the renderer's own geometry, not the scene's
    --stats.index_uploads;
  }

  static void draw(const DrawItem& item) {
    glBindVertexArray(item.gpu->vao);
    glDrawElements(GL_TRIANGLES, item.gpu->index_count, GL_UNSIGNED_INT, nullptr);
  }

  // Text and markers of the labels for one eye, as screen-space quads (pixels, rows from the top).
  void add_text_quad(float x0, float y0, float x1, float y1, float u0, float v0, float u1, float v1, Vec3 c, float a) {
    const TextVertex q[6] = {{x0, y0, u0, v0, c.x, c.y, c.z, a}, {x1, y0, u1, v0, c.x, c.y, c.z, a},
                             {x1, y1, u1, v1, c.x, c.y, c.z, a}, {x0, y0, u0, v0, c.x, c.y, c.z, a},
                             {x1, y1, u1, v1, c.x, c.y, c.z, a}, {x0, y1, u0, v1, c.x, c.y, c.z, a}};
    text_quads.insert(text_quads.end(), q, q + 6);
  }
  void add_text(const std::string& text, float x, float y, float scale, Vec3 colour, float alpha) {
    const float aw = static_cast<float>(font::kAtlasCell * font::kAtlasChars), ah = static_cast<float>(font::kAtlasCell);
    for (std::size_t i = 0; i < text.size(); ++i) {
      int c = static_cast<unsigned char>(text[i]);
      if (c >= 'a' && c <= 'z') c -= 'a' - 'A';
      if (c < font::kAtlasFirst || c >= font::kAtlasFirst + font::kAtlasChars) c = '?';
      const float cell = static_cast<float>((c - font::kAtlasFirst) * font::kAtlasCell);
      const float gx = x + static_cast<float>(i * font::kAdvance) * scale;
      // The glyph's 5×7 texels start one texel into its cell.
      add_text_quad(gx, y, gx + font::kGlyphWidth * scale, y + font::kGlyphHeight * scale, (cell + 1) / aw, 1 / ah,
                    (cell + 1 + font::kGlyphWidth) / aw, (1 + font::kGlyphHeight) / ah, colour, alpha);
    }
  }
  void draw_labels(const FrameScene& scene, const StereoViews& views) {
    if (scene.labels.empty()) return;
    const float scale = static_cast<float>(std::max(1, s.eye_height / 400));
    glDisable(GL_DEPTH_TEST);
    glEnable(GL_BLEND);
    glBlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
    glUseProgram(text_program);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, atlas_tex);
    set(text_program, "u_atlas", 0);
    glUniform2f(loc(text_program, "u_eye_size"), static_cast<float>(s.eye_width), static_cast<float>(s.eye_height));
    glBindVertexArray(text_vao);
    glBindBuffer(GL_ARRAY_BUFFER, text_vbo);
    // Where each label's text goes: to the right of its marker, moved down a line at a time while it
    // would cover an earlier label (placed in the left eye, the same offsets in both eyes so the
    // two pictures still fuse).
    auto project = [&](int e, const Label& l, float& px, float& py) {
      const Vec4 c = views.eye[e].view_projection * Vec4{l.anchor_mm.x, l.anchor_mm.y, l.anchor_mm.z, 1.0f};
      if (c.w <= 1e-4f) return false;  // behind the eye
      // Projected like the scene (so the label carries the anchor's disparity), rows from the top.
      px = (c.x / c.w * 0.5f + 0.5f) * static_cast<float>(s.eye_width);
      py = (0.5f - c.y / c.w * 0.5f) * static_cast<float>(s.eye_height);
      return px > -200 && px < s.eye_width + 200 && py > -50 && py < s.eye_height + 50;
    };
    const float m = 2.0f * scale, line = (font::kGlyphHeight + 3) * scale;
    label_offsets.assign(scene.labels.size(), 0.0f);
    label_boxes.clear();
    for (std::size_t i = 0; i < scene.labels.size(); ++i) {
      float px = 0, py = 0;
      if (!project(0, scene.labels[i], px, py)) continue;
      // The box: from the marker to a glyph's width past the text, so neighbours keep a gap.
      const float x0 = px - m - scale, w = static_cast<float>(font::text_width(scene.labels[i].text, static_cast<int>(scale)));
      const float x1 = px + 3.0f * m + w + font::kAdvance * scale;
      float y0 = py - 0.5f * font::kGlyphHeight * scale;
      for (int tries = 0; tries < 8; ++tries) {
        bool clear = true;
        for (const auto& b : label_boxes) clear = clear && (x1 < b[0] || x0 > b[2] || y0 + line <= b[1] || y0 >= b[3]);
        if (clear) break;
        y0 += line;
        label_offsets[i] += line;
      }
      label_boxes.push_back({x0, y0, x1, y0 + line});
    }
    for (int e = 0; e < 2; ++e) {
      text_quads.clear();
      for (std::size_t i = 0; i < scene.labels.size(); ++i) {
        const Label& l = scene.labels[i];
        float px = 0, py = 0;
        if (!project(e, l, px, py)) continue;
        // A marker on the structure (dark ring, bright dot), the name to its right (a leader line
        // down to it when the name had to move).
        add_text_quad(px - m - scale, py - m - scale, px + m + scale, py + m + scale, -1, 0, -1, 0, {0, 0, 0}, 0.6f);
        add_text_quad(px - m, py - m, px + m, py + m, -1, 0, -1, 0, l.colour, 1.0f);
        const float dy = label_offsets[i];
        if (dy > 0.0f) add_text_quad(px + 0.5f * m, py, px + 0.5f * m + scale, py + dy, -1, 0, -1, 0, l.colour, 0.8f);
        const float tx = px + 3.0f * m, ty = py - 0.5f * font::kGlyphHeight * scale + dy;
        add_text(l.text, tx + scale, ty + scale, scale, {0, 0, 0}, 0.7f);  // drop shadow: legible on any tissue
        add_text(l.text, tx, ty, scale, l.colour, 1.0f);
      }
      if (text_quads.empty()) continue;
      const std::size_t bytes = text_quads.size() * sizeof(TextVertex);
      if (bytes > text_vbo_bytes) {
        glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(bytes), text_quads.data(), GL_STREAM_DRAW);
        text_vbo_bytes = bytes;
      } else {
        glBufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(bytes), text_quads.data());
      }
      glViewport(e * s.eye_width, 0, s.eye_width, s.eye_height);
      glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(text_quads.size()));
    }
    glBindVertexArray(0);
    glDisable(GL_BLEND);
    glEnable(GL_DEPTH_TEST);
  }

  void render(const FrameScene& scene, StereoFrame& out, RenderStats& stats);
};

void StereoRenderer::Impl::render(const FrameScene& scene, StereoFrame& out, RenderStats& stats) {
  ++frame;
  // ---- 1. sync GPU state with the scene ----
  opaque.clear();
  translucent.clear();
  glows.clear();
  std::uint64_t triangles = 0;
  for (const Mesh& mesh : scene.meshes) {
    if (!mesh.geometry) continue;
    GpuMesh& g = meshes[mesh.id];
    const bool new_vertices = !g.uploaded || g.geometry != mesh.geometry || g.geometry_version != mesh.geometry_version;
    const bool new_indices = !g.uploaded || g.topology_version != mesh.topology_version ||
                             static_cast<std::size_t>(g.index_count) != mesh.geometry->indices.size();
    if (new_vertices || new_indices) upload(g, *mesh.geometry, new_vertices, new_indices, stats);
    g.uploaded = true;
    g.geometry = mesh.geometry;
    g.geometry_version = mesh.geometry_version;
    g.topology_version = mesh.topology_version;
    g.last_used = frame;
    paint_burns(mesh, g, scene.burn_whitening_s, stats);
    if (g.index_count == 0) continue;
    Appearance look = default_appearance(mesh.material, mesh.detached);
    look.base_colour = {look.base_colour.x * mesh.tint.x, look.base_colour.y * mesh.tint.y, look.base_colour.z * mesh.tint.z};
    if (mesh.opacity >= 0) look.opacity = mesh.material == MaterialKind::Glow ? mesh.opacity : std::min(mesh.opacity, 1.0f);
    if (mesh.casts_shadow) look.casts_shadow = *mesh.casts_shadow;
    const bool blended = mesh.material == MaterialKind::Retina || mesh.material == MaterialKind::Guide || look.opacity < 1.0f;
    if (mesh.material == MaterialKind::Glow) {
      glows.push_back(DrawItem{&mesh, &g, look, 0.0f});
    } else {
      (blended ? translucent : opaque).push_back(DrawItem{&mesh, &g, look, 0.0f});
    }
    triangles += static_cast<std::uint64_t>(g.index_count / 3);
  }
  // Meshes that left the scene (removed tissue, withdrawn instruments) free their GPU memory.
  for (auto it = meshes.begin(); it != meshes.end();) {
    if (it->second.last_used != frame) {
      release(it->second);
      it = meshes.erase(it);
    } else {
      ++it;
    }
  }
  for (auto it = textures.begin(); it != textures.end();) {
    bool used = false;
    for (const Mesh& m : scene.meshes) used = used || m.texture.get() == it->first;
    if (!used) {
      glDeleteTextures(1, &it->second.id);
      it = textures.erase(it);
    } else {
      ++it;
    }
  }
  for (const Mesh& m : scene.meshes)
    if (m.texture) texture_for(m.texture, stats);

  // ---- 2. shadow map from the primary light: the light pipe, else the chandelier ----
  // (a chandelier beside a light pipe lights without shadows of its own: one map per frame).
  const LightPipe* primary = scene.light_pipe ? &*scene.light_pipe : scene.chandelier ? &*scene.chandelier : nullptr;
  const LightPipe* secondary = scene.light_pipe && scene.chandelier ? &*scene.chandelier : nullptr;
  Mat4 light_vp;
  bool shadows = false;
  Vec3 light_dir{0, 0, -1};
  if (primary) {
    const LightPipe& lp = *primary;
    light_dir = normalize(lp.direction);
    const Vec3 helper = std::fabs(light_dir.z) < 0.9f ? Vec3{0, 0, 1} : Vec3{1, 0, 0};
    // A perspective map covers at most ~160°; wider cones (chandelier-like) are unshadowed outside it.
    const float half = std::min(lp.cone_half_angle_deg, 80.0f) * 3.14159265f / 180.0f;
    light_vp = perspective(2.0f * half, 1.0f, 0.2f, 2.5f * scene.globe_radius_mm + 10.0f) *
               look_at(lp.tip_mm, lp.tip_mm + light_dir, helper);
    bool any_caster = false;
    for (const DrawItem& d : opaque) any_caster = any_caster || d.look.casts_shadow;
    for (const DrawItem& d : translucent) any_caster = any_caster || d.look.casts_shadow;
    if (any_caster) {
      shadows = true;
      glBindFramebuffer(GL_FRAMEBUFFER, shadow_fbo);
      glViewport(0, 0, s.shadow_map_size, s.shadow_map_size);
      glDepthMask(GL_TRUE);
      glClear(GL_DEPTH_BUFFER_BIT);
      glEnable(GL_DEPTH_TEST);
      glDepthFunc(GL_LESS);
      glEnable(GL_POLYGON_OFFSET_FILL);
      glPolygonOffset(2.0f, 4.0f);  // slope-scaled bias against self-shadowing "acne"
      glUseProgram(shadow_program);
      set(shadow_program, "u_light_view_projection", light_vp);
      for (const auto* list : {&opaque, &translucent}) {
        for (const DrawItem& d : *list) {
          if (!d.look.casts_shadow) continue;
          set(shadow_program, "u_model", d.mesh->model);
          draw(d);
        }
      }
      glDisable(GL_POLYGON_OFFSET_FILL);
    }
  }

  // ---- 3. both eyes ----
  const StereoViews views = stereo_views(scene.microscope, scene.globe_radius_mm, s.eye_width, s.eye_height);
  if (scene.fluid_gas) build_disc(scene, stats);

  const bool dof = scene.microscope.depth_of_field;
  if (dof && dof_fbo == 0) make_dof_targets();
  glBindFramebuffer(GL_FRAMEBUFFER, dof ? dof_fbo : fbo);
  glViewport(0, 0, 2 * s.eye_width, s.eye_height);
  glDepthMask(GL_TRUE);
  glClearColor(0, 0, 0, 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDisable(GL_CULL_FACE);

  // Per-frame and per-eye uniforms are set on each shader variant the first time it is used for an
  // eye (variants are separate programs, see shaders.cpp).
  const bool light_on = primary != nullptr;
  const bool gas_on = scene.fluid_gas.has_value();
  float disc_radius = 0;
  Vec3 gas_up{0, 0, 1};
  if (gas_on) {
    gas_up = normalize(scene.fluid_gas->up);
    const float R = scene.globe_radius_mm;
    const float h = std::clamp(scene.fluid_gas->level_mm, -R, R);
    disc_radius = std::sqrt(std::max(R * R - h * h, 0.0f));
  }
  // The image is rendered upside down (y flipped in clip space) so that glReadPixels, which returns
  // the bottom row first, yields rows top to bottom without a copy. Winding flips too; no culling.
  Mat4 flip;
  flip.at(1, 1) = -1.0f;
  const EyeView* eye_view = nullptr;
  GLuint current = 0;
  auto set_light = [&](GLuint p, const LightPipe& lp, const char* pos, const char* dir, const char* outer, const char* inner,
                       const char* intensity, const char* range) {
    const float half = lp.cone_half_angle_deg * 3.14159265f / 180.0f;
    set(p, pos, lp.tip_mm);
    set(p, dir, normalize(lp.direction));
    set(p, outer, std::cos(half));
    set(p, inner, std::cos(0.7f * half));
    set(p, intensity, lp.intensity);
    set(p, range, std::max(lp.range_mm, 1e-3f));
  };
  auto use_variant = [&](std::uint32_t key) {
    const GLuint p = scene_program(key);
    if (p != current) {
      glUseProgram(p);
      current = p;
    }
    std::uint64_t& stamp = globals_stamp[p];
    if (stamp == eye_stamp) return p;
    stamp = eye_stamp;
    set(p, "u_view_projection", flip * eye_view->view_projection);
    set(p, "u_camera", eye_view->position_mm);
    set(p, "u_light_view_projection", light_vp);
    if (primary) set_light(p, *primary, "u_light_position", "u_light_direction", "u_cos_outer", "u_cos_inner", "u_light_intensity", "u_light_range");
    if (secondary)
      set_light(p, *secondary, "u_light2_position", "u_light2_direction", "u_light2_cos_outer", "u_light2_cos_inner",
                "u_light2_intensity", "u_light2_range");
    set(p, "u_ambient", scene.ambient);
    set(p, "u_globe_radius", scene.globe_radius_mm);
    set(p, "u_haze_density", scene.haze_density_per_mm);
    set(p, "u_gas_on", gas_on);
    if (gas_on) {
      set(p, "u_gas_up", gas_up);
      set(p, "u_gas_level", scene.fluid_gas->level_mm);
      set(p, "u_disc_radius", disc_radius);
    }
    set(p, "u_texture", 0);
    set(p, "u_burns", 1);
    set(p, "u_shadow_map", 2);
    return p;
  };
  glActiveTexture(GL_TEXTURE2);
  glBindTexture(GL_TEXTURE_2D, shadow_tex);

  auto draw_scene_item = [&](const DrawItem& d, int material) {
    const bool has_tex = d.mesh && d.mesh->texture;
    const bool has_burns = d.gpu->burn_texture != 0;
    const bool unlit = material == static_cast<int>(MaterialKind::Guide) || material == static_cast<int>(MaterialKind::Glow);
    const std::uint32_t key = unlit ? static_cast<std::uint32_t>(material)
                                    : static_cast<std::uint32_t>(material) | (light_on ? kLight : 0u) |
                                          (shadows ? kShadows : 0u) | (secondary ? kLight2 : 0u) | (gas_on ? kGas : 0u) |
                                          (has_tex ? kTexture : 0u) | (has_burns ? kBurns : 0u) |
                                          (scene.flat_shading ? kFlat : 0u);
    const GLuint p = use_variant(key);
    set(p, "u_model", d.mesh ? d.mesh->model : Mat4::identity());
    set(p, "u_base_colour", d.look.base_colour);
    set(p, "u_opacity", d.look.opacity);
    set(p, "u_specular", d.look.specular);
    set(p, "u_shininess", d.look.shininess);
    if (material == 0) {
      const Appearance det = default_appearance(MaterialKind::Retina, true);
      const Vec3 t = d.mesh->tint;
      set(p, "u_detached", d.mesh->detached);
      set(p, "u_detached_colour", Vec3{det.base_colour.x * t.x, det.base_colour.y * t.y, det.base_colour.z * t.z});
      set(p, "u_detached_opacity", d.mesh->detached ? d.look.opacity : det.opacity);
    }
    if (has_tex) {
      glActiveTexture(GL_TEXTURE0);
      glBindTexture(GL_TEXTURE_2D, textures.at(d.mesh->texture.get()).id);
    }
    if (has_burns) {
      glActiveTexture(GL_TEXTURE1);
      glBindTexture(GL_TEXTURE_2D, d.gpu->burn_texture);
    }
    // Wireframe (operator toggle): the deformable tissue's triangles as lines, to see the mesh.
    const bool lines = scene.wireframe && d.mesh &&
                       (d.mesh->material == MaterialKind::Retina || d.mesh->material == MaterialKind::Membrane ||
                        d.mesh->material == MaterialKind::Gel);
    if (lines) glPolygonMode(GL_FRONT_AND_BACK, GL_LINE);
    draw(d);
    if (lines) glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
  };

  // Translucent layers back to front, from the midpoint between the eyes (the base is small
  // against the viewing distance, so both eyes agree on the order).
  const Vec3 mid = (views.eye[0].position_mm + views.eye[1].position_mm) * 0.5f;
  for (DrawItem& d : translucent) {
    const Vec3 c = d.mesh->model.transform_point((d.gpu->bbox_min + d.gpu->bbox_max) * 0.5f);
    d.sort_distance = length(c - mid);
  }
  // The retina is the back layer of the eye's interior (it lies on the choroid) and the guides are
  // drawn on it: every other translucent layer (membranes on it, gel, the detached retina's
  // neighbours) is on their vitreous side, so they come first whatever their bounding boxes say (a
  // large cap's centre sits nearer the camera than a small membrane lying on it).
  auto layer = [](const DrawItem& d) {
    return d.mesh->material == MaterialKind::Retina ? 0 : d.mesh->material == MaterialKind::Guide ? 1 : 2;
  };
  std::stable_sort(translucent.begin(), translucent.end(), [&](const DrawItem& a, const DrawItem& b) {
    if (layer(a) != layer(b)) return layer(a) < layer(b);
    return a.sort_distance > b.sort_distance;
  });

  for (int e = 0; e < 2; ++e) {
    eye_view = &views.eye[e];
    ++eye_stamp;
    glViewport(e * s.eye_width, 0, s.eye_width, s.eye_height);
    glDisable(GL_BLEND);
    glDepthMask(GL_TRUE);
    const auto seen = [e](const DrawItem& d) { return d.mesh == nullptr || ((d.mesh->eyes >> e) & 1u) != 0; };
    for (const DrawItem& d : opaque)
      if (seen(d)) draw_scene_item(d, static_cast<int>(d.mesh->material));
    glEnable(GL_BLEND);
    glBlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
    glDepthMask(GL_FALSE);
    for (const DrawItem& d : translucent)
      if (seen(d)) draw_scene_item(d, static_cast<int>(d.mesh->material));
    if (gas_on && disc.index_count > 0) {
      DrawItem di{nullptr, &disc, {{0.80f, 0.84f, 0.90f}, 0.12f, 1.2f, 80.0f, false}, 0};
      draw_scene_item(di, kDiscMaterial);
    }
    // Light itself last, added to whatever it shines through (order does not matter for a sum).
    glBlendFuncSeparate(GL_ONE, GL_ONE, GL_ZERO, GL_ONE);
    for (const DrawItem& d : glows)
      if (seen(d)) draw_scene_item(d, static_cast<int>(MaterialKind::Glow));
    glDepthMask(GL_TRUE);
    glDisable(GL_BLEND);
  }

  if (dof) {
    // Focus: blur each pixel by its circle of confusion (see kCompositeFragment).
    glBindTexture(GL_TEXTURE_2D, dof_colour);
    glGenerateMipmap(GL_TEXTURE_2D);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_BLEND);
    const GLuint cp = composite_program;
    glUseProgram(cp);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, dof_colour);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, dof_depth);
    set(cp, "u_colour", 0);
    set(cp, "u_depth", 1);
    glUniform2f(loc(cp, "u_size"), static_cast<float>(2 * s.eye_width), static_cast<float>(s.eye_height));
    set(cp, "u_max_lod", static_cast<float>(std::min(dof_levels - 1, 6)));
    glBindVertexArray(empty_vao);
    for (int e = 0; e < 2; ++e) {
      const EyeView& ev = views.eye[e];
      glViewport(e * s.eye_width, 0, s.eye_width, s.eye_height);
      glUniform2f(loc(cp, "u_eye_x"), static_cast<float>(e * s.eye_width), static_cast<float>((e + 1) * s.eye_width));
      set(cp, "u_near", ev.near_mm);
      set(cp, "u_far", ev.far_mm);
      set(cp, "u_focus", ev.focus_distance_mm);
      set(cp, "u_coc_scale", coc_scale(scene.microscope, ev.focus_distance_mm, 0.5f * static_cast<float>(s.eye_height) * ev.projection.at(1, 1)));
      glDrawArrays(GL_TRIANGLES, 0, 3);
    }
    glEnable(GL_DEPTH_TEST);
  }
  // Labels over the (focused or not) picture: they are an overlay, never blurred.
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  draw_labels(scene, views);

  // ---- 4. read both eyes at once ----
  out.eye_width = s.eye_width;
  out.eye_height = s.eye_height;
  out.sim_time_s = scene.sim_time_s;
  out.step_index = scene.step_index;
  out.frame_index = frame;
  out.rgba.resize(static_cast<std::size_t>(2 * s.eye_width) * s.eye_height * 4);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, 2 * s.eye_width, s.eye_height, GL_RGBA, GL_UNSIGNED_BYTE, out.rgba.data());
  glBindVertexArray(0);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  check_gl("rendering a frame");
  stats.triangles_last_frame = triangles;
  ++stats.frames;
}

StereoRenderer::StereoRenderer(RenderSettings settings)
    : settings_(settings), impl_(std::make_unique<Impl>(settings)) {}

StereoRenderer::~StereoRenderer() = default;

void StereoRenderer::render(const FrameScene& scene, StereoFrame& out) { impl_->render(scene, out, stats_); }

}  // namespace vitreo::render
