#include "synthetic_scene.hpp"

#include <algorithm>
#include <cmath>
#include <memory>

namespace vitreo::render::testing {
namespace {

constexpr float kPi = 3.14159265358979f;
constexpr float kThetaMax = 95.0f;  // the shells reach a little anterior of the equator

float rad(float deg) { return deg * kPi / 180.0f; }

struct Lcg {  // deterministic pseudo-random numbers: the same texture on every machine
  std::uint32_t s;
  float next() {
    s = s * 1664525u + 1013904223u;
    return static_cast<float>(s >> 8) / static_cast<float>(1u << 24);
  }
};

// Bullous detachment: inward displacement (mm) of the retina at polar angle theta, azimuth phi.
float bulla_mm(float theta_deg, float phi_deg) {
  const Vec3 c = retina_point(28.0f, 70.0f, 1.0f);
  const Vec3 p = retina_point(theta_deg, phi_deg, 1.0f);
  const float ang = std::acos(std::clamp(dot(c, p), -1.0f, 1.0f)) * 180.0f / kPi;
  const float t = ang / 20.0f;
  return t >= 1.0f ? 0.0f : 3.0f * (0.5f + 0.5f * std::cos(t * kPi));
}

// Spherical cap around −z with a radial uv mapping (the thesis' "radial texture map").
std::shared_ptr<MeshGeometry> shell(float radius, int target_tris, bool detach) {
  const int rings = std::max(4, static_cast<int>(std::sqrt(static_cast<float>(target_tris) / 4.0f)));
  const int segs = 2 * rings;
  auto g = std::make_shared<MeshGeometry>();
  g->vertices.reserve(static_cast<std::size_t>(rings * (segs + 1) + 1));
  auto add = [&](float theta_deg, float phi_deg) {
    Vec3 p = retina_point(theta_deg, phi_deg, radius);
    const Vec3 n = -normalize(p);
    const float lift = detach ? bulla_mm(theta_deg, phi_deg) : 0.0f;
    p = p * (1.0f - lift / radius);
    const float r = 0.5f * theta_deg / kThetaMax;
    g->vertices.push_back({p, n, {0.5f + r * std::cos(rad(phi_deg)), 0.5f + r * std::sin(rad(phi_deg))},
                           std::clamp(lift / 0.5f, 0.0f, 1.0f)});
  };
  add(0, 0);  // posterior pole
  for (int i = 1; i <= rings; ++i)
    for (int j = 0; j <= segs; ++j) add(kThetaMax * i / rings, 360.0f * j / segs);
  auto idx = [&](int ring, int seg) { return static_cast<std::uint32_t>(1 + (ring - 1) * (segs + 1) + seg); };
  for (int j = 0; j < segs; ++j) {
    g->indices.insert(g->indices.end(), {0u, idx(1, j), idx(1, j + 1)});
  }
  for (int i = 1; i < rings; ++i) {
    for (int j = 0; j < segs; ++j) {
      g->indices.insert(g->indices.end(), {idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)});
      g->indices.insert(g->indices.end(), {idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)});
    }
  }
  return g;
}

// Closed cylinder along local +z from 0 to length (a shaft), radius r.
std::shared_ptr<MeshGeometry> cylinder(float r, float length, int segs) {
  auto g = std::make_shared<MeshGeometry>();
  for (int j = 0; j <= segs; ++j) {
    const float a = 2 * kPi * j / segs;
    const Vec3 n{std::cos(a), std::sin(a), 0};
    g->vertices.push_back({{r * n.x, r * n.y, 0}, n, {float(j) / segs, 0}});
    g->vertices.push_back({{r * n.x, r * n.y, length}, n, {float(j) / segs, 1}});
  }
  for (int j = 0; j < segs; ++j) {
    const auto b = static_cast<std::uint32_t>(2 * j);
    g->indices.insert(g->indices.end(), {b, b + 2, b + 1, b + 1, b + 2, b + 3});
  }
  // Tip cap (at z = 0).
  const auto centre = static_cast<std::uint32_t>(g->vertices.size());
  g->vertices.push_back({{0, 0, 0}, {0, 0, -1}, {0.5f, 0.5f}});
  for (int j = 0; j <= segs; ++j) {
    const float a = 2 * kPi * j / segs;
    g->vertices.push_back({{r * std::cos(a), r * std::sin(a), 0}, {0, 0, -1}, {0.5f, 0.5f}});
  }
  for (int j = 0; j < segs; ++j)
    g->indices.insert(g->indices.end(), {centre, centre + 1 + static_cast<std::uint32_t>(j), centre + 2 + static_cast<std::uint32_t>(j)});
  return g;
}

void stamp(Image& img, float cx, float cy, float radius, Vec3 colour, float alpha) {
  const int x0 = std::max(0, static_cast<int>(cx - radius - 1)), x1 = std::min(img.width - 1, static_cast<int>(cx + radius + 1));
  const int y0 = std::max(0, static_cast<int>(cy - radius - 1)), y1 = std::min(img.height - 1, static_cast<int>(cy + radius + 1));
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      const float d = std::hypot(x + 0.5f - cx, y + 0.5f - cy);
      const float cov = std::clamp(radius + 0.5f - d, 0.0f, 1.0f) * alpha;
      std::uint8_t* p = &img.rgba[(static_cast<std::size_t>(y) * img.width + x) * 4];
      const float a = p[3] / 255.0f;
      if (cov <= a) continue;
      p[0] = static_cast<std::uint8_t>(colour.x * 255);
      p[1] = static_cast<std::uint8_t>(colour.y * 255);
      p[2] = static_cast<std::uint8_t>(colour.z * 255);
      p[3] = static_cast<std::uint8_t>(cov * 255);
    }
  }
}

// Vessel map: arcades leaving the optic disc, branching as they go; alpha = vessel coverage.
ImagePtr vessel_texture() {
  auto img = std::make_shared<Image>();
  img->width = img->height = 256;
  img->rgba.assign(256u * 256u * 4u, 0);
  Lcg rng{12345u};
  const float disc_theta = 16.0f, disc_phi = 180.0f;  // nasal of the posterior pole
  const float dr = 0.5f * disc_theta / kThetaMax * 256;
  const float dx = 128 + dr * std::cos(rad(disc_phi)), dy = 128 + dr * std::sin(rad(disc_phi));
  struct Branch { float x, y, angle, width; int steps; };
  std::vector<Branch> todo;
  for (float a : {-35.0f, 35.0f, 150.0f, -150.0f, 70.0f, -70.0f}) todo.push_back({dx, dy, rad(a), 3.2f, 60});
  while (!todo.empty()) {
    Branch b = todo.back();
    todo.pop_back();
    for (int s = 0; s < b.steps && b.width > 0.6f; ++s) {
      stamp(*img, b.x, b.y, b.width, {0.55f, 0.07f, 0.05f}, 1.0f);
      b.angle += (rng.next() - 0.5f) * 0.35f;
      b.x += 2.0f * std::cos(b.angle);
      b.y += 2.0f * std::sin(b.angle);
      if (rng.next() < 0.05f) {
        todo.push_back({b.x, b.y, b.angle + (rng.next() < 0.5f ? -0.7f : 0.7f), b.width * 0.7f, b.steps - s});
        b.width *= 0.85f;
      }
      b.width *= 0.992f;
    }
  }
  stamp(*img, dx, dy, 9.0f, {0.95f, 0.88f, 0.62f}, 0.95f);  // optic disc
  return img;
}

// Choroid colour: orange-red with a mottled pattern and a darker macula at the pole.
ImagePtr choroid_texture() {
  auto img = std::make_shared<Image>();
  img->width = img->height = 256;
  img->rgba.resize(256u * 256u * 4u);
  for (int y = 0; y < 256; ++y) {
    for (int x = 0; x < 256; ++x) {
      const float fx = x / 256.0f, fy = y / 256.0f;
      const float mottle = 0.5f + 0.25f * std::sin(fx * 61.0f) * std::sin(fy * 53.0f) + 0.25f * std::sin((fx + fy) * 37.0f);
      const float macula = std::exp(-((fx - 0.5f) * (fx - 0.5f) + (fy - 0.5f) * (fy - 0.5f)) / 0.004f);
      const float k = (0.85f + 0.15f * mottle) * (1.0f - 0.35f * macula);
      std::uint8_t* p = &img->rgba[(static_cast<std::size_t>(y) * 256 + x) * 4];
      p[0] = static_cast<std::uint8_t>(255 * k);
      p[1] = static_cast<std::uint8_t>(255 * k * 0.85f);
      p[2] = static_cast<std::uint8_t>(255 * k * 0.8f);
      p[3] = 255;
    }
  }
  return img;
}

}  // namespace

Vec3 retina_point(float theta_deg, float phi_deg, float radius) {
  const float t = rad(theta_deg), p = rad(phi_deg);
  return {radius * std::sin(t) * std::cos(p), radius * std::sin(t) * std::sin(p), -radius * std::cos(t)};
}

Mat4 frame_along(Vec3 origin, Vec3 axis) {
  const Vec3 z = normalize(axis);
  const Vec3 helper = std::fabs(z.z) < 0.9f ? Vec3{0, 0, 1} : Vec3{1, 0, 0};
  const Vec3 x = normalize(cross(helper, z));
  const Vec3 y = cross(z, x);
  Mat4 m;
  m.at(0, 0) = x.x; m.at(1, 0) = x.y; m.at(2, 0) = x.z;
  m.at(0, 1) = y.x; m.at(1, 1) = y.y; m.at(2, 1) = y.z;
  m.at(0, 2) = z.x; m.at(1, 2) = z.y; m.at(2, 2) = z.z;
  m.at(0, 3) = origin.x; m.at(1, 3) = origin.y; m.at(2, 3) = origin.z;
  return m;
}

FrameScene make_scene(const SyntheticOptions& o) {
  static const ImagePtr vessels = vessel_texture();
  static const ImagePtr choroid_tex = choroid_texture();
  FrameScene s;
  s.sim_time_s = 1.25;
  s.step_index = 1250;
  Mesh choroid;
  choroid.id = kChoroid;
  choroid.material = MaterialKind::Choroid;
  choroid.geometry = shell(kChoroidRadius, o.retina_triangles, false);
  choroid.texture = choroid_tex;
  s.meshes.push_back(choroid);
  Mesh retina;
  retina.id = kRetina;
  retina.material = MaterialKind::Retina;
  retina.geometry = shell(kRetinaRadius, o.retina_triangles, o.detached);
  retina.geometry_version = 1;
  retina.texture = vessels;
  s.meshes.push_back(retina);

  // Ports on the pars plana, ~3.5 mm behind the limbus: anterior of the equator.
  const Vec3 port_temporal = retina_point(125.0f, 10.0f, 12.0f);
  const Vec3 port_nasal = retina_point(125.0f, 190.0f, 12.0f);
  if (o.instrument) {
    Mesh tool;
    tool.id = kInstrument;
    tool.material = MaterialKind::Instrument;
    const Vec3 axis = port_temporal + Vec3{0, 0, 4} - o.instrument_tip_mm;  // from tip back out of the port
    tool.geometry = cylinder(0.45f, length(axis) + 2.0f, 16);
    tool.model = frame_along(o.instrument_tip_mm, axis);
    s.meshes.push_back(tool);
  }
  if (o.light_pipe) {
    const Vec3 tip{-4.5f, 1.0f, -1.0f};
    const Vec3 aim{0.5f, -0.5f, -11.0f};
    Mesh pipe;
    pipe.id = kLightPipe;
    pipe.material = MaterialKind::Instrument;
    const Vec3 axis = port_nasal + Vec3{0, 0, 4} - tip;
    pipe.geometry = cylinder(0.35f, length(axis) + 2.0f, 16);
    pipe.model = frame_along(tip, axis);
    pipe.casts_shadow = false;  // it is the light source
    s.meshes.push_back(pipe);
    s.light_pipe = LightPipe{tip, aim - tip, 42.0f, 1.0f, 18.0f};
  }
  if (o.gas) s.fluid_gas = FluidGas{{0, 0, 1}, o.gas_level_mm};
  s.microscope.wide_angle = o.wide_angle;
  return s;
}

Vec2 project_to_pixel(const FrameScene& scene, int eye, Vec3 p, int width, int height) {
  const StereoViews v = stereo_views(scene.microscope, scene.globe_radius_mm, width, height);
  const Vec4 c = v.eye[eye].view_projection * Vec4{p.x, p.y, p.z, 1.0f};
  const float nx = c.x / c.w, ny = c.y / c.w;
  return {(nx + 1.0f) * 0.5f * width, (1.0f - ny) * 0.5f * height};
}

Vec3 ray_sphere_exit(Vec3 from, Vec3 through, float radius) {
  const Vec3 d = normalize(through - from);
  const float b = dot(from, d);
  const float c = dot(from, from) - radius * radius;
  const float t = -b + std::sqrt(std::max(b * b - c, 0.0f));
  return from + d * t;
}

}  // namespace vitreo::render::testing
