#include "rig/session/frame_source.hpp"

#include <cmath>
#include <numbers>

#include "core/geometry/revolved_mesh.hpp"

namespace vitreo::rig {

namespace {

render::Vec3 to_render(const core::Vec3& v) {
  return {static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z())};
}

// Texture coordinates of a point on the globe: azimuth around the optical axis and polar angle from
// the posterior pole, the thesis' radial mapping of the fundus (ch. 2.2).
render::Vec2 fundus_uv(float x, float y, float z) {
  const double r = std::sqrt(double{x} * x + double{y} * y + double{z} * z);
  const double polar = r > 0.0 ? std::acos(std::clamp(-z / r, -1.0, 1.0)) : 0.0;
  const double az = std::atan2(double{y}, double{x});
  return {static_cast<float>(0.5 + 0.5 * (polar / std::numbers::pi) * std::cos(az)),
          static_cast<float>(0.5 + 0.5 * (polar / std::numbers::pi) * std::sin(az))};
}

// A thin cylinder for an instrument shaft from `base` to `tip` (radius in mm).
render::MeshGeometryPtr shaft_mesh(const core::Vec3& base, const core::Vec3& tip, double radius) {
  auto g = std::make_shared<render::MeshGeometry>();
  const core::Vec3 axis = (tip - base).normalized();
  const core::Vec3 side = axis.unitOrthogonal();
  const core::Vec3 up = axis.cross(side);
  constexpr int kSides = 12;
  for (int i = 0; i <= kSides; ++i) {
    const double a = 2.0 * std::numbers::pi * i / kSides;
    const core::Vec3 n = std::cos(a) * side + std::sin(a) * up;
    for (const core::Vec3& end : {base, tip}) {
      g->vertices.push_back({to_render(end + radius * n), to_render(n), {static_cast<float>(i) / kSides, 0.0f}, 0.0f});
    }
  }
  for (std::uint32_t i = 0; i < kSides; ++i) {
    const std::uint32_t a = 2 * i, b = a + 1, c = a + 2, d = a + 3;
    g->indices.insert(g->indices.end(), {a, c, b, b, c, d});
  }
  return g;
}

}  // namespace

void reserve_view_snapshots(const SimulationModel& model, runtime::TripleBuffer<ViewSnapshot>& buffer) {
  // Size all three slots: write to each in turn.
  for (int slot = 0; slot < 3; ++slot) {
    ViewSnapshot& s = buffer.write_slot();
    const auto& world = model.world();
    s.surfaces.resize(world.surface_count());
    for (std::uint32_t i = 0; i < world.surface_count(); ++i) {
      const core::Surface& surf = world.surface(i);
      s.surfaces[i].xyz.reserve(3 * static_cast<std::size_t>(surf.vertex_capacity()));
      s.surfaces[i].rest_xyz.reserve(3 * static_cast<std::size_t>(surf.vertex_capacity()));
      s.surfaces[i].indices.reserve(3 * static_cast<std::size_t>(surf.triangle_slots()) * 2 + 64);
      s.surfaces[i].is_retina = i == model.scene().retina;
    }
    buffer.publish();
  }
}

void capture_view(const SimulationModel& model, std::uint64_t step, double t_s, ViewSnapshot& out) {
  out.step = step;
  out.t_s = t_s;
  const auto& world = model.world();
  for (std::uint32_t i = 0; i < world.surface_count() && i < out.surfaces.size(); ++i) {
    const core::Surface& s = world.surface(i);
    SurfaceSnapshot& snap = out.surfaces[i];
    const std::uint32_t n = s.vertex_slots();
    snap.xyz.resize(3 * static_cast<std::size_t>(n));
    for (std::uint32_t v = 0; v < n; ++v) {
      const core::Vec3& p = s.position(v);
      snap.xyz[3 * v] = static_cast<float>(p.x());
      snap.xyz[3 * v + 1] = static_cast<float>(p.y());
      snap.xyz[3 * v + 2] = static_cast<float>(p.z());
    }
    if (snap.topology_version != s.topology_version()) {
      snap.indices.clear();
      for (std::uint32_t t = 0; t < s.triangle_slots(); ++t) {
        if (!s.triangle_alive(t)) continue;
        for (auto v : s.triangle_vertices(t)) snap.indices.push_back(v);
      }
      snap.rest_xyz.resize(3 * static_cast<std::size_t>(n));
      for (std::uint32_t v = 0; v < n; ++v) {
        const core::Vec3& p = s.rest_position(v);
        for (int k = 0; k < 3; ++k) snap.rest_xyz[3 * v + static_cast<std::uint32_t>(k)] = static_cast<float>(p[k]);
      }
      snap.topology_version = s.topology_version();
    }
  }
  // Instruments as the simulation placed them (eye frame, after the eye's rotation).
  const core::InstrumentSystem& sys = model.instrument_system();
  for (std::uint32_t i = 0; i < 4; ++i) {
    auto& o = out.instruments[i];
    o.present = i < sys.instrument_count() && sys.instrument(i).input.present;
    if (!o.present) continue;
    const core::InstrumentState& st = sys.instrument(i);
    o.inserted = st.inside;
    o.tool_type = static_cast<int>(st.description.kind);
    for (int k = 0; k < 3; ++k) {
      o.tip[k] = static_cast<float>(st.frame.tip[k]);
      o.axis[k] = static_cast<float>(st.frame.u[k]);
    }
  }
  const core::LightExposure& light = sys.light();
  out.light_active = light.active;
  for (int k = 0; k < 3; ++k) {
    out.light_apex[k] = static_cast<float>(light.apex_mm[k]);
    out.light_axis[k] = static_cast<float>(light.axis[k]);
  }
  out.light_half_angle_deg = static_cast<float>(light.half_angle_rad * 180.0 / std::numbers::pi);
  out.zoom = model.controls().zoom;
  out.light_level = model.controls().light_level;
}

FrameBuilder::FrameBuilder(double globe_radius_mm, std::vector<Port> ports)
    : globe_radius_mm_(globe_radius_mm), ports_(std::move(ports)) {
  // The choroid: the globe's inner wall from the posterior pole to just past the ora serrata.
  const core::TriangleMesh m = core::revolve_profile(
      core::sphere_arc_profile(globe_radius_mm + 0.05, 0.0, 115.0 * std::numbers::pi / 180.0, 115), {0.6, 2 * std::numbers::pi});
  auto g = std::make_shared<render::MeshGeometry>();
  for (const auto& p : m.positions) {
    const render::Vec3 q = to_render(p);
    g->vertices.push_back({q, to_render(-p.normalized()), fundus_uv(q.x, q.y, q.z), 0.0f});
  }
  for (const auto& t : m.triangles) g->indices.insert(g->indices.end(), {t[0], t[1], t[2]});
  choroid_ = g;
}

render::FrameScene FrameBuilder::build(const ViewSnapshot& snap) {
  render::FrameScene scene;
  scene.sim_time_s = snap.t_s;
  scene.step_index = snap.step;
  scene.globe_radius_mm = static_cast<float>(globe_radius_mm_);
  ++frame_;

  render::Mesh choroid;
  choroid.id = 1;
  choroid.material = render::MaterialKind::Choroid;
  choroid.geometry = choroid_;
  choroid.tint = {0.85f, 0.35f, 0.22f};  // orange-red pigmented fundus
  scene.meshes.push_back(choroid);

  for (std::size_t i = 0; i < snap.surfaces.size(); ++i) {
    const SurfaceSnapshot& s = snap.surfaces[i];
    auto g = std::make_shared<render::MeshGeometry>();
    const std::size_t n = s.xyz.size() / 3;
    g->vertices.resize(n);
    for (std::size_t v = 0; v < n; ++v) {
      auto& vx = g->vertices[v];
      vx.position_mm = {s.xyz[3 * v], s.xyz[3 * v + 1], s.xyz[3 * v + 2]};
      if (3 * v + 2 < s.rest_xyz.size()) vx.uv = fundus_uv(s.rest_xyz[3 * v], s.rest_xyz[3 * v + 1], s.rest_xyz[3 * v + 2]);
      // Detachment shading: how far the tissue has lifted off the wall (fully greyish at 0.5 mm).
      const double r = std::sqrt(double{vx.position_mm.x} * vx.position_mm.x + double{vx.position_mm.y} * vx.position_mm.y +
                                 double{vx.position_mm.z} * vx.position_mm.z);
      vx.detachment = static_cast<float>(std::clamp((globe_radius_mm_ - r) / 0.5, 0.0, 1.0));
    }
    for (std::size_t t = 0; t + 2 < s.indices.size(); t += 3) {
      const auto a = s.indices[t], b = s.indices[t + 1], c = s.indices[t + 2];
      const render::Vec3 pa = g->vertices[a].position_mm;
      const render::Vec3 e1 = g->vertices[b].position_mm - pa, e2 = g->vertices[c].position_mm - pa;
      const render::Vec3 nrm{e1.y * e2.z - e1.z * e2.y, e1.z * e2.x - e1.x * e2.z, e1.x * e2.y - e1.y * e2.x};
      for (auto v : {a, b, c}) g->vertices[v].normal = g->vertices[v].normal + nrm;
    }
    g->indices = s.indices;
    render::Mesh mesh;
    mesh.id = 10 + static_cast<std::uint32_t>(i);
    mesh.material = s.is_retina ? render::MaterialKind::Retina : render::MaterialKind::Membrane;
    mesh.geometry = g;
    mesh.geometry_version = frame_;
    mesh.topology_version = s.topology_version;
    scene.meshes.push_back(mesh);
  }

  for (int i = 0; i < 4; ++i) {
    const auto& ins = snap.instruments[i];
    if (!ins.present || i >= static_cast<int>(ports_.size())) continue;
    const core::Vec3 tip(ins.tip[0], ins.tip[1], ins.tip[2]);
    const core::Vec3 port = ports_[static_cast<std::size_t>(i)].position_mm;
    const core::Vec3 outward = ports_[static_cast<std::size_t>(i)].outward;
    const core::Vec3 axis = ins.inserted ? core::Vec3(ins.axis[0], ins.axis[1], ins.axis[2]) : core::Vec3(-outward);
    render::Mesh shaft;
    shaft.id = 100 + static_cast<std::uint32_t>(i);
    shaft.material = render::MaterialKind::Instrument;
    // From outside the eye (the handle side) through the port to the tip; 23 gauge = 0.64 mm.
    shaft.geometry = shaft_mesh(port - 14.0 * axis, ins.inserted ? tip : port, 0.32);
    shaft.geometry_version = frame_;
    shaft.topology_version = 1;
    scene.meshes.push_back(shaft);
  }

  // Endoillumination: the light pipe's cone as the simulation placed it.
  if (snap.light_active) {
    render::LightPipe light;
    light.tip_mm = {snap.light_apex[0], snap.light_apex[1], snap.light_apex[2]};
    light.direction = {snap.light_axis[0], snap.light_axis[1], snap.light_axis[2]};
    light.cone_half_angle_deg = snap.light_half_angle_deg;
    light.intensity = static_cast<float>(0.5 + snap.light_level);
    scene.light_pipe = light;
  }
  scene.microscope.target_mm = {0.0f, 0.0f, static_cast<float>(-globe_radius_mm_ * 0.6)};
  scene.microscope.zoom = static_cast<float>(snap.zoom);
  return scene;
}

}  // namespace vitreo::rig
