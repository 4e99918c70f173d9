// Step stage 1: external forces, as accelerations per vertex, once per step.
//
// Gravity with buoyancy (the retina is barely denser than vitreous, so it sinks slowly; under gas it
// falls as it would in air), intraocular pressure along triangle normals, the local force functions
// (detachment), and the drag rate used by the implicit damping in each substep.
#include <algorithm>
#include <cmath>

#include "core/tissue/awake_vertices.hpp"
#include "core/tissue/tissue_world.hpp"

namespace vitreo::core {

namespace {
// Over this distance from the wall its reaction fades in (see below).
constexpr double kContactBand_mm = 1e-3;
}  // namespace

void TissueWorld::compute_external_accelerations(double h) {
  const Environment& env = environment_;
  for (std::uint32_t si = 0; si < surfaces_.size(); ++si) {
    Surface& s = *surfaces_[si];
    Scratch& sc = scratch_[si];
    auto view = s.solver_view();
    const std::uint32_t n = s.vertex_slots();
    const double rho = s.material().density_g_per_mm3;
    const Vec3 g_fluid = env.gravity_mm_s2 * (1.0 - env.fluid_density_g_per_mm3 / rho);
    const Vec3 g_gas = env.gravity_mm_s2 * (1.0 - env.gas_density_g_per_mm3 / rho);
    const bool any_gas = std::isfinite(env.fluid_level_z_mm);
    const double drag = s.material().drag_pa_s_per_mm;
    const double settling_damping = settings_.settling_damping_per_s;

    // A block that fell asleep since the last step becomes immovable to its awake neighbours.
    for (std::uint32_t b = 0; b < s.block_count(); ++b) {
      const bool awake = s.block_awake(b);
      if (!awake && sc.block_was_awake[b]) {
        ++sc.block_sleep_serial[b];  // its springs' wake lengths are taken afresh (pack_springs)
        const std::uint32_t end = std::min(n, (b + 1) * Surface::kSleepBlock);
        for (std::uint32_t v = b * Surface::kSleepBlock; v < end; ++v) {
          sc.effective_inverse_mass[v] = 0.0;
          sc.acceleration[v] = Vec3::Zero();
          sc.contact_load[v] = 0.0;
          sc.previous[v] = view.x[v];  // at rest: no motion for the spring dashpots to see
        }
      }
      sc.block_was_awake[b] = awake ? 1 : 0;
    }

    // Forces first (µN), converted to accelerations at the end.
    for_awake_vertices(si, [&](std::uint32_t v) { sc.acceleration[v] = Vec3::Zero(); });

    // Intraocular pressure presses the retina outward onto the choroid. It is applied along the
    // ray from the globe centre, on each vertex's share of the current (stretched) area: directed
    // by the eye's geometry rather than by triangle orientation, so a crumpled or flipped patch of
    // detached retina is never driven inward by it. (On a sphere about the centre this is exactly
    // the normal pressure; tests/core check it against Laplace's law.)
    const bool pressurised = s.pressurised() && env.apply_pressure && env.intraocular_pressure_pa > 0.0;
    if (pressurised) {
      const std::uint64_t epoch = ++sc.area_epoch;
      for_each_awake_vertex(s, [&](std::uint32_t v) {
        double area = 0.0;
        s.for_each_triangle_of(v, [&](std::uint32_t t, std::uint32_t) {
          if (sc.triangle_epoch[t] != epoch) {  // each triangle once, not once per corner
            sc.triangle_epoch[t] = epoch;
            const auto [a, b, c] = view.tri_v[t];
            sc.triangle_area2[t] = (view.x[b] - view.x[a]).cross(view.x[c] - view.x[a]).norm();
          }
          area += sc.triangle_area2[t];
        });
        sc.current_area[v] = area / 6.0;
      });
    }

    for (const auto& lf : local_forces_) {
      if (lf.d.surface != si || lf.d.scale == 0.0 || lf.d.pressure_pa == 0.0) continue;
      const double p = lf.d.pressure_pa * lf.d.scale;
      for (std::size_t i = 0; i < lf.d.vertices.size(); ++i) {
        const std::uint32_t v = lf.d.vertices[i];
        if (!view.vertex_alive[v] || !s.vertex_awake(v)) continue;  // removed since, or asleep
        const Vec3 toward = lf.d.toward_point_mm - view.x[v];
        const double dist = toward.norm();
        if (!(dist > 1e-9)) continue;
        const double w = lf.d.weights.empty() ? 1.0 : lf.d.weights[i];
        sc.acceleration[v] += toward * (p * w * view.vertex_area[v] / dist);
      }
    }

    // Vitrector suction (thesis ch. 2.6.2.2): only inside each port's hemisphere, scaled by the
    // cosine of the angle off the port axis, capped like the thesis' clamp on small new vertices.
    for (const SuctionField& f : suction_) {
      const double r2 = f.radius_mm * f.radius_mm;
      for_awake_vertices(si, [&](std::uint32_t v) {
        if (!view.vertex_alive[v] || view.inverse_mass[v] == 0.0) return;
        const Vec3 out = view.x[v] - f.apex_mm;
        const double d2 = out.squaredNorm();
        if (d2 > r2 || !(d2 > 1e-18)) return;
        const double along = out.dot(f.axis);
        if (along <= 0.0) return;  // behind the port: outside the hemisphere
        const double d = std::sqrt(d2);
        const double cosine = along / d;
        sc.acceleration[v] -= out * (f.pressure_pa * cosine * view.vertex_area[v] / d);
      });
    }

    const bool walled = s.contained_by_globe();
    const double added_per_area = env.fluid_density_g_per_mm3 * s.material().entrained_fluid_mm;
    const double mu = settings_.wall_friction;
    for_awake_vertices(si, [&](std::uint32_t v) {
      if (!view.vertex_alive[v] || view.inverse_mass[v] == 0.0) {
        sc.acceleration[v] = Vec3::Zero();
        sc.effective_inverse_mass[v] = 0.0;
        sc.drag_rate[v] = 0.0;
        sc.velocity_keep[v] = 1.0;
        sc.contact_load[v] = 0.0;
        return;
      }
      // Inertia = own mass + entrained fluid (none under gas); weight acts on the own mass only.
      const bool in_gas = any_gas && view.x[v].z() > env.fluid_level_z_mm;
      // (Divisions are the cost of this loop: each reciprocal is taken once and multiplied.)
      const double own_mass = s.mass(v);
      const double inertia = own_mass + (in_gas ? 0.0 : added_per_area * view.vertex_area[v]);
      const double inverse_inertia = 1.0 / inertia;
      sc.drag_rate[v] = drag * view.vertex_area[v] * inverse_inertia + settling_damping;
      sc.velocity_keep[v] = 1.0 / (1.0 + h * sc.drag_rate[v]);
      sc.effective_inverse_mass[v] = inverse_inertia * sc.velocity_keep[v];
      const Vec3& g = in_gas ? g_gas : g_fluid;
      const Vec3 radial = view.x[v] - wall_.center();
      const double r = radial.norm();
      const double inverse_r = 1.0 / r;
      if (pressurised && r > 0.0) {
        sc.acceleration[v] += radial * (env.intraocular_pressure_pa * sc.current_area[v] * inverse_r);
      }
      Vec3 a = (sc.acceleration[v] + own_mass * g) * inverse_inertia;
      sc.contact_load[v] = 0.0;
      if (walled && r > 0.0) {
        // Resting contact: where tissue lies on the wall and is pushed into it (intraocular
        // pressure on the attached retina), friction holds the tangential part up to μ times the
        // normal load, fading in over the last kContactBand_mm before the wall.
        //
        // The normal load itself stays in the acceleration: the wall takes it as a constraint
        // when the prediction reaches it (integrate_and_predict stops the predicted position on
        // the wall, before the springs see it), so the wall pushes back exactly as hard as the
        // springs leave it to, never more. Removing the normal load here instead (an explicit
        // reaction fading over a micrometre) made a stiff penalty spring — the load of ~10⁶ mm/s²
        // over 1 µm — that one-step substeps cannot integrate: where a detachment meets the
        // attached retina the springs lifted vertices off the unloaded wall, the full load slammed
        // them back, and they flipped between the two every step at ~5 mm/s, never resting.
        const double clearance = wall_.radius_toward(radial, r) - r - settings_.wall_offset_mm;
        const double engaged = std::clamp(1.0 - clearance / kContactBand_mm, 0.0, 1.0);
        const Vec3 normal = radial * inverse_r;
        const double an = a.dot(normal);
        if (engaged > 0.0 && an > 0.0) {
          const double reaction = engaged * an;
          Vec3 at = a - an * normal;
          const double at_norm = at.norm();
          const double friction = mu * reaction;
          at *= at_norm > friction ? 1.0 - friction / at_norm : 0.0;
          a = at + an * normal;
          sc.contact_load[v] = reaction;  // the wall's normal load, per unit inertia
          sc.contact_normal[v] = normal;
        }
      }
      sc.acceleration[v] = a;
    });
  }
}

}  // namespace vitreo::core
