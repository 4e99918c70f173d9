// Vitrector removal (clipped at the removal hemisphere, exact mass, gated by the cut rate),
// attraction, and tearing that starts at the most strained spring.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "core/tissue/surface_validity.hpp"
#include "core/tissue/tissue_world.hpp"
#include "core/topology/tear.hpp"
#include "core/topology/vitrector.hpp"
#include "topology_test_util.hpp"

using namespace vitreo::core;
using namespace vitreo::core::test;

TEST(Vitrector, RemovesWhatEntersTheRemovalHemisphereClippedAtItsBoundary) {
  Surface s(sheet(kSheetW, kSheetH, kSheetCols, kSheetRows, 0.3, 21));
  const double mass0 = s.total_mass(), area0 = s.total_rest_area();
  VitrectorSettings vs;
  vs.removal_radius_mm = 0.6;
  Vitrector vit(s, vs);
  // Port 0.2 mm above the sheet, sucking down: the sheet inside a disc of radius √(0.6² − 0.2²).
  const Vec3 port(2.03, 1.47, 0.2);
  ASSERT_TRUE(vit.set_pose(port, Vec3(0, 0, -1)));
  const auto r = vit.cut_now();
  ASSERT_TRUE(r.status) << r.status.message();
  EXPECT_TRUE(r.cut);
  EXPECT_GT(r.triangles_removed, 10u);
  const double disc = std::numbers::pi * (0.6 * 0.6 - 0.2 * 0.2);
  // Clipped at the sphere: the removed area is the disc up to the inscribed polygon's deficit.
  EXPECT_NEAR(r.removed_area_mm2, disc, 0.06 * disc);
  EXPECT_NEAR(s.total_rest_area(), area0 - r.removed_area_mm2, 1e-12 * area0);
  EXPECT_NEAR(s.total_mass(), mass0 - r.removed_mass_g, 1e-12 * mass0);
  EXPECT_NEAR(r.removed_mass_g, s.material().areal_density_g_per_mm2() * r.removed_area_mm2, 1e-12 * mass0);
  const auto report = check_surface(s, ValidityLimits{});
  EXPECT_TRUE(report.ok()) << report.summary();
  // Nothing remains inside; the new boundary lies on the clip circle within the snap tolerance.
  const double rho = std::sqrt(0.6 * 0.6 - 0.2 * 0.2);
  for (std::uint32_t t = 0; t < s.triangle_slots(); ++t) {
    if (!s.triangle_alive(t)) continue;
    const auto tv = s.triangle_vertices(t);
    const Vec3 c = (s.position(tv[0]) + s.position(tv[1]) + s.position(tv[2])) / 3.0;
    EXPECT_GT((c - port).norm(), 0.6 - 1e-9);
  }
  for (const auto& seg : new_boundary(s, kSheetW, kSheetH)) {
    const double ra = (seg.a - Vec3(port.x(), port.y(), 0)).norm();
    EXPECT_NEAR(ra, rho, 0.05 * 1.6 * std::sqrt(2.0) * kSheetCell + 1e-9);
  }
}

// The gel's model: aspirated as a volume (rest area × the material's thickness) at the flow rate,
// whole triangles, nearest to the port first, within the suction field's hemisphere.
SurfaceDescription gel_sheet() {
  SurfaceDescription d = sheet(12.0, 12.0, 30, 30, 0.2, 5);
  d.material.thickness_mm = 2.5;  // a gel shell stands for a 2.5 mm layer
  return d;
}
struct AspirationSheet {
  Surface s{gel_sheet()};
  double thickness = s.material().thickness_mm;
  // Rest area of the live triangles whose (current) centroid is within `r` of p.
  double area_within(const Vec3& p, double r) const {
    double a = 0.0;
    for (std::uint32_t t = 0; t < s.triangle_slots(); ++t) {
      if (!s.triangle_alive(t)) continue;
      const auto tv = s.triangle_vertices(t);
      if (((s.position(tv[0]) + s.position(tv[1]) + s.position(tv[2])) / 3.0 - p).norm() <= r) a += s.triangle_rest_area(t);
    }
    return a;
  }
};

TEST(VitrectorAspiration, TakesTheGelAtTheFlowRateNearestFirstAndOnlyInTheField) {
  AspirationSheet g;
  const double area0 = g.s.total_rest_area(), mass0 = g.s.total_mass();
  VitrectorSettings vs;  // the rig's: 1.5 mm field, 25 mm³/s at full vacuum, 7500 cpm
  Vitrector vit(g.s, vs, RemovalModel::kAspirate);
  const Vec3 port(6.0, 6.0, 0.3);  // 0.3 mm above the sheet's middle, sucking down
  ASSERT_TRUE(vit.set_pose(port, Vec3(0, 0, -1)));
  ASSERT_TRUE(vit.set_cut_rate(vs.cut_rate_cpm));
  ASSERT_TRUE(vit.set_vacuum(1.0));
  const double in_field0 = g.area_within(port, vs.field_radius_mm);
  // 0.2 s: 5 mm³ aspirated, 2 mm² of a 2.5 mm-thick sheet; the field holds more than that.
  double removed = 0.0;
  for (int k = 0; k < 200; ++k) {
    const auto r = vit.apply(1e-3);
    ASSERT_TRUE(r.status) << r.status.message();
    removed += r.removed_area_mm2;
  }
  const double expected = vs.gel_flow_mm3_per_s * 0.2 / g.thickness;
  ASSERT_GT(in_field0, 2.0 * expected);
  // Whole triangles: what was paid for, less at most the one triangle the next bite pays for.
  const double largest = 2.0 * (12.0 / 30) * (12.0 / 30);  // a jittered cell's triangle, generously
  EXPECT_LE(removed, expected + 1e-9);
  EXPECT_GE(removed, expected - largest);
  EXPECT_NEAR(g.s.total_rest_area(), area0 - removed, 1e-9 * area0);
  EXPECT_LT(g.s.total_mass(), mass0);
  // Nearest first: the sheet around the port's foot is gone, the field's rim is untouched.
  EXPECT_NEAR(g.area_within(Vec3(6.0, 6.0, 0.0), 0.5), 0.0, 1e-12);
  const double rim0 = AspirationSheet().area_within(Vec3(6.0, 6.0, 0.0), 1.45) - AspirationSheet().area_within(Vec3(6.0, 6.0, 0.0), 1.2);
  EXPECT_NEAR(g.area_within(Vec3(6.0, 6.0, 0.0), 1.45) - g.area_within(Vec3(6.0, 6.0, 0.0), 1.2), rim0, 1e-9);
  // Nothing outside the field, ever: after 5 s everything within reach is gone and no more.
  for (int k = 0; k < 5000; ++k) ASSERT_TRUE(vit.apply(1e-3).status);
  EXPECT_NEAR(g.area_within(port, vs.field_radius_mm), 0.0, 1e-12);
  EXPECT_NEAR(g.s.total_rest_area(), area0 - in_field0, 1e-9 * area0);
  const auto report = check_surface(g.s, ValidityLimits{});
  EXPECT_TRUE(report.ok()) << report.summary();
}

TEST(VitrectorAspiration, FlowFollowsTheVacuumStopsWithTheCutterAndDoesNotAccrueWithoutGel) {
  const Vec3 port(6.0, 6.0, 0.3), away(6.0, 6.0, 5.0);
  auto removed_in = [&](double vacuum, double cut_rate, double seconds, bool start_away) {
    AspirationSheet g;
    VitrectorSettings vs;
    Vitrector vit(g.s, vs, RemovalModel::kAspirate);
    EXPECT_TRUE(vit.set_vacuum(vacuum));
    EXPECT_TRUE(vit.set_cut_rate(cut_rate));
    if (start_away) {  // a second of vacuum in fluid, away from the gel
      EXPECT_TRUE(vit.set_pose(away, Vec3(0, 0, 1)));
      for (int k = 0; k < 1000; ++k) EXPECT_TRUE(vit.apply(1e-3).status);
    }
    EXPECT_TRUE(vit.set_pose(port, Vec3(0, 0, -1)));
    double removed = 0.0;
    for (int k = 0; k < static_cast<int>(seconds * 1000); ++k) removed += vit.apply(1e-3).removed_area_mm2;
    return removed;
  };
  const double thickness = AspirationSheet().thickness, flow = VitrectorSettings{}.gel_flow_mm3_per_s;
  const double full = removed_in(1.0, 7500.0, 0.1, false), half = removed_in(0.5, 7500.0, 0.2, false);
  EXPECT_NEAR(full, flow * 0.1 / thickness, 0.15);  // 1 mm², in triangles of 0.08 mm²
  EXPECT_NEAR(half, full, 0.15);  // half the vacuum: the same gel in twice the time
  EXPECT_EQ(removed_in(1.0, 0.0, 0.5, false), 0.0);  // uncut gel plugs the port
  // Vacuum in fluid aspirates fluid: arriving at the gel, the first bite is one cut's worth, not a second's.
  EXPECT_LT(removed_in(1.0, 7500.0, 0.01, true), flow * 0.01 / thickness + 0.2);
  AspirationSheet g;
  EXPECT_FALSE(Vitrector(g.s, VitrectorSettings{}, RemovalModel::kAspirate).set_vacuum(1.5));
}

// Suction is the solver's (a SuctionField, as the instruments hand it over); the vitrector cuts what
// it draws into the port, at the cut rate.
TEST(Vitrector, CutsOnlyAtTheCutRateWhatTheSuctionDrawsIn) {
  SurfaceDescription d = sheet(kSheetW, kSheetH, kSheetCols, kSheetRows);
  Environment env;
  env.apply_pressure = false;
  env.gravity_mm_s2 = Vec3::Zero();
  TissueWorld world(GlobeWall::sphere(Vec3::Zero(), 1e6), env);
  const auto si = world.add_surface(d);
  Surface& s = world.surface(si);
  for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) {
    const Vec3 p = s.rest_position(v);
    if (p.x() == 0.0 || p.x() == kSheetW) {
      ASSERT_TRUE(s.set_fixed(s.vertex_id(v), true));
    }
  }
  VitrectorSettings vs;
  Vitrector vit(s, vs);
  const Vec3 port(2.0, 1.5, 0.3);
  ASSERT_TRUE(vit.set_pose(port, Vec3(0, 0, -1)));
  ASSERT_TRUE(world.set_suction_fields(std::vector<SuctionField>{{port, Vec3(0, 0, -1), vs.field_radius_mm, 0.8 * vs.suction_pa}}));
  ASSERT_TRUE(vit.set_cut_rate(0.0));
  const double mass0 = s.total_mass();
  // Suction only: tissue under the port rises toward it, nothing is removed.
  const std::uint32_t centre = 6 * (kSheetCols + 1) + 8;
  for (int i = 0; i < 200; ++i) {
    const auto r = vit.apply(1e-3);
    ASSERT_TRUE(r.status) << r.status.message();
    ASSERT_FALSE(r.cut);
    ASSERT_TRUE(world.step(1e-3).ok);
  }
  EXPECT_GT(s.position(centre).z(), 0.02) << "suction must lift the tissue toward the port";
  // Suction acts only in front of the port: tissue that its momentum carries past the opening's
  // plane is in the port (where the next cut takes it), at most a fraction of the port's radius.
  EXPECT_LT(s.position(centre).z(), 0.3 + 0.05);
  EXPECT_EQ(s.total_mass(), mass0);
  // 6000 cuts per minute at 1 ms steps: one cut every 10 steps; removal until the hole is made.
  ASSERT_TRUE(vit.set_cut_rate(6000.0));
  int cuts = 0;
  double removed = 0.0;
  for (int i = 0; i < 400; ++i) {
    const auto r = vit.apply(1e-3);
    ASSERT_TRUE(r.status) << r.status.message();
    cuts += r.cut ? 1 : 0;
    removed += r.removed_mass_g;
    ASSERT_TRUE(world.step(1e-3).ok);
    if (r.cut) {
      const auto report = check_surface(s);
      ASSERT_TRUE(report.ok()) << report.summary();
    }
  }
  EXPECT_NEAR(cuts, 40, 1);
  EXPECT_GT(removed, 0.0);
  EXPECT_NEAR(s.total_mass(), mass0 - removed, 1e-12 * mass0);
  EXPECT_NEAR(vit.total_removed_mass_g(), removed, 1e-15);
  for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) {
    if (!s.vertex_alive(v)) continue;
    ASSERT_TRUE(std::isfinite(s.position(v).norm()));
    EXPECT_LT(s.velocity(v).norm(), 1e3) << "small pieces must not explode";
  }
}

TEST(Vitrector, InvalidRequestsAreRefused) {
  Surface s(sheet(kSheetW, kSheetH, kSheetCols, kSheetRows));
  Vitrector vit(s);
  EXPECT_FALSE(vit.apply(1e-3).status) << "no pose yet";
  EXPECT_FALSE(vit.set_pose(Vec3(std::nan(""), 0, 0), Vec3::UnitZ()));
  EXPECT_FALSE(vit.set_pose(Vec3::Zero(), Vec3::Zero()));
  EXPECT_FALSE(vit.set_cut_rate(-1.0));
  EXPECT_FALSE(vit.set_cut_rate(1e6));
  EXPECT_FALSE(vit.set_cut_rate(std::nan("")));
  ASSERT_TRUE(vit.set_pose(Vec3(1, 1, 1), Vec3(0, 0, -1)));
  // Refused requests change nothing: no pose or cut rate is taken, the sheet is untouched.
  ASSERT_TRUE(vit.set_cut_rate(6000.0));
  const auto version = s.topology_version();
  const double mass = s.total_mass();
  std::vector<Vec3> x, v;
  for (std::uint32_t i = 0; i < s.vertex_slots(); ++i) {
    x.push_back(s.position(i));
    v.push_back(s.velocity(i));
  }
  EXPECT_FALSE(vit.apply(0.0).status);
  EXPECT_FALSE(vit.apply(INFINITY).status);
  EXPECT_FALSE(vit.apply(std::nan("")).status);
  EXPECT_FALSE(vit.set_pose(Vec3(1, 1, INFINITY), Vec3(0, 0, -1)));
  EXPECT_EQ(vit.port(), Vec3(1, 1, 1));
  EXPECT_EQ(s.topology_version(), version);
  EXPECT_EQ(s.total_mass(), mass);
  for (std::uint32_t i = 0; i < s.vertex_slots(); ++i) {
    EXPECT_EQ(s.position(i), x[i]);
    EXPECT_EQ(s.velocity(i), v[i]);
  }
  // Tearing: a stale handle, a split parameter out of range, a line spring: refused, nothing changes.
  const EdgeId e = s.edge_id(s.find_edge(20, 21));
  TearSettings bad;
  bad.at = 0.99;
  EXPECT_FALSE(tear_spring(s, e, bad).status);
  EXPECT_FALSE(tear_spring(s, EdgeId{e.index, e.generation + 1}).status);
  EXPECT_EQ(s.topology_version(), version);
  EXPECT_EQ(s.total_mass(), mass);
}

TEST(Tear, ACrackOpensAtTheStrainedSpringAndEndsInsideTheAdjacentTriangles) {
  Surface s(sheet(kSheetW, kSheetH, kSheetCols, kSheetRows));
  const double mass0 = s.total_mass();
  const std::uint32_t a = 6 * (kSheetCols + 1) + 8, b = a + 1;
  const std::uint32_t e = s.find_edge(a, b);
  ASSERT_NE(e, kNone);
  const Vec3 mid = 0.5 * (s.position(a) + s.position(b));
  const EdgeId id = s.edge_id(e);
  const auto r = tear_spring(s, id);
  ASSERT_TRUE(r.status) << r.status.message();
  EXPECT_EQ(r.vertices_added, 4u) << "split point, its copy, and two crack tips";
  const auto report = check_surface(s, ValidityLimits{});
  EXPECT_TRUE(report.ok()) << report.summary();
  EXPECT_NEAR(s.total_mass(), mass0, 1e-12 * mass0);
  EXPECT_LT(max_rest_vector_error(s), 1e-12);
  // The new boundary: from the split point half way to each opposite vertex, no farther.
  const auto boundary = new_boundary(s, kSheetW, kSheetH);
  ASSERT_EQ(boundary.size(), 4u);
  for (const auto& seg : boundary) {
    // Half way to an opposite vertex of the (right-angled) cells: at most half the cell diagonal.
    EXPECT_LE((seg.a - mid).norm(), 0.5 * std::sqrt(1.25) * kSheetCell + 1e-9);
    EXPECT_LE((seg.b - mid).norm(), 0.5 * std::sqrt(1.25) * kSheetCell + 1e-9);
  }
  EXPECT_FALSE(tear_spring(s, id).status) << "the torn spring's handle is stale";
}

TEST(Tear, PropagatesFromTheMostStrainedSpringWhereThePullIs) {
  Surface s(sheet(kSheetW, kSheetH, kSheetCols, kSheetRows));
  // Pull a column of vertices near the middle sideways: the springs next to them strain most.
  const std::uint32_t pulled = 6 * (kSheetCols + 1) + 8;
  for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) {
    const Vec3 p = s.rest_position(v);
    if (p.x() > 2.0 + 1e-9) {
      ASSERT_TRUE(s.set_position(s.vertex_id(v), p + Vec3(0.05, 0.0, 0.0)));
    }
  }
  ASSERT_TRUE(s.set_position(s.vertex_id(pulled), s.rest_position(pulled) + Vec3(0.0, 0.0, 0.2)));
  const auto torn = propagate_tears(s, 0.15, 5);
  EXPECT_GE(torn, 1u);
  const auto report = check_surface(s);
  EXPECT_TRUE(report.ok()) << report.summary();
  // The first tear is at the pulled vertex.
  bool near_pull = false;
  for (const auto& seg : new_boundary(s, kSheetW, kSheetH)) near_pull = near_pull || (seg.a - s.rest_position(pulled)).norm() < 1.01 * kSheetCell;
  EXPECT_TRUE(near_pull);
}
