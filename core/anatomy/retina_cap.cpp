#include "core/anatomy/retina_cap.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

#include "core/common/validate.hpp"
#include "core/geometry/revolved_mesh.hpp"
#include "core/topology/clean_topology.hpp"
#include "core/common/units.hpp"

namespace vitreo::core {

namespace {

using units::kDeg;

// Unit direction from the globe centre at polar angle theta from the posterior pole (−z) and
// azimuth phi (0 = +x, nasal).
Vec3 direction(double theta_rad, double phi_rad) {
  return {std::sin(theta_rad) * std::cos(phi_rad), std::sin(theta_rad) * std::sin(phi_rad), -std::cos(theta_rad)};
}

}  // namespace

RetinaCapScene build_retina_cap(const RetinaCapOptions& o) {
  require_range(o.globe_radius_mm, 5.0, 20.0, "retina cap: globe_radius_mm");
  require_range(o.ora_serrata_deg, 30.0, 170.0, "retina cap: ora_serrata_deg");
  if (o.retina_vertices < 50 || o.retina_vertices > 2'000'000) {
    throw InvalidArgument("retina cap: retina_vertices must be in [50, 2000000]");
  }
  require_range(o.optic_disc_offset_deg, 0.0, 45.0, "retina cap: optic_disc_offset_deg");
  require_range(o.optic_disc_radius_mm, 0.0, 3.0, "retina cap: optic_disc_radius_mm");
  require_range(o.detachment_radius_deg, 1.0, 90.0, "retina cap: detachment_radius_deg");
  require_range(o.detachment_center_deg, 0.0, 170.0, "retina cap: detachment_center_deg");
  require_range(o.membrane_radius_deg, 1.0, 90.0, "retina cap: membrane_radius_deg");
  if (o.membrane_attachment_stride < 1) throw InvalidArgument("retina cap: membrane_attachment_stride must be >= 1");

  const double R = o.globe_radius_mm;
  RetinaCapScene scene{TissueWorld(GlobeWall::sphere(Vec3::Zero(), R), o.environment, o.solver)};
  TissueWorld& world = scene.world;

  // Retina: the cap from the posterior pole to the ora serrata, lying on the wall.
  const double ora = o.ora_serrata_deg * kDeg;
  SurfaceDescription retina;
  retina.material = o.retina;
  retina.pressurised = true;
  retina.contained_by_globe = true;
  const int segments = std::max(8, static_cast<int>(o.ora_serrata_deg));
  retina.mesh = revolve_profile(sphere_arc_profile(R, 0.0, ora, segments),
                                {edge_length_for_vertex_count(R, ora, o.retina_vertices), 2.0 * std::numbers::pi});
  const std::size_t nv = retina.mesh.positions.size();
  scene.retina = world.add_surface(retina);
  Surface& rs = world.surface(scene.retina);

  // Anchors: the ora serrata ring (last ring of the profile) and the optic disc rim.
  const double ora_arc = R * ora;
  const Vec3 disc = direction(o.optic_disc_offset_deg * kDeg, 0.0) * R;
  for (std::uint32_t v = 0; v < nv; ++v) {
    const bool at_ora = retina.mesh.surface_coords[v].x() > ora_arc - 1e-6;
    const bool at_disc = (rs.position(v) - disc).norm() <= o.optic_disc_radius_mm;
    if (at_ora || at_disc) {
      (void)rs.set_fixed(rs.vertex_id(v), true);
      ++scene.anchored_vertices;
    }
  }

  if (o.detachment) {
    LocalForceDescription f;
    f.name = "detachment";
    f.surface = scene.retina;
    f.toward_point_mm = Vec3::Zero();
    f.pressure_pa = o.detachment_pressure_pa;
    const Vec3 center = direction(o.detachment_center_deg * kDeg, std::numbers::pi);
    const double radius = o.detachment_radius_deg * kDeg;
    for (std::uint32_t v = 0; v < nv; ++v) {
      if (rs.is_fixed(v)) continue;
      const double ang = angle_between(rs.position(v), center);
      if (ang < radius) {
        f.vertices.push_back(v);
        // Smooth edge so the detachment has no crease at its border.
        const double u = ang / radius;
        f.weights.push_back(std::clamp(1.5 * (1.0 - u * u), 0.0, 1.0));
      }
    }
    scene.detachment_force = world.add_local_force(f);
  }

  if (o.membrane) {
    const double extent = o.membrane_radius_deg * kDeg;
    const Vec3 pole(0.0, 0.0, -R);
    std::vector<std::uint32_t> to_membrane(nv, kNone);
    SurfaceDescription m;
    m.material = o.retina;
    m.material.name = "epiretinal membrane";
    m.material.membrane_modulus_pa_mm = 4.0 * o.retina.membrane_modulus_pa_mm;
    m.contained_by_globe = true;
    std::vector<std::uint32_t> from_retina;
    for (const auto& t : retina.mesh.triangles) {
      bool inside = true;
      for (auto v : t) inside = inside && angle_between(retina.mesh.positions[v], pole) <= extent;
      if (!inside) continue;
      std::array<std::uint32_t, 3> mt{};
      for (int k = 0; k < 3; ++k) {
        const auto v = t[static_cast<std::size_t>(k)];
        if (to_membrane[v] == kNone) {
          to_membrane[v] = static_cast<std::uint32_t>(m.mesh.positions.size());
          m.mesh.positions.push_back(retina.mesh.positions[v]);
          from_retina.push_back(v);
        }
        mt[static_cast<std::size_t>(k)] = to_membrane[v];
      }
      m.mesh.triangles.push_back(mt);
    }
    if (m.mesh.triangles.empty()) throw InvalidArgument("retina cap: membrane radius too small for the mesh");
    scene.membrane = world.add_surface(m);
    for (std::uint32_t v = 0; v < from_retina.size(); v += static_cast<std::uint32_t>(o.membrane_attachment_stride)) {
      AttachmentDescription a;
      a.surface_a = scene.membrane;
      a.vertex_a = v;
      a.surface_b = scene.retina;
      a.vertex_b = from_retina[v];
      a.stiffness_un_per_mm = 2e3;
      a.break_force_un = o.membrane_break_force_un;
      world.add_attachment(a);
      ++scene.attachments;
    }
  }
  // The solver's tears and creep clean up after themselves like the tools' cuts (clean_topology.hpp).
  install_clean_topology(world);
  return scene;
}

}  // namespace vitreo::core
