#include "rig/session/instrument_models.hpp"

#include <algorithm>
#include <cmath>
#include <memory>

namespace vitreo::rig {

namespace {

using render::MaterialKind;

constexpr float kPi = 3.14159265f;

// A mesh under construction, in the instrument's frame.
struct Builder {
  std::shared_ptr<render::MeshGeometry> g = std::make_shared<render::MeshGeometry>();

  std::uint32_t vertex(render::Vec3 p, render::Vec3 n, float highlight = 0.0f, render::Vec2 uv = {}) {
    g->vertices.push_back({p, n, uv, 0.0f, highlight});
    return static_cast<std::uint32_t>(g->vertices.size() - 1);
  }
  void tri(std::uint32_t a, std::uint32_t b, std::uint32_t c) { g->indices.insert(g->indices.end(), {a, b, c}); }

  // A tube along +z at (cx, cy) from z0 to z1, radii r0 at z0 and r1 at z1 (a cone when they
  // differ), highlight h0 → h1 along it; capped at z1 when asked (a flat end).
  void tube(float cx, float cy, float z0, float z1, float r0, float r1, int sides, bool cap_end = false, float h0 = 0.0f,
            float h1 = 0.0f) {
    const std::uint32_t first = static_cast<std::uint32_t>(g->vertices.size());
    const float slope = (r0 - r1) / std::max(std::fabs(z1 - z0), 1e-6f);
    for (int i = 0; i <= sides; ++i) {
      const float a = 2.0f * kPi * static_cast<float>(i) / static_cast<float>(sides);
      const float c = std::cos(a), s = std::sin(a);
      const render::Vec3 n = normalize(render::Vec3{c, s, slope});
      vertex({cx + r0 * c, cy + r0 * s, z0}, n, h0, {static_cast<float>(i) / sides, 0.0f});
      vertex({cx + r1 * c, cy + r1 * s, z1}, n, h1, {static_cast<float>(i) / sides, 1.0f});
    }
    for (int i = 0; i < sides; ++i) {
      const std::uint32_t a = first + 2 * static_cast<std::uint32_t>(i), b = a + 1, c = a + 2, d = a + 3;
      tri(a, c, b);
      tri(b, c, d);
    }
    if (cap_end && r1 > 0.0f) disc({cx, cy, z1}, {0, 0, z1 >= z0 ? 1.0f : -1.0f}, r1, sides, h1, h1);
  }
  // A disc (a fan) at `centre` facing `normal`, highlight hc at the centre → hr at the rim.
  void disc(render::Vec3 centre, render::Vec3 normal, float radius, int sides, float hc = 0.0f, float hr = 0.0f) {
    normal = normalize(normal);
    const render::Vec3 helper = std::fabs(normal.z) < 0.9f ? render::Vec3{0, 0, 1} : render::Vec3{1, 0, 0};
    const render::Vec3 a = normalize(cross(normal, helper)), b = cross(normal, a);
    const std::uint32_t c = vertex(centre, normal, hc);
    for (int i = 0; i <= sides; ++i) {
      const float t = 2.0f * kPi * static_cast<float>(i) / static_cast<float>(sides);
      vertex(centre + (a * std::cos(t) + b * std::sin(t)) * radius, normal, hr);
      if (i > 0) tri(c, c + static_cast<std::uint32_t>(i), c + static_cast<std::uint32_t>(i) + 1);
    }
  }
  // A flat plate: the convex outline (across, along) in the plane spanned by `across` and `along`
  // from `origin`, given `thickness` along across × along (both faces and the rim).
  void plate(render::Vec3 origin, render::Vec3 across, render::Vec3 along, const std::vector<render::Vec2>& outline, float thickness) {
    const render::Vec3 n = normalize(cross(across, along));
    const std::size_t k = outline.size();
    for (float side : {-0.5f, 0.5f}) {
      const std::uint32_t first = static_cast<std::uint32_t>(g->vertices.size());
      for (const render::Vec2& o : outline) vertex(origin + across * o.x + along * o.y + n * (side * thickness), n * side);
      for (std::size_t i = 1; i + 1 < k; ++i) tri(first, first + static_cast<std::uint32_t>(i), first + static_cast<std::uint32_t>(i + 1));
    }
    for (std::size_t i = 0; i < k; ++i) {
      const render::Vec2 p = outline[i], q = outline[(i + 1) % k];
      const render::Vec3 pa = origin + across * p.x + along * p.y, qa = origin + across * q.x + along * q.y;
      const render::Vec3 edge_n = normalize(cross(qa - pa, n));
      const std::uint32_t a = vertex(pa - n * (0.5f * thickness), edge_n), b = vertex(pa + n * (0.5f * thickness), edge_n);
      const std::uint32_t c = vertex(qa - n * (0.5f * thickness), edge_n), d = vertex(qa + n * (0.5f * thickness), edge_n);
      tri(a, c, b);
      tri(b, c, d);
    }
  }
};

render::Mesh make_mesh(Builder& b, std::uint32_t id, MaterialKind material, const render::Mat4& model, std::uint64_t version,
                       render::Vec3 tint = {1, 1, 1}, float opacity = -1.0f) {
  render::Mesh m;
  m.id = id;
  m.material = material;
  m.geometry = b.g;
  m.geometry_version = version;
  m.topology_version = version;
  m.model = model;
  m.tint = tint;
  m.opacity = opacity;
  if (material != MaterialKind::Instrument) m.casts_shadow = false;
  return m;
}

constexpr int kSides = 16;
const render::Vec3 kSteel{1.0f, 1.0f, 1.0f};
const render::Vec3 kDarkSteel{0.78f, 0.78f, 0.80f};
const render::Vec3 kAimGreen{0.35f, 1.0f, 0.30f};
const render::Vec3 kWarmWhite{1.0f, 0.96f, 0.86f};

}  // namespace

render::Mat4 instrument_placement(const render::Vec3& tip, const render::Vec3& axis, const render::Vec3& up) {
  const render::Vec3 z = normalize(axis);
  render::Vec3 x = up - z * dot(up, z);
  if (length(x) < 1e-5f) x = std::fabs(z.x) < 0.9f ? render::Vec3{1, 0, 0} - z * z.x : render::Vec3{0, 1, 0} - z * z.y;
  x = normalize(x);
  const render::Vec3 y = cross(z, x);
  render::Mat4 m;
  const render::Vec3 cols[4] = {x, y, z, tip};
  for (int c = 0; c < 4; ++c) {
    m.at(0, c) = cols[c].x;
    m.at(1, c) = cols[c].y;
    m.at(2, c) = cols[c].z;
  }
  return m;
}

void add_instrument_meshes(const InstrumentView& v, std::uint32_t first_id, std::uint64_t version, std::vector<render::Mesh>& out) {
  using K = core::InstrumentKind;
  const render::Mat4 model = instrument_placement(v.tip_mm, v.axis, v.up);
  const float r = v.shaft_radius_mm, L = std::max(v.shaft_length_mm, 1.0f);
  const auto& d = v.dims;
  std::uint32_t id = first_id;
  Builder metal;
  auto shaft_to = [&](float setback) { metal.tube(0, 0, -L, -setback, r, r, kSides, true); };
  switch (v.kind) {
    case K::kForceps:
    case K::kScissors: {
      const float J = static_cast<float>(d.jaw_length_mm);
      shaft_to(J);
      // Jaws from the hinge at the shaft's end, each opened by half the angle the handle leaves
      // (core: jaw_open_deg · (1 − actuation)), exactly where the core's jaw capsules lie.
      const float half = static_cast<float>(d.jaw_open_deg) * kPi / 180.0f * (1.0f - std::clamp(v.actuation, 0.0f, 1.0f));
      const float jr = static_cast<float>(d.jaw_radius_mm);
      const render::Vec3 hinge{0, 0, -J};
      out.push_back(make_mesh(metal, id++, MaterialKind::Instrument, model, version));
      Builder jaws;  // their own mesh: what the handle moves
      for (float side : {1.0f, -1.0f}) {
        const render::Vec3 along{side * std::sin(half), 0.0f, std::cos(half)};
        if (v.kind == K::kForceps) {
          // End-gripping jaws: flat faces toward each other (across y), 2·jaw_radius thick, so the
          // gap between their faces is the core's jaw gap; a grasping platform at the end.
          jaws.plate(hinge, render::Vec3{0, 1, 0}, along, {{-0.13f, 0.0f}, {0.13f, 0.0f}, {0.09f, J}, {-0.09f, J}}, 2.0f * jr);
        } else {
          // Scissors: pointed blades in the opening plane, offset across so they shear past each other.
          const render::Vec3 across{std::cos(half), 0.0f, -side * std::sin(half)};
          jaws.plate(hinge + render::Vec3{0, side * 0.5f * jr, 0}, across * side, along,
                     {{-0.03f, 0.0f}, {0.12f, 0.0f}, {0.0f, J}, {-0.03f, 0.85f * J}}, jr);
        }
      }
      out.push_back(make_mesh(jaws, id++, MaterialKind::Instrument, model, version, v.kind == K::kForceps ? kDarkSteel : kSteel));
      break;
    }
    case K::kVitrector: {
      shaft_to(0.12f);
      metal.tube(0, 0, -0.12f, 0.0f, r, 0.75f * r, kSides, true);  // the rounded, closed end
      out.push_back(make_mesh(metal, id++, MaterialKind::Instrument, model, version));
      // The side port facing +x (v): a dark opening; the inner guillotine sweeps across it and
      // back once per cut, so at 2500–7500 cuts/min the port flickers from frame to frame.
      const float setback = static_cast<float>(d.vitrector_port_setback_mm), half_len = 0.2f, half_w = 0.16f;
      Builder port;
      port.plate({r + 0.004f, 0, -setback}, render::Vec3{0, 1, 0}, render::Vec3{0, 0, 1},
                 {{-half_w, -half_len}, {half_w, -half_len}, {half_w, half_len}, {-half_w, half_len}}, 0.004f);
      out.push_back(make_mesh(port, id++, MaterialKind::Static, model, version, {0.04f, 0.03f, 0.03f}));
      const float cover = v.cutting ? 1.0f - std::fabs(2.0f * v.cut_phase - 1.0f) : 0.0f;  // 0 open … 1 closed
      if (cover > 0.02f) {
        Builder cutter;
        const float top = half_len, bottom = half_len - 2.0f * half_len * cover;
        cutter.plate({r + 0.012f, 0, -setback}, render::Vec3{0, 1, 0}, render::Vec3{0, 0, 1},
                     {{-half_w, bottom}, {half_w, bottom}, {half_w, top}, {-half_w, top}}, 0.004f);
        out.push_back(make_mesh(cutter, id++, MaterialKind::Instrument, model, version, {1.1f, 1.1f, 1.1f}));
      }
      break;
    }
    case K::kBlade: {
      const float B = static_cast<float>(d.blade_length_mm);
      shaft_to(B);
      // A lanceolate (MVR) blade: two cutting edges meeting at the point.
      metal.plate({0, 0, -B}, render::Vec3{1, 0, 0}, render::Vec3{0, 0, 1}, {{-0.2f, 0.0f}, {0.2f, 0.0f}, {0.27f, 0.45f * B}, {0.0f, B}, {-0.27f, 0.45f * B}},
                  0.03f);
      out.push_back(make_mesh(metal, id++, MaterialKind::Instrument, model, version, {1.05f, 1.05f, 1.08f}));
      break;
    }
    case K::kSidewaysBlade: {
      shaft_to(0.0f);
      // Bent 90° at the tip: its edge runs along v for sideways_blade_mm.
      const float S = static_cast<float>(d.sideways_blade_mm);
      metal.plate({0, 0, 0}, render::Vec3{1, 0, 0}, render::Vec3{0, 0, 1}, {{0.0f, -0.3f}, {0.6f * S, -0.12f}, {S, 0.0f}, {0.0f, 0.06f}}, 0.03f);
      out.push_back(make_mesh(metal, id++, MaterialKind::Instrument, model, version, {1.05f, 1.05f, 1.08f}));
      break;
    }
    case K::kPick: {
      const float P = static_cast<float>(d.pick_length_mm);
      shaft_to(P);
      metal.tube(0, 0, -P, 0.0f, 1.6f * static_cast<float>(d.pick_radius_mm), static_cast<float>(d.pick_radius_mm), 8);
      Builder hook;
      hook.tube(0, 0, 0.0f, P, static_cast<float>(d.pick_radius_mm), 0.5f * static_cast<float>(d.pick_radius_mm), 8, true);
      out.push_back(make_mesh(metal, id++, MaterialKind::Instrument, model, version));
      // The hook bent toward v: its own placement, turned 90° about y.
      render::Mat4 bend = instrument_placement(v.tip_mm, v.up, -v.axis);
      out.push_back(make_mesh(hook, id++, MaterialKind::Instrument, bend, version));
      break;
    }
    case K::kDrainageNeedle: {
      // The flute needle's soft silicone tip (blunt, as the thesis' surgeons asked), its lumen dark.
      shaft_to(1.0f);
      out.push_back(make_mesh(metal, id++, MaterialKind::Instrument, model, version));
      Builder soft;
      soft.tube(0, 0, -1.0f, 0.0f, 0.9f * r, 0.85f * r, kSides);
      out.push_back(make_mesh(soft, id++, MaterialKind::Instrument, model, version, {1.2f, 1.32f, 1.42f}, 0.7f));
      Builder lumen;
      lumen.disc({0, 0, 0.002f}, {0, 0, 1}, 0.5f * r, kSides);
      out.push_back(make_mesh(lumen, id++, MaterialKind::Static, model, version, {0.05f, 0.05f, 0.06f}));
      break;
    }
    case K::kEndolaser: {
      shaft_to(0.0f);
      out.push_back(make_mesh(metal, id++, MaterialKind::Instrument, model, version));
      Builder fibre;
      fibre.disc({0, 0, 0.003f}, {0, 0, 1}, 0.45f * r, kSides, 1.0f, 0.3f);
      out.push_back(make_mesh(fibre, id++, MaterialKind::Glow, model, version, kAimGreen, v.firing ? 3.0f : 1.0f));
      if (v.aim_hit) {
        // The aiming beam (faint in clear fluid) and its spot on the tissue, where the core's ray
        // meets it: the laser will burn there. Built in the eye frame.
        Builder beam;
        const render::Vec3 to = v.aim_mm - v.tip_mm;
        const float len = length(to);
        if (len > 1e-3f) {
          beam.tube(0, 0, 0.0f, len, 0.012f, 0.02f, 6, false, 1.0f, 0.6f);
          out.push_back(make_mesh(beam, id++, MaterialKind::Glow, instrument_placement(v.tip_mm, to, v.up), version, kAimGreen,
                                  v.firing ? 0.9f : 0.25f));
        }
        Builder spot;
        const render::Vec3 n = normalize(v.aim_normal);
        spot.disc(v.aim_mm + n * 0.03f, n, 0.75f * v.aim_spot_mm, 20, 1.0f, 0.0f);
        out.push_back(make_mesh(spot, id++, MaterialKind::Glow, render::Mat4::identity(), version,
                                v.firing ? render::Vec3{1.0f, 1.0f, 0.9f} : kAimGreen, v.firing ? 6.0f : 2.5f));
      }
      break;
    }
    case K::kLightPipe: {
      shaft_to(0.0f);
      out.push_back(make_mesh(metal, id++, MaterialKind::Instrument, model, version));
      Builder tip;
      tip.disc({0, 0, 0.003f}, {0, 0, 1}, 0.8f * r, kSides, 1.0f, 0.6f);
      out.push_back(make_mesh(tip, id++, MaterialKind::Glow, model, version, kWarmWhite, 3.0f * v.light_intensity));
      // The cone of light in the vitreous: faint, fading with distance from the fibre.
      Builder cone;
      const float reach = 9.0f, half = std::clamp(v.cone_half_angle_deg, 1.0f, 85.0f) * kPi / 180.0f;
      cone.tube(0, 0, 0.0f, reach, 0.7f * r, 0.7f * r + reach * std::tan(half), 24, false, 1.0f, 0.0f);
      out.push_back(make_mesh(cone, id++, MaterialKind::Glow, model, version, kWarmWhite, 0.04f * v.light_intensity));
      break;
    }
  }
}

void add_chandelier_meshes(render::Vec3 base_mm, render::Vec3 direction, std::uint32_t first_id, std::vector<render::Mesh>& out) {
  const render::Mat4 model = instrument_placement(base_mm, direction, render::Vec3{0, 0, 1});
  Builder fibre;
  fibre.tube(0, 0, -2.0f, 0.0f, 0.2f, 0.2f, 12, true);  // a 27-gauge fibre 2 mm into the cavity
  out.push_back(make_mesh(fibre, first_id, MaterialKind::Instrument, model, 1, {0.9f, 0.9f, 0.95f}));
  Builder tip;
  tip.disc({0, 0, 0.003f}, {0, 0, 1}, 0.16f, 12, 1.0f, 0.6f);
  out.push_back(make_mesh(tip, first_id + 1, MaterialKind::Glow, model, 1, kWarmWhite, 3.0f));
}

}  // namespace vitreo::rig
