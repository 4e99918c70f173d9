// The solver's own tears and plastic creep through the topology hook (core/topology/clean_topology.hpp):
// forceps pulling a sheet tear it where they pull, the crack grows from there, and after every
// step the mesh is valid, above the quality floor and its mass exact; creep that shrinks a spring
// below the floor is cleaned up at the step boundary (without the hook it is not — the control).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "core/anatomy/retina_cap.hpp"
#include "core/tissue/surface_validity.hpp"
#include "core/tissue/tissue_world.hpp"
#include "core/topology/clean_topology.hpp"
#include "core/topology/quality.hpp"
#include "topology_test_util.hpp"

using namespace vitreo::core;
using namespace vitreo::core::test;

namespace {

TissueWorld free_world() {
  Environment env;
  env.apply_pressure = false;
  env.gravity_mm_s2 = Vec3::Zero();
  return TissueWorld(GlobeWall::sphere(Vec3::Zero(), 1e6), env);
}

// The live triangle whose rest shape contains (x, y) in the sheet's plane, with its barycentrics.
std::uint32_t triangle_at(const Surface& s, double x, double y, Vec3& bary) {
  for (std::uint32_t t = 0; t < s.triangle_slots(); ++t) {
    if (!s.triangle_alive(t)) continue;
    const auto tv = s.triangle_vertices(t);
    const Vec3 a = s.rest_position(tv[0]), b = s.rest_position(tv[1]), c = s.rest_position(tv[2]);
    const double det = (b.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (b.y() - a.y());
    const double u = ((x - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (y - a.y())) / det;
    const double v = ((b.x() - a.x()) * (y - a.y()) - (x - a.x()) * (b.y() - a.y())) / det;
    if (u >= 0 && v >= 0 && u + v <= 1) {
      bary = Vec3(1 - u - v, u, v);
      return t;
    }
  }
  return kNone;
}

}  // namespace

TEST(SolverTearing, ForcepsPullingASheetTearItAtTheGripAndEveryStepLeavesACleanMesh) {
  TissueWorld world = free_world();
  SurfaceDescription d = sheet(kSheetW, kSheetH, kSheetCols, kSheetRows, 0.3, 7);
  d.material.tear_strain = 0.3;
  const std::uint32_t si = world.add_surface(d);
  Surface& s = world.surface(si);
  for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) {
    const double x = s.rest_position(v).x();
    if (x == 0.0 || x == kSheetW) {
      ASSERT_TRUE(s.set_fixed(s.vertex_id(v), true));
    }
  }
  install_clean_topology(world);
  ASSERT_NE(world.topology_hook(si), nullptr);
  const double mass0 = s.total_mass();

  // Forceps grasp the sheet off-centre and lift it out of its plane at 20 mm/s.
  const Vec3 grasp(1.6, 1.3, 0.0);
  GripDescription g;
  g.surface = si;
  g.triangle = s.triangle_id(triangle_at(s, grasp.x(), grasp.y(), g.bary));
  ASSERT_TRUE(g.triangle.valid());
  g.target_mm = grasp;
  const std::uint32_t grip = world.add_grip(g);
  ASSERT_NE(grip, kNone);

  std::vector<Vec3> tears;
  const ValidityLimits limits = quality_limits();
  for (int step = 0; step < 1500 && tears.size() < 12; ++step) {
    ASSERT_TRUE(world.set_grip_target(grip, grasp + Vec3(0.0, 0.0, 0.02 * (step + 1))));
    const StepReport r = world.step(1e-3);
    ASSERT_TRUE(r.ok) << r.error;
    for (const auto& e : world.events()) {
      if (e.kind == TissueEventKind::kTear) tears.push_back(e.position_mm);
    }
    if (r.tears > 0) {
      const auto report = check_surface(s, limits);
      ASSERT_TRUE(report.ok()) << "after the tears of step " << step << ": " << report.summary();
    }
    ASSERT_NEAR(s.total_mass(), mass0 - world.cleanup_removed_mass_g(), 1e-12 * mass0);
  }
  ASSERT_GE(tears.size(), 3u) << "the pull must tear the sheet";
  // The first tear is where the forceps pull (in the sheet's plane), not at the fixed edges.
  const auto planar = [](const Vec3& p) { return Vec3(p.x(), p.y(), 0.0); };
  EXPECT_LT((planar(tears.front()) - grasp).norm(), 2.0 * kSheetCell) << "first tear at " << tears.front().transpose();
  // The crack grows from there: every later tear lies within two cells of an earlier one or of the
  // grip (a point pull tears the ring around the forceps, on either side of the first tear).
  for (std::size_t i = 1; i < tears.size(); ++i) {
    double nearest = (planar(tears[i]) - grasp).norm();
    for (std::size_t j = 0; j < i; ++j) nearest = std::min(nearest, (planar(tears[i]) - planar(tears[j])).norm());
    EXPECT_LT(nearest, 2.0 * kSheetCell) << "tear " << i << " at " << tears[i].transpose() << " is not at the crack";
  }
  const auto report = check_surface(s, limits);
  EXPECT_TRUE(report.ok()) << report.summary();
}

// Two pinned vertices squeezed to 1 µm apart: plastic creep shortens their spring's rest length
// towards that, step by step. With the hook the cleanup collapses the spring once it is below the
// floor (2 µm); without it (the control) the floor is broken.
TEST(SolverTearing, CreepBelowTheQualityFloorIsCleanedUpAtTheStepBoundary) {
  auto run = [](bool hooked, std::uint32_t& collapsed_vertices) {
    TissueWorld world = free_world();
    SurfaceDescription d = sheet(kSheetW, kSheetH, kSheetCols, kSheetRows);
    d.material.tear_strain = INFINITY;
    d.material.plastic_yield_strain = 0.05;
    d.material.plastic_rate_per_s = 1000.0;  // creeps fully each step beyond the yield
    const std::uint32_t si = world.add_surface(d);
    Surface& s = world.surface(si);
    const std::uint32_t u = 6 * (kSheetCols + 1) + 8, v = u + 1;  // neighbours on a row
    EXPECT_TRUE(s.set_fixed(s.vertex_id(u), true));
    EXPECT_TRUE(s.set_fixed(s.vertex_id(v), true));
    EXPECT_TRUE(s.set_position(s.vertex_id(v), s.position(u) + Vec3(1e-3, 0.0, 0.0)));
    if (hooked) install_clean_topology(world);
    const std::uint32_t live0 = s.vertex_count();
    const ValidityLimits limits = quality_limits();
    bool floor_held = true;
    for (int step = 0; step < 60; ++step) {
      EXPECT_TRUE(world.step(1e-3).ok);
      floor_held = floor_held && check_surface(s, limits).ok();
      const auto plain = check_surface(s);
      EXPECT_TRUE(plain.ok()) << plain.summary();
    }
    collapsed_vertices = live0 - s.vertex_count();
    return floor_held;
  };
  std::uint32_t collapsed_control = 0, collapsed = 0;
  EXPECT_FALSE(run(false, collapsed_control)) << "the scenario must creep below the floor";
  EXPECT_EQ(collapsed_control, 0u);
  EXPECT_TRUE(run(true, collapsed)) << "the hook must keep the floor after every step";
  EXPECT_GE(collapsed, 1u);
}

TEST(SolverTearing, TheBuildersInstallTheHookOnEverySurface) {
  RetinaCapOptions o;
  o.retina_vertices = 2000;
  o.membrane = true;
  RetinaCapScene scene = build_retina_cap(o);
  for (std::uint32_t s = 0; s < scene.world.surface_count(); ++s) EXPECT_NE(scene.world.topology_hook(s), nullptr);
}
