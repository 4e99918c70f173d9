#include "strip_stiffness.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <utility>
#include <vector>

#include "core/anatomy/retina_cap.hpp"

namespace vitreo::test {

using namespace vitreo::core;

namespace {

constexpr double kDt = 1e-3;

}  // namespace

GlobeWall far_wall() { return GlobeWall::sphere(Vec3::Zero(), 1e6); }

Environment weightless() {
  Environment env;
  env.gravity_mm_s2 = Vec3::Zero();
  env.apply_pressure = false;
  return env;
}

TriangleMesh retina_strip(int retina_vertices, double width_mm, double length_mm) {
  RetinaCapOptions o;
  o.retina_vertices = retina_vertices;
  o.detachment = false;
  const RetinaCapScene scene = build_retina_cap(o);
  const Surface& s = scene.world.surface(scene.retina);
  const double R = o.globe_radius_mm;
  auto flat = [&](std::uint32_t v) {
    const Vec3& p = s.rest_position(v);
    const double polar = std::acos(std::clamp(-p.z() / p.norm(), -1.0, 1.0));  // from the posterior pole
    const double azimuth = std::atan2(p.y(), p.x());
    return Vec3(R * azimuth, R * (polar - std::numbers::pi / 2), 0.0);
  };
  TriangleMesh m;
  std::vector<std::uint32_t> index(s.vertex_slots(), kNone);
  for (std::uint32_t t = 0; t < s.triangle_slots(); ++t) {
    if (!s.triangle_alive(t)) continue;
    const auto tv = s.triangle_vertices(t);
    bool inside = true;
    for (const auto v : tv) {
      const Vec3 p = flat(v);
      inside = inside && std::abs(p.y()) <= width_mm / 2 && p.x() >= 0.0 && p.x() <= length_mm;
    }
    if (!inside) continue;
    std::array<std::uint32_t, 3> out{};
    for (std::size_t k = 0; k < 3; ++k) {
      if (index[tv[k]] == kNone) {
        index[tv[k]] = static_cast<std::uint32_t>(m.positions.size());
        m.positions.push_back(flat(tv[k]));
      }
      out[k] = index[tv[k]];
    }
    m.triangles.push_back(out);
  }
  return m;
}

StripLoad strip_load(const TriangleMesh& mesh, double sigma) {
  StripLoad l;
  double y0 = 1e9, y1 = -1e9;
  l.x0 = 1e9, l.x1 = -1e9;
  for (const auto& p : mesh.positions) {
    l.x0 = std::min(l.x0, p.x()), l.x1 = std::max(l.x1, p.x()), y0 = std::min(y0, p.y()), y1 = std::max(y1, p.y());
  }
  for (const auto& t : mesh.triangles)
    for (std::size_t k = 0; k < 3; ++k) l.longest_edge = std::max(l.longest_edge, (mesh.positions[t[k]] - mesh.positions[t[(k + 1) % 3]]).norm());
  l.width = y1 - y0;
  l.y_mid = 0.5 * (y0 + y1);
  for (std::uint32_t v = 0; v < mesh.positions.size(); ++v) {
    if (mesh.positions[v].x() < l.x0 + 0.3 * l.longest_edge) l.clamped.push_back(v);
    if (mesh.positions[v].x() > l.x1 - 0.3 * l.longest_edge) l.pulled.push_back(v);
  }
  const auto& x = mesh.positions;
  std::sort(l.pulled.begin(), l.pulled.end(), [&](auto a, auto b) { return x[a].y() < x[b].y(); });
  for (std::size_t i = 0; i < l.pulled.size(); ++i) {
    const double lo = i == 0 ? y0 : 0.5 * (x[l.pulled[i - 1]].y() + x[l.pulled[i]].y());
    const double hi = i + 1 == l.pulled.size() ? y1 : 0.5 * (x[l.pulled[i]].y() + x[l.pulled[i + 1]].y());
    l.force_un.push_back(sigma * (hi - lo));
  }
  return l;
}

double strip_strain(const TriangleMesh& mesh, const StripLoad& load, const std::function<Vec3(std::uint32_t)>& position) {
  auto mean_x = [&](double at) {
    double now = 0.0, rest = 0.0;
    int n = 0;
    for (std::uint32_t v = 0; v < mesh.positions.size(); ++v) {
      if (std::abs(mesh.positions[v].x() - at) > 0.6 * load.longest_edge) continue;
      now += position(v).x(), rest += mesh.positions[v].x(), ++n;
    }
    return std::pair{now / n, rest / n};
  };
  const auto [a_now, a_rest] = mean_x(load.x0 + (load.x1 - load.x0) / 3);
  const auto [b_now, b_rest] = mean_x(load.x0 + 2 * (load.x1 - load.x0) / 3);
  return ((b_now - a_now) - (b_rest - a_rest)) / (b_rest - a_rest);
}

StripResult stretch_strip(const TriangleMesh& mesh, const TissueMaterial& material, double strain_target,
                          const SolverSettings& settings, double max_settle_s) {
  SurfaceDescription d;
  d.mesh = mesh;
  d.material = material;
  d.material.tear_strain = INFINITY;
  d.contained_by_globe = false;
  TissueWorld world(far_wall(), weightless(), settings);
  const std::uint32_t id = world.add_surface(d);
  Surface& s = world.surface(id);
  StripResult r;
  r.vertices = mesh.positions.size();
  const double sigma = strain_target * material.membrane_modulus_pa_mm;
  const StripLoad load = strip_load(mesh, sigma);
  for (const auto v : load.clamped) r.clamped = r.clamped && s.set_fixed(s.vertex_id(v), true).is_ok();
  LocalForceDescription f;
  f.name = "pull";
  f.surface = id;
  f.toward_point_mm = Vec3(1e9, load.y_mid, 0.0);
  f.pressure_pa = 1e5;
  for (std::size_t i = 0; i < load.pulled.size(); ++i) {
    r.applied_force_un += load.force_un[i];
    f.vertices.push_back(load.pulled[i]);
    f.weights.push_back(load.force_un[i] / (f.pressure_pa * s.vertex_rest_area(load.pulled[i])));
  }
  r.expected_force_un = sigma * load.width;
  world.add_local_force(f);

  int i = 0;
  for (; i < static_cast<int>(max_settle_s / kDt); ++i) {
    r.steps_ok = r.steps_ok && world.step(kDt).ok;
    if (world.awake_blocks() == 0) break;
  }
  r.settle_s = i * kDt;
  r.modulus = sigma / strip_strain(mesh, load, [&](std::uint32_t v) { return s.position(v); });
  return r;
}

double strip_stiffness_error(int retina_vertices, const SolverSettings& settings) {
  const TissueMaterial retina;  // the retina's values (scenes/materials.toml)
  const StripResult r = stretch_strip(retina_strip(retina_vertices, 2.0, 8.0), retina, 0.01, settings);
  return r.modulus / retina.membrane_modulus_pa_mm - 1.0;
}

}  // namespace vitreo::test
