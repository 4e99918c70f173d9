#include "rig/session/frame_source.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace vitreo::rig {

namespace {

render::Vec3 to_render(const core::Vec3& v) {
  return {static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z())};
}

// A thin cylinder from `base` to `tip` (radius in mm): instrument shafts and port cannulas.
render::MeshGeometryPtr cylinder_mesh(const core::Vec3& base, const core::Vec3& tip, double radius) {
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

render::ImagePtr to_image(const core::RgbaImage& src) {
  if (src.width <= 0 || src.height <= 0) return nullptr;
  auto img = std::make_shared<render::Image>();
  img->width = src.width;
  img->height = src.height;
  img->rgba = src.rgba;  // both: row 0 is v = 0, straight alpha
  return img;
}

// How far a point has lifted off the wall → 0 (lying on it, within its own thickness) … 1 (0.6 mm
// or more off it: greyish, translucent).
float detachment_of(const core::GlobeWall& wall, const core::Vec3& p, double thickness_mm) {
  return static_cast<float>(std::clamp((wall.clearance(p) - thickness_mm) / 0.5, 0.0, 1.0));
}

// Mesh ids: static meshes 1..99, tissue 100 + surface, instruments 200 + i, shifted per loaded case
// so the renderer never reuses a previous case's cached buffers or burn textures.
std::uint32_t mesh_id(std::uint64_t serial, std::uint32_t local) {
  return static_cast<std::uint32_t>((serial % 1000) * 1000) + local;
}

}  // namespace

std::unique_ptr<CaseVisuals> build_case_visuals(const PreparedCase& c) {
  const core::Scene& s = *c.scene;
  auto v = std::make_unique<CaseVisuals>();
  v->index = c.index;
  v->name = s.description.name;
  v->title = s.description.title;
  v->eye = s.eye;
  v->focus_mm = c.focus_mm;
  v->globe_radius_mm = static_cast<float>(0.5 * (s.eye.wall.radius_toward(core::Vec3::UnitX()) + s.eye.wall.radius_toward(-core::Vec3::UnitZ())));
  v->camera_z_mm = static_cast<float>(s.eye.lens_center_z_mm - 0.5 * s.description.anatomy.lens_thickness_mm - 0.5);
  const render::ImagePtr choroid = to_image(s.textures.choroid);
  v->retina_texture = to_image(s.textures.retina);
  std::uint32_t id = 1;
  for (const core::RenderMesh& rm : s.eye.static_meshes) {
    auto g = std::make_shared<render::MeshGeometry>();
    g->vertices.reserve(rm.mesh.positions.size());
    for (std::size_t i = 0; i < rm.mesh.positions.size(); ++i) {
      render::Vertex vx;
      vx.position_mm = to_render(rm.mesh.positions[i]);
      vx.normal = to_render(rm.mesh.positions[i].normalized());
      if (i < rm.uv.size()) vx.uv = {static_cast<float>(rm.uv[i].x()), static_cast<float>(rm.uv[i].y())};
      g->vertices.push_back(vx);
    }
    for (const auto& t : rm.mesh.triangles) g->indices.insert(g->indices.end(), {t[0], t[1], t[2]});
    // Smooth normals of the revolved and prism meshes from their triangles.
    for (auto& vx : g->vertices) vx.normal = {0, 0, 0};
    for (std::size_t t = 0; t + 2 < g->indices.size(); t += 3) {
      auto& a = g->vertices[g->indices[t]];
      auto& b = g->vertices[g->indices[t + 1]];
      auto& cc = g->vertices[g->indices[t + 2]];
      const render::Vec3 e1 = b.position_mm - a.position_mm, e2 = cc.position_mm - a.position_mm;
      const render::Vec3 n{e1.y * e2.z - e1.z * e2.y, e1.z * e2.x - e1.x * e2.z, e1.x * e2.y - e1.y * e2.x};
      a.normal = a.normal + n;
      b.normal = b.normal + n;
      cc.normal = cc.normal + n;
    }
    if (rm.texture == "choroid") {
      // The retina lies on this surface; draw the choroid 0.15 mm behind it so the depth test
      // never mixes the two (the retina is blended over it).
      for (auto& vx : g->vertices) {
        const float r = std::sqrt(vx.position_mm.x * vx.position_mm.x + vx.position_mm.y * vx.position_mm.y +
                                  vx.position_mm.z * vx.position_mm.z);
        if (r > 0.0f) vx.position_mm = vx.position_mm * ((r + 0.15f) / r);
      }
    }
    render::Mesh m;
    m.id = id++;
    m.geometry = g;
    m.tint = {rm.base_rgba[0], rm.base_rgba[1], rm.base_rgba[2]};
    if (rm.texture == "choroid") {
      m.material = render::MaterialKind::Choroid;
      m.texture = choroid;
      m.tint = {1, 1, 1};
    } else {
      m.material = render::MaterialKind::Static;
      m.opacity = rm.base_rgba[3];
      m.casts_shadow = false;
    }
    v->statics.push_back(std::move(m));
  }
  // The three cannulas standing in the sclerotomies.
  for (const core::SclerotomyPort& p : s.eye.ports) {
    Port pivot;
    pivot.position_mm = 0.5 * (p.outer_mm + p.inner_mm);
    pivot.outward = -p.axis;
    v->ports.push_back(pivot);
    render::Mesh m;
    m.id = id++;
    m.material = render::MaterialKind::Static;
    m.geometry = cylinder_mesh(p.inner_mm, p.outer_mm - 1.5 * p.axis, 0.45);
    m.tint = {0.55f, 0.57f, 0.6f};
    m.casts_shadow = false;
    v->statics.push_back(std::move(m));
  }
  v->surface_material.assign(s.world.surface_count(), render::MaterialKind::Membrane);
  if (s.retina != core::kNone) v->surface_material[s.retina] = render::MaterialKind::Retina;
  if (s.gel != core::kNone) v->surface_material[s.gel] = render::MaterialKind::Gel;
  return v;
}

void prepare_view_snapshots(PreparedCase& c) {
  const core::TissueWorld& world = c.scene->world;
  c.spare_views.assign(3, ViewSnapshot{});
  for (ViewSnapshot& s : c.spare_views) {
    s.case_serial = c.serial;
    s.visuals = c.visuals;
    s.surfaces.resize(world.surface_count());
    for (std::uint32_t i = 0; i < world.surface_count(); ++i) {
      const core::Surface& surf = world.surface(i);
      SurfaceSnapshot& ss = s.surfaces[i];
      ss.vertex_capacity = surf.vertex_capacity();
      ss.index_capacity = 3 * surf.triangle_slots() * 2 + 64;  // cuts add triangles
      ss.xyz.reserve(3 * static_cast<std::size_t>(ss.vertex_capacity));
      ss.rest_xyz.reserve(3 * static_cast<std::size_t>(ss.vertex_capacity));
      ss.indices.reserve(ss.index_capacity);
    }
  }
  c.spare_views_used = 0;
}

bool capture_view(SimulationModel& model, std::uint64_t step, double t_s, ViewSnapshot& out) {
  PreparedCase& c = model.mutable_case();
  if (out.case_serial != c.serial || out.visuals != c.visuals) {
    if (c.spare_views_used >= c.spare_views.size()) return false;
    std::swap(out, c.spare_views[c.spare_views_used++]);  // moves vectors: no allocation
    for (auto& s : out.surfaces) s.topology_version = ~std::uint64_t{0};
  }
  out.step = step;
  out.t_s = t_s;
  const auto& world = model.world();
  for (std::uint32_t i = 0; i < world.surface_count() && i < out.surfaces.size(); ++i) {
    const core::Surface& s = world.surface(i);
    SurfaceSnapshot& snap = out.surfaces[i];
    const std::uint32_t n = std::min(s.vertex_slots(), snap.vertex_capacity);
    snap.xyz.resize(3 * static_cast<std::size_t>(n));
    for (std::uint32_t v = 0; v < n; ++v) {
      const core::Vec3& p = s.position(v);
      snap.xyz[3 * v] = static_cast<float>(p.x());
      snap.xyz[3 * v + 1] = static_cast<float>(p.y());
      snap.xyz[3 * v + 2] = static_cast<float>(p.z());
    }
    if (snap.topology_version != s.topology_version()) {
      snap.indices.clear();
      for (std::uint32_t t = 0; t < s.triangle_slots() && snap.indices.size() + 3 <= snap.index_capacity; ++t) {
        if (!s.triangle_alive(t)) continue;
        const auto tri = s.triangle_vertices(t);
        if (tri[0] >= n || tri[1] >= n || tri[2] >= n) continue;
        for (auto v : tri) snap.indices.push_back(v);
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
  const core::Simulation& sys = model.simulation();
  constexpr std::uint32_t kSlots = sizeof(out.instruments) / sizeof(out.instruments[0]);
  for (std::uint32_t i = 0; i < kSlots; ++i) {
    auto& o = out.instruments[i];
    o.present = i < sys.instrument_count() && sys.instrument(i).input.present;
    if (!o.present) continue;
    const core::InstrumentState& st = sys.instrument(i);
    o.inserted = st.inside;
    o.tool_type = static_cast<int>(st.description.kind);
    o.port = static_cast<int>(st.description.port);
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
  // The operator's zoom overrides the pedal's until the pedal moves it again (a command is recorded).
  out.zoom = model.zoom_override() > 0.0 ? model.zoom_override() : model.controls().zoom;
  out.light_level = model.controls().light_level;
  out.wireframe = model.wireframe();
  out.labels = model.labels();
  out.fluid_level_z_mm = std::isfinite(sys.fluid_level_z_mm()) ? sys.fluid_level_z_mm() : 1e300;
  out.n_burns = 0;
  for (const core::BurnSpot& b : sys.burns()) {
    if (out.n_burns >= ViewSnapshot::kMaxBurns) break;
    BurnSnapshot& o = out.burns[out.n_burns++];
    const core::Vec3 p = sys.burn_position(b);
    for (int k = 0; k < 3; ++k) o.position_mm[k] = static_cast<float>(p[k]);
    o.diameter_mm = static_cast<float>(b.diameter_mm);
    o.surface = b.surface;
    const core::Surface& s = world.surface(b.surface);
    // Surface coordinates while the burnt triangle still exists (a cut replaces it) and its corners are
    // in the snapshot's vertex range; otherwise only the position goes to the renderer.
    o.on_triangle = false;
    if (b.surface < out.surfaces.size() && s.triangle_alive(b.triangle.index) && s.triangle_id(b.triangle.index) == b.triangle) {
      const auto corners = s.triangle_vertices(b.triangle.index);
      const std::size_t n = out.surfaces[b.surface].xyz.size() / 3;
      o.on_triangle = corners[0] < n && corners[1] < n && corners[2] < n;
    }
    if (o.on_triangle) {
      const auto corners = s.triangle_vertices(b.triangle.index);
      for (int k = 0; k < 3; ++k) {
        o.corners[k] = corners[static_cast<std::size_t>(k)];
        o.barycentric[k] = static_cast<float>(b.bary[k]);
      }
    }
  }
  return true;
}

render::FrameScene FrameBuilder::build(const ViewSnapshot& snap) {
  render::FrameScene scene;
  scene.sim_time_s = snap.t_s;
  scene.step_index = snap.step;
  ++frame_;
  const CaseVisuals* cv = snap.visuals;
  if (!cv) return scene;
  serial_ = snap.case_serial;
  scene.globe_radius_mm = cv->globe_radius_mm;
  for (render::Mesh m : cv->statics) {
    m.id = mesh_id(serial_, m.id);
    scene.meshes.push_back(std::move(m));
  }

  for (std::size_t i = 0; i < snap.surfaces.size(); ++i) {
    const SurfaceSnapshot& s = snap.surfaces[i];
    const render::MaterialKind material = i < cv->surface_material.size() ? cv->surface_material[i] : render::MaterialKind::Membrane;
    auto g = std::make_shared<render::MeshGeometry>();
    const std::size_t n = s.xyz.size() / 3;
    g->vertices.resize(n);
    for (std::size_t v = 0; v < n; ++v) {
      auto& vx = g->vertices[v];
      vx.position_mm = {s.xyz[3 * v], s.xyz[3 * v + 1], s.xyz[3 * v + 2]};
      if (3 * v + 2 < s.rest_xyz.size()) {
        // Texture coordinates from where the tissue lies at rest, so the vessels move with it.
        const core::Vec3 rest(s.rest_xyz[3 * v], s.rest_xyz[3 * v + 1], s.rest_xyz[3 * v + 2]);
        const core::Vec2 uv = cv->eye.fundus_uv(cv->eye.fundus_coords(rest));
        vx.uv = {static_cast<float>(uv.x()), static_cast<float>(uv.y())};
      }
      if (material == render::MaterialKind::Retina) {
        vx.detachment = detachment_of(cv->eye.wall, core::Vec3(vx.position_mm.x, vx.position_mm.y, vx.position_mm.z),
                                      cv->eye.parameters.retina_thickness_mm);
      }
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
    mesh.id = mesh_id(serial_, 100 + static_cast<std::uint32_t>(i));
    mesh.material = material;
    mesh.geometry = g;
    mesh.geometry_version = frame_;
    mesh.topology_version = s.topology_version;
    if (material == render::MaterialKind::Retina) mesh.texture = cv->retina_texture;
    for (std::uint32_t b = 0; b < snap.n_burns; ++b) {
      if (snap.burns[b].surface != i) continue;
      render::LaserBurn burn;
      const BurnSnapshot& spot = snap.burns[b];
      if (spot.on_triangle) {
        burn.hit_point = render::LaserBurn::SurfacePoint{{spot.corners[0], spot.corners[1], spot.corners[2]},
                                                         {spot.barycentric[0], spot.barycentric[1], spot.barycentric[2]}};
      } else {
        burn.hit_position_mm = render::Vec3{spot.position_mm[0], spot.position_mm[1], spot.position_mm[2]};
      }
      burn.radius_mm = 0.5f * snap.burns[b].diameter_mm;
      mesh.burns.push_back(burn);
    }
    scene.meshes.push_back(std::move(mesh));
  }

  constexpr std::size_t kSlots = sizeof(snap.instruments) / sizeof(snap.instruments[0]);
  for (std::size_t i = 0; i < kSlots; ++i) {
    const auto& ins = snap.instruments[i];
    if (!ins.present || ins.port < 0 || ins.port >= static_cast<int>(cv->ports.size())) continue;
    const Port& port = cv->ports[static_cast<std::size_t>(ins.port)];
    const core::Vec3 tip(ins.tip[0], ins.tip[1], ins.tip[2]);
    const core::Vec3 axis = ins.inserted ? core::Vec3(ins.axis[0], ins.axis[1], ins.axis[2]) : core::Vec3(-port.outward);
    render::Mesh shaft;
    shaft.id = mesh_id(serial_, 200 + static_cast<std::uint32_t>(i));
    shaft.material = render::MaterialKind::Instrument;
    // From outside the eye (the handle side) through the port to the tip; 23 gauge = 0.64 mm.
    shaft.geometry = cylinder_mesh(port.position_mm - 14.0 * axis, ins.inserted ? tip : port.position_mm, 0.32);
    shaft.geometry_version = frame_;
    shaft.topology_version = 1;
    scene.meshes.push_back(std::move(shaft));
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
  if (snap.fluid_level_z_mm < 1e299) scene.fluid_gas = render::FluidGas{{0, 0, 1}, static_cast<float>(snap.fluid_level_z_mm)};
  // The surgeon's wide-angle viewing system: it brings the fundus into view through the pupil with
  // its own optics; we do not model that refraction but place the virtual camera on the optical
  // axis just behind the lens, looking down the axis. Zoom narrows the field.
  // The field opens up (as wide-angle systems do, to ~130°) until the region of interest is in it.
  const core::Vec3 camera(0.0, 0.0, cv->camera_z_mm);
  const core::Vec3 to_focus = cv->focus_mm - camera;
  const double off_axis_deg = std::atan2(std::hypot(to_focus.x(), to_focus.y()), -to_focus.z()) * 180.0 / std::numbers::pi;
  scene.microscope.target_mm = {0.0f, 0.0f, static_cast<float>(cv->eye.fovea_mm.z())};
  scene.microscope.wide_angle = true;
  scene.microscope.wide_distance_mm = cv->camera_z_mm;
  scene.microscope.wide_field_deg = static_cast<float>(std::clamp(2.0 * (off_axis_deg + 14.0), 90.0, 130.0));
  scene.microscope.zoom = static_cast<float>(snap.zoom);
  scene.wireframe = snap.wireframe;
  return scene;
}

}  // namespace vitreo::rig
