// Stereo 1280×1024 frame time of the renderer at several triangle counts, and its overhead against
// bare OpenGL drawing the same triangles (issue 8 bar: ≤ 20 %).
//
//   build/test/bench/bench_render --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
//
// Two references draw the same triangles of the same scene, re-uploading the deforming retina every
// frame as the renderer does, both eyes into one side-by-side framebuffer, one glReadPixels:
//  - "bare GL, same shading" (BareGlSameShading): hand-written GL calls with the renderer's own
//    shaders, textures and shadow pass, uniforms set once — what the renderer costs beyond the GL
//    work its picture needs (scene sync, per-mesh state, sorting, variant selection). This is the
//    issue-8 bar (≤ 20 %): BM_RendererOverhead, counter overhead_pct.
//  - "bare GL, plain" (BarePlainGl): one Blinn-Phong program, a directional light, no shadows,
//    textures or blending — the reference of PLATFORM-NOTES; counter plain_ratio shows what the
//    microscope look (spotlight, shadow map, translucent retina, haze) costs on top.
// Each BM_RendererOverhead iteration times all three back to back (the machine is shared and
// noisy) and reports medians.
#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "shaders.hpp"  // the renderer's GLSL, for the same-shading reference
#include "synthetic_scene.hpp"
#include "vitreo/render/camera.hpp"
#include "vitreo/render/egl_context.hpp"
#include "vitreo/render/renderer.hpp"

namespace vr = vitreo::render;
namespace vt = vitreo::render::testing;
using Clock = std::chrono::steady_clock;

namespace {

constexpr int kEyeW = 1280, kEyeH = 1024;

vr::EglContext& context() {
  static vr::EglContext ctx;  // one per process; benchmarks run on the main thread
  return ctx;
}

vr::FrameScene scene_for(int triangles) {
  vt::SyntheticOptions o;
  o.retina_triangles = triangles / 2;  // choroid and retina shells of equal size, plus two shafts
  return vt::make_scene(o);
}

std::uint64_t count_triangles(const vr::FrameScene& s) {
  std::uint64_t n = 0;
  for (const auto& m : s.meshes) n += m.geometry->indices.size() / 3;
  return n;
}

// Marks the retina as deformed (new geometry object and version), as the simulation will every step.
void deform(vr::FrameScene& s) {
  for (auto& m : s.meshes) {
    if (m.id != vt::kRetina) continue;
    m.geometry = std::make_shared<vr::MeshGeometry>(*m.geometry);
    ++m.geometry_version;
  }
}

GLuint compile(GLenum type, const char* src) {
  GLuint sh = glCreateShader(type);
  glShaderSource(sh, 1, &src, nullptr);
  glCompileShader(sh);
  return sh;
}

// The bare-GL reference: all meshes merged into one buffer (instrument vertices pre-transformed).
class BarePlainGl {
 public:
  explicit BarePlainGl(const vr::FrameScene& s) {
    const char* vs = R"(#version 450 core
layout(location = 0) in vec3 p; layout(location = 1) in vec3 n;
uniform mat4 vp; out vec3 vn; out vec3 vp_world;
void main() { vn = n; vp_world = p; gl_Position = vp * vec4(p, 1.0); })";
    const char* fs = R"(#version 450 core
in vec3 vn; in vec3 vp_world; uniform vec3 cam; out vec4 o;
void main() {
  vec3 n = normalize(vn); vec3 v = normalize(cam - vp_world); if (dot(n, v) < 0.0) n = -n;
  vec3 l = normalize(vec3(0.3, 0.2, 1.0)); vec3 h = normalize(l + v);
  float d = max(dot(n, l), 0.0); float sp = pow(max(dot(n, h), 0.0), 40.0);
  o = vec4(vec3(0.8, 0.35, 0.2) * (0.05 + d) + vec3(0.3) * sp, 1.0);
})";
    prog_ = glCreateProgram();
    glAttachShader(prog_, compile(GL_VERTEX_SHADER, vs));
    glAttachShader(prog_, compile(GL_FRAGMENT_SHADER, fs));
    glLinkProgram(prog_);
    for (const auto& m : s.meshes) {
      const auto base = static_cast<std::uint32_t>(verts_.size());
      if (m.id == vt::kRetina) {
        retina_offset_ = verts_.size();
        retina_count_ = m.geometry->vertices.size();
      }
      for (vr::Vertex v : m.geometry->vertices) {
        v.position_mm = m.model.transform_point(v.position_mm);
        v.normal = m.model.transform_dir(v.normal);
        verts_.push_back(v);
      }
      for (std::uint32_t i : m.geometry->indices) indices_.push_back(base + i);
    }
    glGenVertexArrays(1, &vao_);
    glBindVertexArray(vao_);
    glGenBuffers(1, &vbo_);
    glBindBuffer(GL_ARRAY_BUFFER, vbo_);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(verts_.size() * sizeof(vr::Vertex)), verts_.data(), GL_DYNAMIC_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(vr::Vertex), nullptr);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(vr::Vertex), reinterpret_cast<void*>(offsetof(vr::Vertex, normal)));
    glGenBuffers(1, &ibo_);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo_);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(indices_.size() * 4), indices_.data(), GL_STATIC_DRAW);
    glBindVertexArray(0);
    glGenFramebuffers(1, &fbo_);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glGenRenderbuffers(2, rb_);
    glBindRenderbuffer(GL_RENDERBUFFER, rb_[0]);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, 2 * kEyeW, kEyeH);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb_[0]);
    glBindRenderbuffer(GL_RENDERBUFFER, rb_[1]);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, 2 * kEyeW, kEyeH);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb_[1]);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    views_ = vr::stereo_views(s.microscope, s.globe_radius_mm, kEyeW, kEyeH);
    pixels_.resize(static_cast<std::size_t>(2 * kEyeW) * kEyeH * 4);
  }
  ~BarePlainGl() {
    glDeleteProgram(prog_);
    glDeleteBuffers(1, &vbo_);
    glDeleteBuffers(1, &ibo_);
    glDeleteVertexArrays(1, &vao_);
    glDeleteFramebuffers(1, &fbo_);
    glDeleteRenderbuffers(2, rb_);
  }
  void frame() {
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glBindBuffer(GL_ARRAY_BUFFER, vbo_);  // the retina deforms: re-upload its vertices
    glBufferSubData(GL_ARRAY_BUFFER, static_cast<GLintptr>(retina_offset_ * sizeof(vr::Vertex)),
                    static_cast<GLsizeiptr>(retina_count_ * sizeof(vr::Vertex)), verts_.data() + retina_offset_);
    glViewport(0, 0, 2 * kEyeW, kEyeH);
    glClearColor(0, 0, 0, 1);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glEnable(GL_DEPTH_TEST);
    glUseProgram(prog_);
    glBindVertexArray(vao_);
    for (int e = 0; e < 2; ++e) {
      glViewport(e * kEyeW, 0, kEyeW, kEyeH);
      glUniformMatrix4fv(glGetUniformLocation(prog_, "vp"), 1, GL_FALSE, views_.eye[e].view_projection.m.data());
      const vr::Vec3 c = views_.eye[e].position_mm;
      glUniform3f(glGetUniformLocation(prog_, "cam"), c.x, c.y, c.z);
      glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(indices_.size()), GL_UNSIGNED_INT, nullptr);
    }
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, 2 * kEyeW, kEyeH, GL_RGBA, GL_UNSIGNED_BYTE, pixels_.data());
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
  }

 private:
  GLuint prog_ = 0, vao_ = 0, vbo_ = 0, ibo_ = 0, fbo_ = 0, rb_[2] = {0, 0};
  std::vector<vr::Vertex> verts_;
  std::vector<std::uint32_t> indices_;
  std::size_t retina_offset_ = 0, retina_count_ = 0;
  vr::StereoViews views_;
  std::vector<std::uint8_t> pixels_;
};


// The renderer's frame for this scene, written out as straight GL calls (see the header comment).
class BareGlSameShading {
 public:
  explicit BareGlSameShading(const vr::FrameScene& s) {
    views_ = vr::stereo_views(s.microscope, s.globe_radius_mm, kEyeW, kEyeH);
    const vr::LightPipe& lp = *s.light_pipe;
    const vr::Vec3 dir = vr::normalize(lp.direction);
    light_dir_ = dir;
    const vr::Vec3 helper = std::fabs(dir.z) < 0.9f ? vr::Vec3{0, 0, 1} : vr::Vec3{1, 0, 0};
    const float half = std::min(lp.cone_half_angle_deg, 80.0f) * 3.14159265f / 180.0f;
    light_vp_ = vr::perspective(2.0f * half, 1.0f, 0.2f, 2.5f * s.globe_radius_mm + 10.0f) *
                vr::look_at(lp.tip_mm, lp.tip_mm + dir, helper);
    const char* depth_vs = vitreo::render::shaders::kShadowVertex;
    depth_prog_ = link(depth_vs, vitreo::render::shaders::kShadowFragment);
    for (const auto& m : s.meshes) {
      Item it;
      it.mesh = &m;
      it.look = vr::default_appearance(m.material, m.detached);
      vitreo::render::shaders::FragmentVariant variant;
      variant.material = static_cast<int>(m.material);
      variant.light = variant.shadows = true;
      variant.texture = m.texture != nullptr;
      const std::string src = vitreo::render::shaders::scene_fragment_source(variant);
      it.prog = link(vitreo::render::shaders::kSceneVertex, src.c_str());
      glGenVertexArrays(1, &it.vao);
      glBindVertexArray(it.vao);
      glGenBuffers(1, &it.vbo);
      glBindBuffer(GL_ARRAY_BUFFER, it.vbo);
      glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(m.geometry->vertices.size() * sizeof(vr::Vertex)),
                   m.geometry->vertices.data(), GL_DYNAMIC_DRAW);
      const GLsizei st = sizeof(vr::Vertex);
      glEnableVertexAttribArray(0);
      glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, st, reinterpret_cast<void*>(offsetof(vr::Vertex, position_mm)));
      glEnableVertexAttribArray(1);
      glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, st, reinterpret_cast<void*>(offsetof(vr::Vertex, normal)));
      glEnableVertexAttribArray(2);
      glVertexAttribPointer(2, 2, GL_FLOAT, GL_FALSE, st, reinterpret_cast<void*>(offsetof(vr::Vertex, uv)));
      glEnableVertexAttribArray(3);
      glVertexAttribPointer(3, 1, GL_FLOAT, GL_FALSE, st, reinterpret_cast<void*>(offsetof(vr::Vertex, detachment)));
      glEnableVertexAttribArray(4);
      glVertexAttribPointer(4, 1, GL_FLOAT, GL_FALSE, st, reinterpret_cast<void*>(offsetof(vr::Vertex, highlight)));
      glGenBuffers(1, &it.ibo);
      glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, it.ibo);
      glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(m.geometry->indices.size() * 4),
                   m.geometry->indices.data(), GL_STATIC_DRAW);
      it.count = static_cast<GLsizei>(m.geometry->indices.size());
      glBindVertexArray(0);
      if (m.texture) {
        glGenTextures(1, &it.tex);
        glBindTexture(GL_TEXTURE_2D, it.tex);
        const int levels = 1 + static_cast<int>(std::floor(std::log2(std::max(m.texture->width, m.texture->height))));
        glTexStorage2D(GL_TEXTURE_2D, levels, GL_RGBA8, m.texture->width, m.texture->height);
        glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
        glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, m.texture->width, m.texture->height, GL_RGBA, GL_UNSIGNED_BYTE,
                        m.texture->rgba.data());
        glGenerateMipmap(GL_TEXTURE_2D);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
      }
      // Uniforms that do not change per frame, set once.
      const GLuint p = it.prog;
      glUseProgram(p);
      glUniformMatrix4fv(glGetUniformLocation(p, "u_model"), 1, GL_FALSE, m.model.m.data());
      glUniformMatrix4fv(glGetUniformLocation(p, "u_light_view_projection"), 1, GL_FALSE, light_vp_.m.data());
      glUniform3f(glGetUniformLocation(p, "u_base_colour"), it.look.base_colour.x, it.look.base_colour.y, it.look.base_colour.z);
      glUniform1f(glGetUniformLocation(p, "u_opacity"), it.look.opacity);
      glUniform1f(glGetUniformLocation(p, "u_specular"), it.look.specular);
      glUniform1f(glGetUniformLocation(p, "u_shininess"), it.look.shininess);
      const vr::Appearance det = vr::default_appearance(vr::MaterialKind::Retina, true);
      glUniform3f(glGetUniformLocation(p, "u_detached_colour"), det.base_colour.x, det.base_colour.y, det.base_colour.z);
      glUniform1f(glGetUniformLocation(p, "u_detached_opacity"), det.opacity);
      glUniform1i(glGetUniformLocation(p, "u_detached"), 0);
      glUniform3f(glGetUniformLocation(p, "u_light_position"), lp.tip_mm.x, lp.tip_mm.y, lp.tip_mm.z);
      glUniform3f(glGetUniformLocation(p, "u_light_direction"), dir.x, dir.y, dir.z);
      const float cone = lp.cone_half_angle_deg * 3.14159265f / 180.0f;
      glUniform1f(glGetUniformLocation(p, "u_cos_outer"), std::cos(cone));
      glUniform1f(glGetUniformLocation(p, "u_cos_inner"), std::cos(0.7f * cone));
      glUniform1f(glGetUniformLocation(p, "u_light_intensity"), lp.intensity);
      glUniform1f(glGetUniformLocation(p, "u_light_range"), lp.range_mm);
      glUniform1f(glGetUniformLocation(p, "u_ambient"), s.ambient);
      glUniform1f(glGetUniformLocation(p, "u_globe_radius"), s.globe_radius_mm);
      glUniform1f(glGetUniformLocation(p, "u_haze_density"), s.haze_density_per_mm);
      glUniform1i(glGetUniformLocation(p, "u_gas_on"), 0);
      glUniform1i(glGetUniformLocation(p, "u_texture"), 0);
      glUniform1i(glGetUniformLocation(p, "u_burns"), 1);
      glUniform1i(glGetUniformLocation(p, "u_shadow_map"), 2);
      it.vp_loc = glGetUniformLocation(p, "u_view_projection");
      it.cam_loc = glGetUniformLocation(p, "u_camera");
      const bool blended = m.material == vr::MaterialKind::Retina || it.look.opacity < 1.0f;
      (blended ? translucent_ : opaque_).push_back(it);
      if (it.look.casts_shadow && !(m.casts_shadow && !*m.casts_shadow)) casters_.push_back(it);
      if (m.id == vt::kRetina) retina_ = it;
    }
    glGenTextures(1, &shadow_tex_);
    glBindTexture(GL_TEXTURE_2D, shadow_tex_);
    glTexStorage2D(GL_TEXTURE_2D, 1, GL_DEPTH_COMPONENT24, 1024, 1024);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
    glGenFramebuffers(1, &shadow_fbo_);
    glBindFramebuffer(GL_FRAMEBUFFER, shadow_fbo_);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, shadow_tex_, 0);
    glDrawBuffer(GL_NONE);
    glReadBuffer(GL_NONE);
    glGenFramebuffers(1, &fbo_);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glGenRenderbuffers(2, rb_);
    glBindRenderbuffer(GL_RENDERBUFFER, rb_[0]);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, 2 * kEyeW, kEyeH);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb_[0]);
    glBindRenderbuffer(GL_RENDERBUFFER, rb_[1]);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, 2 * kEyeW, kEyeH);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb_[1]);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    pixels_.resize(static_cast<std::size_t>(2 * kEyeW) * kEyeH * 4);
  }
  ~BareGlSameShading() {
    for (auto* list : {&opaque_, &translucent_}) {
      for (Item& it : *list) {
        glDeleteProgram(it.prog);
        glDeleteVertexArrays(1, &it.vao);
        glDeleteBuffers(1, &it.vbo);
        glDeleteBuffers(1, &it.ibo);
        if (it.tex) glDeleteTextures(1, &it.tex);
      }
    }
    glDeleteProgram(depth_prog_);
    glDeleteTextures(1, &shadow_tex_);
    glDeleteFramebuffers(1, &shadow_fbo_);
    glDeleteFramebuffers(1, &fbo_);
    glDeleteRenderbuffers(2, rb_);
  }
  void frame(const vr::FrameScene& s) {
    // Deforming retina: re-upload its vertices.
    for (const auto& m : s.meshes) {
      if (m.id != vt::kRetina) continue;
      glBindBuffer(GL_ARRAY_BUFFER, retina_.vbo);
      glBufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(m.geometry->vertices.size() * sizeof(vr::Vertex)),
                      m.geometry->vertices.data());
    }
    glBindFramebuffer(GL_FRAMEBUFFER, shadow_fbo_);
    glViewport(0, 0, 1024, 1024);
    glDepthMask(GL_TRUE);
    glClear(GL_DEPTH_BUFFER_BIT);
    glEnable(GL_DEPTH_TEST);
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(2.0f, 4.0f);
    glUseProgram(depth_prog_);
    glUniformMatrix4fv(glGetUniformLocation(depth_prog_, "u_light_view_projection"), 1, GL_FALSE, light_vp_.m.data());
    for (const Item& it : casters_) {
      glUniformMatrix4fv(glGetUniformLocation(depth_prog_, "u_model"), 1, GL_FALSE, it.mesh->model.m.data());
      glBindVertexArray(it.vao);
      glDrawElements(GL_TRIANGLES, it.count, GL_UNSIGNED_INT, nullptr);
    }
    glDisable(GL_POLYGON_OFFSET_FILL);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glViewport(0, 0, 2 * kEyeW, kEyeH);
    glClearColor(0, 0, 0, 1);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glActiveTexture(GL_TEXTURE2);
    glBindTexture(GL_TEXTURE_2D, shadow_tex_);
    vr::Mat4 flip;
    flip.at(1, 1) = -1.0f;
    for (int e = 0; e < 2; ++e) {
      glViewport(e * kEyeW, 0, kEyeW, kEyeH);
      const vr::Mat4 vp = flip * views_.eye[e].view_projection;
      const vr::Vec3 c = views_.eye[e].position_mm;
      auto draw = [&](const Item& it) {
        glUseProgram(it.prog);
        glUniformMatrix4fv(it.vp_loc, 1, GL_FALSE, vp.m.data());
        glUniform3f(it.cam_loc, c.x, c.y, c.z);
        if (it.tex) {
          glActiveTexture(GL_TEXTURE0);
          glBindTexture(GL_TEXTURE_2D, it.tex);
        }
        glBindVertexArray(it.vao);
        glDrawElements(GL_TRIANGLES, it.count, GL_UNSIGNED_INT, nullptr);
      };
      glDisable(GL_BLEND);
      glDepthMask(GL_TRUE);
      for (const Item& it : opaque_) draw(it);
      glEnable(GL_BLEND);
      glBlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
      glDepthMask(GL_FALSE);
      for (const Item& it : translucent_) draw(it);
      glDepthMask(GL_TRUE);
      glDisable(GL_BLEND);
    }
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, 2 * kEyeW, kEyeH, GL_RGBA, GL_UNSIGNED_BYTE, pixels_.data());
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
  }

 private:
  struct Item {
    const vr::Mesh* mesh = nullptr;
    vr::Appearance look{};
    GLuint prog = 0, vao = 0, vbo = 0, ibo = 0, tex = 0;
    GLint vp_loc = -1, cam_loc = -1;
    GLsizei count = 0;
  };
  static GLuint link(const char* vs, const char* fs) {
    GLuint p = glCreateProgram();
    GLuint v = compile(GL_VERTEX_SHADER, vs), f = compile(GL_FRAGMENT_SHADER, fs);
    glAttachShader(p, v);
    glAttachShader(p, f);
    glLinkProgram(p);
    glDeleteShader(v);
    glDeleteShader(f);
    return p;
  }
  vr::StereoViews views_;
  vr::Mat4 light_vp_;
  vr::Vec3 light_dir_;
  GLuint depth_prog_ = 0, shadow_tex_ = 0, shadow_fbo_ = 0, fbo_ = 0, rb_[2] = {0, 0};
  std::vector<Item> opaque_, translucent_, casters_;
  Item retina_;
  std::vector<std::uint8_t> pixels_;
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

void BM_StereoFrame(benchmark::State& state, int triangles) {
  context();
  vr::StereoRenderer renderer({kEyeW, kEyeH, 1024, 1024});
  vr::FrameScene scene = scene_for(triangles);
  vr::StereoFrame frame;
  renderer.render(scene, frame);  // warm-up: static uploads, shader compilation
  for (auto _ : state) {
    deform(scene);
    renderer.render(scene, frame);
    benchmark::DoNotOptimize(frame.rgba.data());
  }
  state.counters["tris_per_eye"] = static_cast<double>(count_triangles(scene));
  state.counters["fps"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

void BM_BareGL(benchmark::State& state, int triangles) {
  context();
  const vr::FrameScene scene = scene_for(triangles);
  BarePlainGl bare(scene);
  bare.frame();
  for (auto _ : state) bare.frame();
  state.counters["tris_per_eye"] = static_cast<double>(count_triangles(scene));
  state.counters["fps"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

void BM_RendererOverhead(benchmark::State& state, int triangles) {
  context();
  vr::StereoRenderer renderer({kEyeW, kEyeH, 1024, 1024});
  vr::FrameScene scene = scene_for(triangles);
  BareGlSameShading same(scene);
  BarePlainGl plain(scene);
  vr::StereoFrame frame;
  renderer.render(scene, frame);
  same.frame(scene);
  plain.frame();
  std::vector<double> ours, same_t, plain_t;
  for (auto _ : state) {
    deform(scene);
    const auto t0 = Clock::now();
    renderer.render(scene, frame);
    const auto t1 = Clock::now();
    same.frame(scene);
    const auto t2 = Clock::now();
    plain.frame();
    const auto t3 = Clock::now();
    ours.push_back(std::chrono::duration<double>(t1 - t0).count());
    same_t.push_back(std::chrono::duration<double>(t2 - t1).count());
    plain_t.push_back(std::chrono::duration<double>(t3 - t2).count());
    state.SetIterationTime(ours.back());
  }
  const double m_ours = median(ours), m_same = median(same_t), m_plain = median(plain_t);
  state.counters["renderer_ms_p50"] = m_ours * 1e3;
  state.counters["same_shading_gl_ms_p50"] = m_same * 1e3;
  state.counters["plain_gl_ms_p50"] = m_plain * 1e3;
  state.counters["overhead_pct"] = 100.0 * (m_ours / m_same - 1.0);
  state.counters["plain_ratio"] = m_ours / m_plain;
  state.counters["tris_per_eye"] = static_cast<double>(count_triangles(scene));
}

// Which GL the figures are from (llvmpipe here, a GPU's driver on a rig) goes into the output's context.
void name_the_gl() {
  try {
    benchmark::AddCustomContext("egl", context().description());
  } catch (const std::exception& e) {
    benchmark::AddCustomContext("egl", std::string("unavailable: ") + e.what());
  }
}

const bool registered = [] {
  name_the_gl();
  for (int tris : {2000, 20000, 100000}) {
    const std::string size = "/1280x1024/" + std::to_string(tris) + "tris";
    benchmark::RegisterBenchmark(("BM_StereoFrame" + size).c_str(), BM_StereoFrame, tris)
        ->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);
    benchmark::RegisterBenchmark(("BM_BareGL" + size).c_str(), BM_BareGL, tris)
        ->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);
    benchmark::RegisterBenchmark(("BM_RendererOverhead" + size).c_str(), BM_RendererOverhead, tris)
        ->Unit(benchmark::kMillisecond)->UseManualTime()->Iterations(tris >= 100000 ? 20 : 40);
  }
  return true;
}();

}  // namespace
