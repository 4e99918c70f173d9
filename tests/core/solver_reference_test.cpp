// The solver against analytic solutions: a hanging chain (catenary), a pressurised spherical
// membrane (Laplace's law) and the small oscillations of a spring–mass chain.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/geometry/revolved_mesh.hpp"
#include "core/tissue/tissue_world.hpp"

using namespace vitreo::core;

namespace {

GlobeWall far_wall() { return GlobeWall::sphere(Vec3::Zero(), 1e6); }

Environment no_fluid(const Vec3& gravity) {
  Environment env;
  env.gravity_mm_s2 = gravity;
  env.fluid_density_g_per_mm3 = 0.0;
  env.apply_pressure = false;
  return env;
}

// Catenary parameter a for a chain of length L hung between supports D apart: L = 2a sinh(D / 2a).
double catenary_parameter(double length, double span) {
  double lo = 1e-6, hi = 1e6;
  for (int i = 0; i < 200; ++i) {
    const double mid = std::sqrt(lo * hi);
    (2 * mid * std::sinh(span / (2 * mid)) > length ? lo : hi) = mid;
  }
  return std::sqrt(lo * hi);
}

}  // namespace

TEST(SolverReference, HangingChainSagsLikeACatenary) {
  const int links = 60;
  const double span = 10.0, length = 14.0, link = length / links;
  // Start as a "V" whose links already have their rest length; rest vectors are irrelevant
  // (direction stiffness 0), so the chain is free to find its own shape.
  SurfaceDescription chain;
  chain.material.direction_stiffness_ratio = 0.0;
  chain.material.drag_pa_s_per_mm = 0.0;
  chain.material.internal_damping_s = 0.0;  // the analytic reference is purely elastic
  chain.contained_by_globe = false;
  const double half_drop = std::sqrt((length / 2) * (length / 2) - (span / 2) * (span / 2));
  for (int i = 0; i <= links; ++i) {
    const double s = i * link;  // arc length along the V
    const double u = s <= length / 2 ? s / (length / 2) : (length - s) / (length / 2);
    const double x = -span / 2 + span * s / length;
    chain.mesh.positions.emplace_back(x, 0.0, -half_drop * u);
    chain.extra_vertex_mass_g.push_back(1e-3);
  }
  for (std::uint32_t i = 0; i < static_cast<std::uint32_t>(links); ++i) chain.line_springs.push_back({i, i + 1, 1e7});

  SolverSettings settings;
  settings.substeps = 8;
  settings.iterations = 8;
  settings.settling_damping_per_s = 20.0;
  TissueWorld world(far_wall(), no_fluid({0, 0, -units::kStandardGravity_mm_s2}), settings);
  const auto id = world.add_surface(chain);
  Surface& s = world.surface(id);
  ASSERT_TRUE(s.set_fixed(s.vertex_id(0), true));
  ASSERT_TRUE(s.set_fixed(s.vertex_id(static_cast<std::uint32_t>(links)), true));
  for (int i = 0; i < 4000; ++i) ASSERT_TRUE(world.step(1e-3).ok);

  const double a = catenary_parameter(length, span);
  const double sag = a * (std::cosh(span / (2 * a)) - 1.0);
  const double lowest = s.position(static_cast<std::uint32_t>(links / 2)).z();
  // A 60-link discrete chain differs from the continuous catenary by O(1/N²): well under 1 %.
  EXPECT_NEAR(-lowest, sag, 0.01 * sag) << "analytic sag " << sag;
  // And every node lies on the curve z = a cosh(x/a) − a − sag.
  for (int i = 0; i <= links; ++i) {
    const Vec3& p = s.position(static_cast<std::uint32_t>(i));
    const double z = a * std::cosh(p.x() / a) - a - sag;
    EXPECT_NEAR(p.z(), z, 0.01 * sag) << "node " << i;
  }
}

TEST(SolverReference, PressurisedSphereFollowsLaplacesLaw) {
  // A closed membrane sphere of rest radius R0 and modulus E·t under inner pressure P. A spring
  // network with Van Gelder stiffness has equibiaxial tension T = 3/2 E·t · ε (Poisson 1/3) per unit
  // rest length; per unit current length T·R0/R. Laplace: P = 2T/R  ⇒  P R² − 3 E t R + 3 E t R0 = 0.
  const double r0 = 5.0, et = 1000.0, p = 40.0;
  const double r_expected = (3 * et - std::sqrt(9 * et * et - 12 * p * et * r0)) / (2 * p);

  SurfaceDescription sphere;
  sphere.material.membrane_modulus_pa_mm = et;
  sphere.material.direction_stiffness_ratio = 0.0;
  sphere.material.tear_strain = INFINITY;
  sphere.material.internal_damping_s = 0.0;
  sphere.pressurised = true;
  sphere.contained_by_globe = false;
  sphere.mesh = revolve_profile(sphere_arc_profile(r0, 0.0, std::numbers::pi, 512), {0.35, 2 * std::numbers::pi});

  SolverSettings settings;
  settings.substeps = 4;
  settings.iterations = 4;
  settings.settling_damping_per_s = 50.0;
  Environment env = no_fluid(Vec3::Zero());
  env.apply_pressure = true;
  env.intraocular_pressure_pa = p;
  TissueWorld world(far_wall(), env, settings);
  const auto id = world.add_surface(sphere);
  for (int i = 0; i < 3000; ++i) ASSERT_TRUE(world.step(1e-3).ok);

  const Surface& s = world.surface(id);
  double mean = 0.0;
  for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) mean += s.position(v).norm();
  mean /= s.vertex_slots();
  // Tolerance: 1 % of the radius, i.e. ~10 % of the stretch (R − R0 ≈ 0.5 mm); the revolved
  // triangulation is near but not exactly equilateral.
  EXPECT_NEAR(mean, r_expected, 0.01 * r_expected) << "R0 " << r0 << ", analytic R " << r_expected;
  EXPECT_GT(mean, r0 + 0.5 * (r_expected - r0)) << "the sphere must actually inflate";
}

TEST(SolverReference, SpringMassChainOscillatesAtItsNormalModeFrequency) {
  // N masses m between two walls, springs k: ω_n = 2 √(k/m) sin(nπ / 2(N+1)).
  const int n = 3;
  const double k = 20.0, m = 0.01, spacing = 2.0, amplitude = 0.01;
  SurfaceDescription chain;
  chain.material.direction_stiffness_ratio = 0.0;
  chain.material.drag_pa_s_per_mm = 0.0;
  chain.material.internal_damping_s = 0.0;
  chain.contained_by_globe = false;
  for (int i = 0; i <= n + 1; ++i) {
    chain.mesh.positions.emplace_back(i * spacing, 0.0, 0.0);
    chain.extra_vertex_mass_g.push_back(m);
  }
  for (std::uint32_t i = 0; i <= static_cast<std::uint32_t>(n); ++i) chain.line_springs.push_back({i, i + 1, k});

  SolverSettings settings;
  settings.substeps = 4;
  TissueWorld world(far_wall(), no_fluid(Vec3::Zero()), settings);
  Surface& s = world.surface(world.add_surface(chain));
  ASSERT_TRUE(s.set_fixed(s.vertex_id(0), true));
  ASSERT_TRUE(s.set_fixed(s.vertex_id(static_cast<std::uint32_t>(n + 1)), true));
  // Excite the first mode exactly.
  for (int j = 1; j <= n; ++j) {
    const double shape = std::sin(j * std::numbers::pi / (n + 1));
    ASSERT_TRUE(s.set_position(s.vertex_id(static_cast<std::uint32_t>(j)), Vec3(j * spacing + amplitude * shape, 0, 0)));
  }

  const double omega = 2 * std::sqrt(k / m) * std::sin(std::numbers::pi / (2 * (n + 1)));
  const double dt = 1e-3;
  // Time upward zero crossings of the middle mass (linear interpolation between steps).
  std::vector<double> crossings;
  double prev = amplitude;
  for (int i = 1; i <= 3000; ++i) {
    ASSERT_TRUE(world.step(dt).ok);
    const double u = s.position(2).x() - 2 * spacing;
    if (prev < 0.0 && u >= 0.0) crossings.push_back((i - 1 + prev / (prev - u)) * dt);
    prev = u;
  }
  ASSERT_GE(crossings.size(), 5u);
  const double period = (crossings.back() - crossings.front()) / static_cast<double>(crossings.size() - 1);
  EXPECT_NEAR(2 * std::numbers::pi / period, omega, 0.005 * omega) << "analytic ω " << omega;
}
