#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/geometry/revolved_mesh.hpp"
#include "core/tissue/surface.hpp"
#include "core/tissue/surface_validity.hpp"
#include "test_meshes.hpp"

using namespace vitreo::core;

namespace {

SurfaceDescription rect_surface(int cols = 8, int rows = 6) {
  SurfaceDescription d;
  d.mesh = test::rectangle(4.0, 3.0, cols, rows);
  d.contained_by_globe = false;
  return d;
}

}  // namespace

TEST(Surface, MassComesFromRestAreaAndDensity) {
  const Surface s(rect_surface());
  EXPECT_TRUE(check_surface(s).ok()) << check_surface(s).summary();
  const double expected = s.material().areal_density_g_per_mm2() * 4.0 * 3.0;
  EXPECT_NEAR(s.total_mass(), expected, 1e-12 * expected);
  EXPECT_NEAR(s.total_rest_area(), 12.0, 1e-12);
}

TEST(Surface, SpringStiffnessReproducesTheMembraneModulusOnEquilateralTriangles) {
  // An equilateral lattice edge has two triangles of area √3/4 a²: k = E t · (√3/2 a²) / a².
  SurfaceDescription d;
  const double a = 1.0;
  d.mesh.positions = {{0, 0, 0}, {a, 0, 0}, {a / 2, a * std::sqrt(3.0) / 2, 0}, {a / 2, -a * std::sqrt(3.0) / 2, 0}};
  d.mesh.triangles = {{0, 1, 2}, {1, 0, 3}};
  d.contained_by_globe = false;
  const Surface s(d);
  const std::uint32_t e = s.find_edge(0, 1);
  ASSERT_NE(e, kNone);
  EXPECT_NEAR(s.edge_stiffness(e), d.material.membrane_modulus_pa_mm * std::sqrt(3.0) / 2.0, 1e-9);
}

TEST(Surface, TearSplitsAnInteriorSpringAtItsMidpointAndConservesMass) {
  Surface s(rect_surface());
  const double mass0 = s.total_mass();
  const double area0 = s.total_rest_area();
  // An interior horizontal edge in the middle of the sheet.
  const std::uint32_t e = s.find_edge(3 * 9 + 4, 3 * 9 + 5);
  ASSERT_NE(e, kNone);
  const auto [a, b] = s.edge_vertices(e);
  const EdgeId id = s.edge_id(e);
  const Vec3 mid = 0.5 * (s.position(a) + s.position(b));
  const auto tris0 = s.triangle_count();
  const auto r = s.tear_edge(id);
  ASSERT_TRUE(r.status) << r.status.message();
  EXPECT_FALSE(s.is_current(id)) << "the torn spring's handle must go stale";
  EXPECT_EQ(s.triangle_count(), tris0 + 2);
  // The fracture vertices sit exactly at the strained spring's midpoint, one on each side.
  EXPECT_LT((s.position(r.vertex_a_side) - mid).norm(), 1e-12);
  EXPECT_LT((s.position(r.vertex_b_side) - mid).norm(), 1e-12);
  EXPECT_NE(s.find_edge(a, r.vertex_a_side), kNone);
  EXPECT_NE(s.find_edge(r.vertex_b_side, b), kNone);
  EXPECT_EQ(s.find_edge(a, r.vertex_b_side), kNone) << "the two sides must be disconnected at the crack";
  EXPECT_NEAR(s.total_mass(), mass0, 1e-12 * mass0);
  EXPECT_NEAR(s.total_rest_area(), area0, 1e-12 * area0);
  const auto report = check_surface(s);
  EXPECT_TRUE(report.ok()) << report.summary();
}

TEST(Surface, RepeatedTearsKeepTheMeshValidAndTheMassExact) {
  Surface s(rect_surface(12, 10));
  const double mass0 = s.total_mass();
  // Tear a line of springs across the sheet, as a propagating crack would.
  int torn = 0;
  for (int i = 1; i < 12; ++i) {
    const std::uint32_t a = 5 * 13 + static_cast<std::uint32_t>(i);
    const std::uint32_t b = 6 * 13 + static_cast<std::uint32_t>(i);
    const std::uint32_t e = s.find_edge(a, b);
    if (e == kNone) continue;
    ASSERT_TRUE(s.tear_edge(s.edge_id(e)).status);
    ++torn;
    const auto report = check_surface(s);
    ASSERT_TRUE(report.ok()) << "after tear " << torn << ": " << report.summary();
  }
  EXPECT_GE(torn, 10);
  EXPECT_NEAR(s.total_mass(), mass0, 1e-12 * mass0);
}

TEST(Surface, TearingABoundarySpringThatReachesTheBoundaryAgainSeparatesFans) {
  // Tearing the boundary edge of a corner triangle makes its opposite vertex (also on the boundary)
  // a bow-tie unless it is duplicated; the validity checker proves it was.
  Surface s(rect_surface(4, 4));
  const std::uint32_t e = s.find_edge(1, 2);  // bottom boundary
  ASSERT_NE(e, kNone);
  ASSERT_TRUE(s.tear_edge(s.edge_id(e)).status);
  const auto report = check_surface(s);
  EXPECT_TRUE(report.ok()) << report.summary();
}

TEST(Surface, StaleHandlesAreRefusedAndChangeNothing) {
  Surface s(rect_surface());
  const std::uint32_t e = s.find_edge(3 * 9 + 4, 3 * 9 + 5);
  const EdgeId id = s.edge_id(e);
  ASSERT_TRUE(s.tear_edge(id).status);
  const auto edges = s.edge_count();
  const auto again = s.tear_edge(id);
  EXPECT_FALSE(again.status);
  EXPECT_NE(again.status.message().find("stale"), std::string::npos);
  EXPECT_EQ(s.edge_count(), edges);
  EXPECT_FALSE(s.set_position(VertexId{9999, 0}, Vec3::Zero()));
}

TEST(Surface, RunTimeSettersRejectNonFiniteAndOutOfRangeValues) {
  Surface s(rect_surface());
  const VertexId v = s.vertex_id(10);
  EXPECT_FALSE(s.set_position(v, Vec3(std::nan(""), 0, 0)));
  EXPECT_FALSE(s.set_velocity(v, Vec3(INFINITY, 0, 0)));
  EXPECT_FALSE(s.set_surface_traction(std::nan("")));
  EXPECT_FALSE(s.set_surface_traction(0.01));
  EXPECT_TRUE(s.set_surface_traction(0.8));
  EXPECT_NEAR(s.edge_rest_length(0), 0.8 * (s.rest_position(s.edge_vertices(0)[1]) - s.rest_position(s.edge_vertices(0)[0])).norm(), 1e-12);
}

TEST(Surface, ConstructionRejectsBadGeometryAndMaterials) {
  SurfaceDescription d = rect_surface();
  d.mesh.positions[3].x() = std::nan("");
  EXPECT_THROW(Surface{d}, InvalidArgument);
  d = rect_surface();
  d.mesh.triangles.push_back({0, 0, 1});
  EXPECT_THROW(Surface{d}, InvalidArgument);
  d = rect_surface();
  d.mesh.triangles.push_back(d.mesh.triangles[0]);  // third triangle on one edge
  d.mesh.triangles.push_back(d.mesh.triangles[0]);
  EXPECT_THROW(Surface{d}, InvalidArgument);
  d = rect_surface();
  d.material.membrane_modulus_pa_mm = -1.0;
  EXPECT_THROW(Surface{d}, InvalidArgument);
  d = rect_surface();
  d.material.density_g_per_mm3 = std::nan("");
  EXPECT_THROW(Surface{d}, InvalidArgument);
}

TEST(Surface, PoolsNeverGrowAfterConstruction) {
  SurfaceDescription d = rect_surface(4, 4);
  d.capacity.growth_fraction = 0.0;
  d.capacity.minimum_extra = 4;
  Surface s(d);
  const auto cap = s.vertex_capacity();
  int refused = 0;
  for (int i = 0; i < 200; ++i) {
    // Keep tearing any live interior spring until the pools refuse.
    bool did = false;
    for (std::uint32_t e = 0; e < s.edge_slots() && !did; ++e) {
      if (!s.edge_alive(e)) continue;
      const auto r = s.tear_edge(s.edge_id(e));
      if (r.status) {
        did = true;
      } else {
        ++refused;
        EXPECT_NE(r.status.message().find("pool full"), std::string::npos) << r.status.message();
        break;
      }
    }
    if (!did) break;
  }
  EXPECT_GT(refused, 0);
  EXPECT_EQ(s.vertex_capacity(), cap);
  EXPECT_TRUE(check_surface(s).ok()) << check_surface(s).summary();
}
