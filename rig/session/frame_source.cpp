#include "rig/session/frame_source.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "rig/session/instrument_models.hpp"
#include "core/common/units.hpp"

namespace vitreo::rig {

namespace {

using core::units::kDeg;

render::Vec3 to_render(const core::Vec3& v) {
  return {static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z())};
}

// A thin cylinder from `base` to `tip` (radius in mm): port cannulas and instruments outside the eye.
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

// Triamcinolone crystals in the gel: fine white grains (a texel, ~0.06 mm, and small clumps) on a
// faint white haze, deterministic from the case's texture seed; the gel's uv are the fundus
// coordinates of its shells (1024 texels ≈ 66 mm).
render::ImagePtr triamcinolone_texture(std::uint64_t seed) {
  auto img = std::make_shared<render::Image>();
  const int n = 1024;
  img->width = img->height = n;
  img->rgba.assign(static_cast<std::size_t>(n) * n * 4, 0);
  std::uint64_t s = seed;
  auto next = [&] {  // splitmix64: successive values uncorrelated (no streaks of grains)
    std::uint64_t z = (s += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  };
  for (std::size_t i = 0; i < img->rgba.size(); i += 4) {
    img->rgba[i] = 250, img->rgba[i + 1] = 250, img->rgba[i + 2] = 245, img->rgba[i + 3] = 55;
  }
  for (int k = 0; k < n * n / 12; ++k) {
    const int x = static_cast<int>(next() % n), y = static_cast<int>(next() % n);
    const bool clump = next() % 8 == 0;
    const auto a = static_cast<std::uint8_t>(140 + next() % 110);
    for (int dy = 0; dy <= (clump ? 1 : 0); ++dy) {
      for (int dx = 0; dx <= (clump ? 1 : 0); ++dx) {
        std::uint8_t* p = &img->rgba[(static_cast<std::size_t>((y + dy) % n) * n + static_cast<std::size_t>((x + dx) % n)) * 4];
        p[3] = std::max(p[3], a);
      }
    }
  }
  return img;
}

// How far a point has lifted off the wall → 0 (lying on it, within its own thickness) … 1 (0.6 mm
// or more off it: greyish, translucent).
float detachment_of(const core::GlobeWall& wall, const core::Vec3& p, double thickness_mm) {
  return static_cast<float>(std::clamp((wall.clearance(p) - thickness_mm) / 0.5, 0.0, 1.0));
}

// Mesh ids: static meshes 1..99, tissue 100 + surface, instruments 200 + 10·slot, guides 300 + g,
// the chandelier 390, shifted per loaded case so the renderer never reuses a previous case's
// cached buffers or burn textures.
std::uint32_t mesh_id(std::uint64_t serial, std::uint32_t local) {
  return static_cast<std::uint32_t>((serial % 1000) * 1000) + local;
}

// The wall point under a fundus-plane point (the inverse of EyeModel::fundus_coords on the wall).
core::Vec3 wall_at_fundus(const core::EyeModel& eye, double x, double y) {
  const double s = std::min(std::hypot(x, y), eye.fundus_extent_mm);
  return eye.wall_point(eye.polar_at_arc(s), std::atan2(y, x));
}

std::string upper(std::string s) {
  for (char& c : s) c = static_cast<char>(c == '_' ? ' ' : std::toupper(static_cast<unsigned char>(c)));
  return s;
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
      const render::Vec3 n = cross(b.position_mm - a.position_mm, cc.position_mm - a.position_mm);
      a.normal = a.normal + n;
      b.normal = b.normal + n;
      cc.normal = cc.normal + n;
    }
    if (rm.texture == "choroid") {
      // The retina lies on this surface; draw the choroid 0.15 mm behind it so the depth test
      // never mixes the two (the retina is blended over it).
      for (auto& vx : g->vertices) {
        const float r = length(vx.position_mm);
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
  if (s.description.view.gel_stain == core::GelStain::kTriamcinolone) v->gel_stain = triamcinolone_texture(s.description.texture_seed);

  // Guides, drawn through the points the case's criteria measure when a criterion measures them,
  // lifted a little off the retina so they lie on its surface.
  const auto& samples = c.metrics->progress().guide_samples();
  for (std::size_t g = 0; g < s.guides.size(); ++g) {
    GuideVisual gv;
    gv.name = s.guides[g].name;
    gv.kind = s.guides[g].kind;
    const std::vector<core::Vec3>* pts = &s.guides[g].polyline_mm;
    for (const auto& smp : samples) {
      if (smp.guide == g) {
        pts = &smp.points;
        gv.measured = true;
      }
    }
    for (const core::Vec3& p : *pts) gv.points.push_back(to_render(p - 0.06 * p.normalized()));
    v->guides.push_back(std::move(gv));
  }
  // The structures' names (the labels toggle), anchored on the fundus.
  const double lift = s.eye.parameters.retina_thickness_mm;
  auto label = [&](const core::Vec3& at, const std::string& text) {
    v->labels.push_back({to_render(at - lift * at.normalized()), upper(text), {0.95f, 0.95f, 0.85f}});
  };
  label(s.eye.fovea_mm, "fovea");
  label(s.eye.optic_disc_mm, "optic disc");
  // "horseshoe tear", "erm membrane" — but "tear", not "tear tear".
  auto named = [](const std::string& name, const std::string& kind) {
    return name.find(kind) == std::string::npos ? name + " " + kind : name;
  };
  for (const auto& t : s.description.tears) label(core::wall_point_at(s.eye, t.center), named(t.name, "tear"));
  for (const auto& m : s.description.membranes) label(core::wall_point_at(s.eye, m.center), named(m.name, "membrane"));
  for (const auto& d : s.description.detachments) label(core::wall_point_at(s.eye, d.center), d.name);
  // A boundary of the retina near the ora is where the retina ends, not a cut.
  v->retina_edge_polar_rad = s.eye.ora_polar_rad - 1.5 * kDeg;
  if (s.description.view.chandelier) {
    // A chandelier fibre through the superior pars plana (12 o'clock), aimed at the posterior pole.
    const core::SclerotomyPort& ref = s.eye.ports.front();
    const double rho = std::hypot(ref.inner_mm.x(), ref.inner_mm.y());
    const core::Vec3 base(0.0, rho, ref.inner_mm.z());
    const core::Vec3 dir = (s.eye.fovea_mm - base).normalized();
    v->chandelier = true;
    v->chandelier_tip = to_render(base + 2.0 * dir);
    v->chandelier_direction = to_render(dir);
  }
  return v;
}

void prepare_view_snapshots(PreparedCase& c) {
  const core::TissueWorld& world = c.scene->world;
  c.spare_views.assign(kViewSnapshotsPerCase, ViewSnapshot{});
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
  c.view_measured_at_s = -1e300;
}

namespace {

// The score, criteria, guide progress and event counts for the picture (physics thread). The
// criteria scan the world, so they are measured again only every kProgressEvery_s.
void capture_progress(SimulationModel& model, ViewSnapshot& out) {
  PreparedCase& c = model.mutable_case();
  core::SessionMetrics& metrics = model.metrics();
  const double t = model.world().time_s();
  if (t < c.view_measured_at_s || t - c.view_measured_at_s >= kProgressEvery_s) {
    (void)metrics.score();
    c.view_measured_at_s = t;
  }
  const auto& samples = metrics.progress().guide_samples();
  out.n_guides = 0;
  for (const auto& smp : samples) {
    if (out.n_guides >= ViewSnapshot::kMaxGuides) break;
    GuideProgressSnapshot& g = out.guides[out.n_guides++];
    g.guide = smp.guide;
    g.n = static_cast<std::uint32_t>(std::min(smp.covered.size(), GuideProgressSnapshot::kMaxSamples));
    std::copy_n(smp.covered.begin(), g.n, g.covered);
  }
  OverlaySnapshot& o = out.overlay;
  const core::ScoreCard& card = metrics.last_score();
  o.score_total = card.total;
  o.n_scores = 0;
  for (const auto& e : card.categories) {
    if (o.n_scores >= OverlaySnapshot::kMaxEntries) break;
    o.score_name[o.n_scores] = e.name;
    o.score_value[o.n_scores++] = e.value;
  }
  o.n_criteria = 0;
  for (const auto& cr : metrics.progress().criteria()) {
    if (o.n_criteria >= OverlaySnapshot::kMaxEntries) break;
    const std::uint32_t i = o.n_criteria++;
    o.criterion_kind[i] = core::to_string(cr.kind);
    std::snprintf(o.criterion_target[i], sizeof o.criterion_target[i], "%s", cr.target.c_str());
    o.criterion_progress[i] = cr.progress;
    o.criterion_met[i] = cr.met;
  }
  const core::SessionTotals& totals = metrics.totals();
  o.elapsed_s = totals.elapsed_s;
  const core::MicroscopeGlance& glance = metrics.microscope_glance();
  o.scope_judged = glance.judged;
  o.scope_field_radius = glance.field_radius;
  o.scope_defocus_mm = glance.defocus_mm;
  o.scope_depth_of_field_mm = glance.depth_of_field_mm;
  const double w = totals.microscope_working_time_s;
  o.out_of_field_share = w > 0.0 ? totals.out_of_field_s / w : 0.0;
  o.out_of_focus_share = w > 0.0 ? totals.out_of_focus_s / w : 0.0;
  o.force_limit_un = totals.force_limit_un;
  o.retina_contacts = totals.retina_contacts;
  o.iatrogenic_events = totals.iatrogenic_events();
  o.retina_tears = totals.retina_tears;
  for (std::size_t k = 0; k < OverlaySnapshot::kMaxEventKinds; ++k) o.event_counts[k] = k < totals.events.size() ? totals.events[k] : 0;
  o.retina_force_un = 0.0;
  const core::Simulation& sys = model.simulation();
  for (std::uint32_t i = 0; i < sys.instrument_count(); ++i) o.retina_force_un = std::max(o.retina_force_un, sys.instrument(i).retina_force_un);
}

}  // namespace

bool capture_view(SimulationModel& model, std::uint64_t step, double t_s, ViewSnapshot& out) {
  PreparedCase& c = model.mutable_case();
  if (out.case_serial != c.serial || out.visuals != c.visuals) {
    if (c.spare_views_used >= c.spare_views.size()) return false;
    std::swap(out, c.spare_views[c.spare_views_used++]);  // moves vectors: no allocation
    for (auto& s : out.surfaces) s.topology_version = ~std::uint64_t{0};
  }
  out.step = step;
  out.t_s = t_s;
  out.case_time_s = model.world().time_s();
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
  // Instruments as the simulation placed them (eye frame, after the eye's rotation), with their
  // handles and what the pedals make them do.
  const core::Simulation& sys = model.simulation();
  const SurgicalControls& controls = model.controls();
  constexpr std::uint32_t kSlots = sizeof(out.instruments) / sizeof(out.instruments[0]);
  for (std::uint32_t i = 0; i < kSlots; ++i) {
    auto& o = out.instruments[i];
    o.present = i < sys.instrument_count() && sys.instrument(i).input.present;
    if (!o.present) continue;
    const core::InstrumentState& st = sys.instrument(i);
    o.inserted = st.inside;
    o.kind = static_cast<int>(st.description.kind);
    o.port = static_cast<int>(st.description.port);
    for (int k = 0; k < 3; ++k) {
      o.tip[k] = static_cast<float>(st.frame.tip[k]);
      o.axis[k] = static_cast<float>(st.frame.u[k]);
      o.up[k] = static_cast<float>(st.frame.v[k]);
      o.aim_point[k] = static_cast<float>(st.aim_point_mm[k]);
    }
    o.shaft_radius_mm = static_cast<float>(core::shaft_radius_mm(st.description.gauge));
    o.actuation = static_cast<float>(st.input.actuation);
    const core::InstrumentDimensions& d = st.description.dimensions;
    const double dims[8] = {d.jaw_length_mm, d.jaw_open_deg, d.jaw_radius_mm, d.pick_length_mm,
                            d.pick_radius_mm, d.blade_length_mm, d.sideways_blade_mm, d.vitrector_port_setback_mm};
    for (int k = 0; k < 8; ++k) o.dims[k] = static_cast<float>(dims[k]);
    o.cutting = st.description.kind == core::InstrumentKind::kVitrector && st.input.pedal > 0.0;
    o.cut_rate_hz = static_cast<float>(controls.cut_rate_cpm > 0.0 ? controls.cut_rate_cpm / 60.0 : sys.options().vitrector.cut_rate_cpm / 60.0);
    o.aim_hit = st.description.kind == core::InstrumentKind::kEndolaser && st.inside && st.aim_hit;
    o.firing = st.description.kind == core::InstrumentKind::kEndolaser && st.input.trigger;
  }
  const core::LightExposure& light = sys.light();
  out.light_active = light.active;
  for (int k = 0; k < 3; ++k) {
    out.light_apex[k] = static_cast<float>(light.apex_mm[k]);
    out.light_axis[k] = static_cast<float>(light.axis[k]);
  }
  out.light_half_angle_deg = static_cast<float>(light.half_angle_rad * 180.0 / std::numbers::pi);
  out.light_level = controls.light_level;
  const core::Microscope& scope = model.microscope();
  out.view_center_mm[0] = scope.center_mm().x();
  out.view_center_mm[1] = scope.center_mm().y();
  out.zoom = scope.zoom();
  out.focus_mm = scope.focus_mm();
  out.depth_of_field_mm = scope.depth_of_field_mm();
  out.field_deg = scope.field_deg();
  out.wide_angle = scope.wide_angle();
  out.image_inverted = scope.image_inverted();
  out.wireframe = model.wireframe();
  out.labels = model.labels();
  out.flat_shading = model.flat_shading();
  out.fluid_level_z_mm = std::isfinite(sys.fluid_level_z_mm()) ? sys.fluid_level_z_mm() : 1e300;
  out.n_burns = 0;
  for (const core::BurnSpot& b : sys.burns()) {
    if (out.n_burns >= ViewSnapshot::kMaxBurns) break;
    BurnSnapshot& o = out.burns[out.n_burns++];
    const core::Vec3 p = sys.burn_position(b);
    for (int k = 0; k < 3; ++k) o.position_mm[k] = static_cast<float>(p[k]);
    o.diameter_mm = static_cast<float>(b.diameter_mm);
    o.age_s = static_cast<float>(out.case_time_s - b.time_s);
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
  capture_progress(model, out);
  return true;
}

// ---- Render service thread -----------------------------------------------------------------------

void FrameBuilder::update_rims(std::size_t surface, const SurfaceSnapshot& s, const CaseVisuals& cv) {
  if (rims_.size() <= surface) rims_.resize(surface + 1);
  Rims& r = rims_[surface];
  if (r.topology_version == s.topology_version) return;
  r.topology_version = s.topology_version;
  const std::size_t n = s.xyz.size() / 3;
  r.rim.assign(n, 0.0f);
  // Boundary edges are those only one triangle uses: sort the edges and keep the unpaired ones.
  std::vector<std::uint64_t> edges;
  edges.reserve(s.indices.size());
  for (std::size_t t = 0; t + 2 < s.indices.size(); t += 3) {
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = s.indices[t + static_cast<std::size_t>(k)], b = s.indices[t + static_cast<std::size_t>((k + 1) % 3)];
      edges.push_back((std::uint64_t{std::min(a, b)} << 32) | std::max(a, b));
    }
  }
  std::sort(edges.begin(), edges.end());
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i + 1;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    if (j - i == 1) {
      for (const std::uint32_t v : {static_cast<std::uint32_t>(edges[i] >> 32), static_cast<std::uint32_t>(edges[i] & 0xffffffffu)}) {
        if (v >= n || 3 * v + 2 >= s.rest_xyz.size()) continue;
        // Where the retina ends at the ora is not a cut: only edges made by cuts and tears roll.
        const core::Vec3 rest(s.rest_xyz[3 * v], s.rest_xyz[3 * v + 1], s.rest_xyz[3 * v + 2]);
        const double polar = std::acos(std::clamp(-rest.z() / std::max(rest.norm(), 1e-9), -1.0, 1.0));
        if (polar < cv.retina_edge_polar_rad) r.rim[v] = 1.0f;
      }
    }
    i = j;
  }
  // One ring inward rolls a little too: the rim is a narrow band, not a line.
  std::vector<float> band = r.rim;
  for (std::size_t t = 0; t + 2 < s.indices.size(); t += 3) {
    float m = 0.0f;
    for (int k = 0; k < 3; ++k) m = std::max(m, r.rim[s.indices[t + static_cast<std::size_t>(k)]]);
    if (m <= 0.0f) continue;
    for (int k = 0; k < 3; ++k) band[s.indices[t + static_cast<std::size_t>(k)]] = std::max(band[s.indices[t + static_cast<std::size_t>(k)]], 0.2f);
  }
  r.rim = std::move(band);
}

void FrameBuilder::add_overlay(const ViewSnapshot& snap, const CaseVisuals& cv, render::FrameScene& scene) {
  const OverlaySnapshot& o = snap.overlay;
  render::InstructorOverlay ov;
  char line[160];
  std::snprintf(line, sizeof line, "%s  T %.1f S  SCORE %.0f", upper(cv.name).c_str(), o.elapsed_s, o.score_total);
  ov.lines.emplace_back(line);
  std::string cats;
  for (std::uint32_t i = 0; i < o.n_scores; ++i) {
    std::string n = upper(o.score_name[i] ? o.score_name[i] : "?");
    n = n.substr(0, n.find(' '));  // the first word: TARGET, EFFICIENCY, TISSUE, INSTRUMENT
    std::snprintf(line, sizeof line, "%s%s %.0f", cats.empty() ? "" : "  ", n.c_str(), o.score_value[i]);
    cats += line;
  }
  if (!cats.empty()) ov.lines.push_back(cats);
  for (std::uint32_t i = 0; i < o.n_criteria; ++i) {
    // Progress toward the criterion's goal (membrane freed 0.51 of a 0.5 goal reads 100 %), said so:
    // a bare "100%" read as the whole membrane freed.
    std::snprintf(line, sizeof line, "%s %s %.0f%% OF GOAL%s", upper(o.criterion_kind[i] ? o.criterion_kind[i] : "?").c_str(),
                  upper(o.criterion_target[i]).c_str(), 100.0 * o.criterion_progress[i], o.criterion_met[i] ? "  MET" : "");
    ov.lines.emplace_back(line);
  }
  std::snprintf(line, sizeof line, "RETINAL CONTACTS %u  IATROGENIC EVENTS %u", o.retina_contacts, o.iatrogenic_events);
  ov.lines.emplace_back(line);
  // Microscope handling's inputs: zoom and focus now, where the work lies in the view (field radius
  // 1 = its edge; off the focal plane against half the depth of field), and the shares so far.
  std::snprintf(line, sizeof line, "MICROSCOPE ZOOM %.1f  FOCUS %+.1f MM  DEPTH OF FIELD %.1f MM", snap.zoom, snap.focus_mm,
                o.scope_depth_of_field_mm);
  ov.lines.emplace_back(line);
  if (o.scope_judged) {
    const bool in_field = o.scope_field_radius <= 1.0, in_focus = o.scope_defocus_mm <= 0.5 * o.scope_depth_of_field_mm;
    if (in_field) {
      std::snprintf(line, sizeof line, "TIP %s AT %.0f%% OF THE FIELD RADIUS, %s", "IN FIELD", 100.0 * o.scope_field_radius,
                    in_focus ? "IN FOCUS" : "OUT OF FOCUS");
    } else {
      std::snprintf(line, sizeof line, "TIP OUT OF THE FIELD, %s", in_focus ? "IN FOCUS" : "OUT OF FOCUS");
    }
    ov.lines.emplace_back(line);
  }
  std::snprintf(line, sizeof line, "WORK OUT OF FIELD %.0f%%  OUT OF FOCUS %.0f%%", 100.0 * o.out_of_field_share,
                100.0 * o.out_of_focus_share);
  ov.lines.emplace_back(line);
  ov.retina_force_un = static_cast<float>(o.retina_force_un);
  ov.force_limit_un = static_cast<float>(o.force_limit_un > 0.0 ? o.force_limit_un : 3000.0);
  // Events that appeared since the last frame, newest last (grasps and releases are not news).
  for (std::size_t k = 0; k < OverlaySnapshot::kMaxEventKinds && k < core::kInstrumentEventKinds; ++k) {
    const auto kind = static_cast<core::InstrumentEventKind>(k);
    if (o.event_counts[k] > events_seen_[k] && kind != core::InstrumentEventKind::kGrasp &&
        kind != core::InstrumentEventKind::kRelease && kind != core::InstrumentEventKind::kLaserBurn) {
      std::snprintf(line, sizeof line, "%.1f S %s", o.elapsed_s, upper(core::to_string(kind)).c_str());
      recent_events_.emplace_back(line);
    }
    events_seen_[k] = o.event_counts[k];
  }
  constexpr std::size_t kKeep = 6;
  if (recent_events_.size() > kKeep) recent_events_.erase(recent_events_.begin(), recent_events_.end() - kKeep);
  ov.events = recent_events_;
  scene.instructor = std::move(ov);
}

render::FrameScene FrameBuilder::build(const ViewSnapshot& snap) {
  render::FrameScene scene;
  scene.sim_time_s = snap.t_s;
  scene.step_index = snap.step;
  ++frame_;
  const CaseVisuals* cv = snap.visuals;
  if (!cv) return scene;
  if (serial_ != snap.case_serial) {  // a new case: nothing derived from the last one carries over
    rims_.clear();
    events_seen_.fill(0);
    recent_events_.clear();
  }
  serial_ = snap.case_serial;
  scene.globe_radius_mm = cv->globe_radius_mm;
  for (render::Mesh m : cv->statics) {
    m.id = mesh_id(serial_, m.id);
    scene.meshes.push_back(std::move(m));
  }

  const double thickness = cv->eye.parameters.retina_thickness_mm;
  for (std::size_t i = 0; i < snap.surfaces.size(); ++i) {
    const SurfaceSnapshot& s = snap.surfaces[i];
    const render::MaterialKind material = i < cv->surface_material.size() ? cv->surface_material[i] : render::MaterialKind::Membrane;
    const bool retina = material == render::MaterialKind::Retina;
    if (retina) update_rims(i, s, *cv);
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
      if (retina) {
        vx.detachment = detachment_of(cv->eye.wall, core::Vec3(vx.position_mm.x, vx.position_mm.y, vx.position_mm.z), thickness);
        // A cut edge or tear rolls toward the vitreous and shows whiter.
        const float rim = v < rims_[i].rim.size() ? rims_[i].rim[v] : 0.0f;
        vx.highlight = rim;
        if (rim > 0.0f) vx.position_mm = vx.position_mm - normalize(vx.position_mm) * (0.08f * rim);
      }
    }
    for (std::size_t t = 0; t + 2 < s.indices.size(); t += 3) {
      const auto a = s.indices[t], b = s.indices[t + 1], c = s.indices[t + 2];
      const render::Vec3 pa = g->vertices[a].position_mm;
      const render::Vec3 nrm = cross(g->vertices[b].position_mm - pa, g->vertices[c].position_mm - pa);
      for (auto v : {a, b, c}) g->vertices[v].normal = g->vertices[v].normal + nrm;
    }
    g->indices = s.indices;
    render::Mesh mesh;
    mesh.id = mesh_id(serial_, 100 + static_cast<std::uint32_t>(i));
    mesh.material = material;
    mesh.geometry = g;
    mesh.geometry_version = frame_;
    mesh.topology_version = s.topology_version;
    if (retina) mesh.texture = cv->retina_texture;
    if (material == render::MaterialKind::Gel && cv->gel_stain) {
      mesh.texture = cv->gel_stain;
      mesh.tint = {1.0f, 1.0f, 0.98f};
    }
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
      burn.age_s = snap.burns[b].age_s;
      mesh.burns.push_back(burn);
    }
    scene.meshes.push_back(std::move(mesh));
  }

  constexpr std::size_t kSlots = sizeof(snap.instruments) / sizeof(snap.instruments[0]);
  for (std::size_t i = 0; i < kSlots; ++i) {
    const auto& ins = snap.instruments[i];
    if (!ins.present || ins.port < 0 || ins.port >= static_cast<int>(cv->ports.size())) continue;
    const Port& port = cv->ports[static_cast<std::size_t>(ins.port)];
    const std::uint32_t first_id = mesh_id(serial_, 200 + 10 * static_cast<std::uint32_t>(i));
    if (!ins.inserted) {
      // Out of the eye: only the part outside the port, along the cannula.
      render::Mesh shaft;
      shaft.id = first_id;
      shaft.material = render::MaterialKind::Instrument;
      shaft.geometry = cylinder_mesh(port.position_mm + 14.0 * port.outward, port.position_mm + 1.0 * port.outward, ins.shaft_radius_mm);
      shaft.geometry_version = frame_;
      shaft.topology_version = 1;
      scene.meshes.push_back(std::move(shaft));
      continue;
    }
    InstrumentView view;
    view.kind = static_cast<core::InstrumentKind>(ins.kind);
    view.tip_mm = {ins.tip[0], ins.tip[1], ins.tip[2]};
    view.axis = {ins.axis[0], ins.axis[1], ins.axis[2]};
    view.up = {ins.up[0], ins.up[1], ins.up[2]};
    // From the tip back through the port and 14 mm beyond it (the handle's side).
    view.shaft_length_mm = length(view.tip_mm - to_render(port.position_mm)) + 14.0f;
    view.shaft_radius_mm = ins.shaft_radius_mm;
    view.actuation = ins.actuation;
    auto& d = view.dims;
    d.jaw_length_mm = ins.dims[0], d.jaw_open_deg = ins.dims[1], d.jaw_radius_mm = ins.dims[2], d.pick_length_mm = ins.dims[3];
    d.pick_radius_mm = ins.dims[4], d.blade_length_mm = ins.dims[5], d.sideways_blade_mm = ins.dims[6];
    d.vitrector_port_setback_mm = ins.dims[7];
    view.cutting = ins.cutting;
    const double phase = snap.case_time_s * static_cast<double>(ins.cut_rate_hz);
    view.cut_phase = static_cast<float>(phase - std::floor(phase));
    view.aim_hit = ins.aim_hit;
    view.aim_mm = {ins.aim_point[0], ins.aim_point[1], ins.aim_point[2]};
    view.aim_normal = -normalize(view.aim_mm);  // the fundus faces the globe's centre
    view.firing = ins.firing;
    view.cone_half_angle_deg = snap.light_half_angle_deg;
    view.light_intensity = static_cast<float>(0.5 + snap.light_level);
    add_instrument_meshes(view, first_id, frame_, scene.meshes);
  }

  // Endoillumination: the light pipe's cone as the simulation placed it; the chandelier's wide cone.
  const float intensity = static_cast<float>(0.5 + snap.light_level);
  if (snap.light_active) {
    render::LightPipe light;
    light.tip_mm = {snap.light_apex[0], snap.light_apex[1], snap.light_apex[2]};
    light.direction = {snap.light_axis[0], snap.light_axis[1], snap.light_axis[2]};
    light.cone_half_angle_deg = snap.light_half_angle_deg;
    light.intensity = intensity;
    scene.light_pipe = light;
  }
  if (cv->chandelier) {
    render::LightPipe ch;
    ch.tip_mm = cv->chandelier_tip;
    ch.direction = cv->chandelier_direction;
    ch.cone_half_angle_deg = 70.0f;
    ch.intensity = 0.8f * intensity;
    ch.range_mm = 22.0f;
    scene.chandelier = ch;
    add_chandelier_meshes(cv->chandelier_tip, cv->chandelier_direction, mesh_id(serial_, 390), scene.meshes);
  }
  if (snap.fluid_level_z_mm < 1e299) scene.fluid_gas = render::FluidGas{{0, 0, 1}, static_cast<float>(snap.fluid_level_z_mm)};

  // The microscope through the eye's optics: the contact lens (or the wide-angle system) brings the
  // fundus into view through the pupil; we do not model that refraction but place the virtual
  // camera on the axis just behind the lens, looking at the field centre on the fundus with the
  // optics' field over the zoom. The image shows fundus +x right and +y up at the field centre, as
  // the joystick moves it; focus moves the sharp plane off the fundus toward the microscope.
  const double cx = snap.view_center_mm[0], cy = snap.view_center_mm[1];
  const core::Vec3 target = wall_at_fundus(cv->eye, cx, cy);
  const core::Vec3 target_on_retina = target - thickness * target.normalized();
  const double eps = 0.05;
  const core::Vec3 up = wall_at_fundus(cv->eye, cx, cy + eps) - wall_at_fundus(cv->eye, cx, cy - eps);
  const core::Vec3 pupil(0.0, 0.0, cv->camera_z_mm);
  render::Microscope& m = scene.microscope;
  m.target_mm = to_render(target_on_retina);
  m.image_up = to_render(up.norm() > 1e-9 ? up : core::Vec3::UnitY());
  m.wide_angle = true;
  m.view_point_mm = to_render(pupil);
  m.zoom = static_cast<float>(snap.zoom);
  m.wide_field_deg = static_cast<float>(snap.field_deg * snap.zoom);
  m.image_inverted = snap.image_inverted;
  // Sharp where the microscope handling score calls the work in focus (Berek's depth of field,
  // core/scene/microscope.cpp): the picture and the score agree.
  m.depth_of_field = true;
  m.depth_of_field_mm = static_cast<float>(snap.depth_of_field_mm);
  m.focus_distance_mm = static_cast<float>(std::max((target_on_retina - pupil).norm() - snap.focus_mm, 1.0));
  scene.wireframe = snap.wireframe;
  scene.flat_shading = snap.flat_shading;
  // Clear infusion fluid scatters little; the gel (its own haze) and the light cone show the rest.
  scene.haze_density_per_mm = 0.008f;

  // Guides and labels (the labels toggle shows or hides both).
  if (snap.labels) {
    for (std::size_t gi = 0; gi < cv->guides.size(); ++gi) {
      const GuideVisual& gv = cv->guides[gi];
      const GuideProgressSnapshot* progress = nullptr;
      for (std::uint32_t k = 0; k < snap.n_guides; ++k) {
        if (snap.guides[k].guide == gi) progress = &snap.guides[k];
      }
      auto geo = std::make_shared<render::MeshGeometry>();
      const std::size_t np = gv.points.size();
      const bool closed = gv.kind == core::GuideKind::kLaserRing;
      const float half_width = gv.kind == core::GuideKind::kLaserRing ? 0.05f : 0.06f;
      std::size_t done = 0;
      if (gv.kind == core::GuideKind::kTarget) {
        // Navigation targets: a ring around each point.
        for (std::size_t k = 0; k < np; ++k) {
          const render::Vec3 c = gv.points[k], nrm = -normalize(c);
          const render::Vec3 a = normalize(cross(nrm, std::fabs(nrm.z) < 0.9f ? render::Vec3{0, 0, 1} : render::Vec3{1, 0, 0}));
          const render::Vec3 b = cross(nrm, a);
          const auto first = static_cast<std::uint32_t>(geo->vertices.size());
          for (int j = 0; j <= 32; ++j) {
            const float t = 6.2831853f * static_cast<float>(j) / 32.0f;
            const render::Vec3 dir = a * std::cos(t) + b * std::sin(t);
            geo->vertices.push_back({c + dir * 0.35f, nrm, {}, 0.0f, 0.0f});
            geo->vertices.push_back({c + dir * 0.47f, nrm, {}, 0.0f, 0.0f});
            if (j > 0) {
              const std::uint32_t q = first + 2 * static_cast<std::uint32_t>(j - 1);
              geo->indices.insert(geo->indices.end(), {q, q + 2, q + 1, q + 1, q + 2, q + 3});
            }
          }
        }
      } else if (np >= 2) {
        for (std::size_t k = 0; k < np; ++k) {
          const render::Vec3 p = gv.points[k];
          const render::Vec3 prev = gv.points[k > 0 ? k - 1 : (closed ? np - 1 : 0)];
          const render::Vec3 next = gv.points[k + 1 < np ? k + 1 : (closed ? 0 : np - 1)];
          const render::Vec3 nrm = -normalize(p);
          const render::Vec3 side = normalize(cross(next - prev, nrm)) * half_width;
          const float h = progress && k < progress->n && progress->covered[k] ? 1.0f : 0.0f;
          done += h > 0.0f;
          geo->vertices.push_back({p - side, nrm, {}, 0.0f, h});
          geo->vertices.push_back({p + side, nrm, {}, 0.0f, h});
        }
        const std::size_t segments = closed ? np : np - 1;
        for (std::size_t k = 0; k < segments; ++k) {
          const auto a = static_cast<std::uint32_t>(2 * k), b = static_cast<std::uint32_t>(2 * ((k + 1) % np));
          geo->indices.insert(geo->indices.end(), {a, b, a + 1, a + 1, b, b + 1});
        }
      }
      render::Mesh guide;
      guide.id = mesh_id(serial_, 300 + static_cast<std::uint32_t>(gi));
      guide.material = render::MaterialKind::Guide;
      guide.geometry = geo;
      guide.geometry_version = frame_;
      guide.topology_version = frame_;
      scene.meshes.push_back(std::move(guide));
      if (np > 0) {
        char text[96];
        if (progress && np > 0) {
          std::snprintf(text, sizeof text, "%s %.0f%%", upper(gv.name).c_str(), 100.0 * static_cast<double>(done) / static_cast<double>(np));
        } else {
          std::snprintf(text, sizeof text, "%s", upper(gv.name).c_str());
        }
        scene.labels.push_back({gv.points[0], text, {1.0f, 0.9f, 0.35f}});
      }
    }
    for (const render::Label& l : cv->labels) scene.labels.push_back(l);
  }
  add_overlay(snap, *cv, scene);
  return scene;
}

}  // namespace vitreo::rig
