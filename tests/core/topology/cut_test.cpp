// Swept-blade cutting: every intersection case, geometric accuracy (Hausdorff distance between the
// swept path's intersection with the sheet and the new boundary), exact mass, rest vectors
// consistent with the undeformed sheet, the sideways blade and scissors, refusals.
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <cmath>
#include <numbers>

#include "core/tissue/surface_validity.hpp"
#include "core/topology/blade_tools.hpp"
#include "core/topology/cut.hpp"
#include "topology_test_util.hpp"

using namespace vitreo::core;
using namespace vitreo::core::test;

namespace {


// A vertical blade (along z) through the sheet at xy.
BladeEdge vertical(double x, double y) { return {Vec3(x, y, -0.5), Vec3(x, y, 0.5)}; }

// Hausdorff distance between a path on the sheet (its part inside the sheet) and the new boundary.
double hausdorff(const Surface& s, const std::vector<Vec3>& path) {
  const auto boundary = new_boundary(s, kSheetW, kSheetH);
  if (boundary.empty()) return INFINITY;
  double d = 0.0;
  for (const auto& seg : boundary) {
    for (double f : {0.0, 0.25, 0.5, 0.75, 1.0}) d = std::max(d, distance_point_polyline(seg.a + f * (seg.b - seg.a), path));
  }
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    for (int k = 0; k <= 20; ++k) {
      const Vec3 p = path[i] + (k / 20.0) * (path[i + 1] - path[i]);
      if (p.x() <= 1e-9 || p.y() <= 1e-9 || p.x() >= kSheetW - 1e-9 || p.y() >= kSheetH - 1e-9) continue;
      d = std::max(d, distance_point_segments(p, boundary));
    }
  }
  return d;
}

struct Fixture {
  Surface s;
  Cutter cutter;
  double mass0, area0;
  explicit Fixture(double jitter = 0.0, unsigned seed = 1)
      : s(sheet(kSheetW, kSheetH, kSheetCols, kSheetRows, jitter, seed)), cutter(s), mass0(s.total_mass()), area0(s.total_rest_area()) {}
  void expect_valid_and_exact(const char* what) {
    const auto report = check_surface(s, ValidityLimits{});
    EXPECT_TRUE(report.ok()) << what << ": " << report.summary();
    EXPECT_NEAR(s.total_mass(), mass0, 1e-12 * mass0) << what;
    EXPECT_NEAR(s.total_rest_area(), area0, 1e-12 * area0) << what;
    EXPECT_LT(max_rest_vector_error(s), 1e-12) << what << ": rest vectors must match the undeformed sheet";
  }
};

}  // namespace

TEST(Cut, AStraightStrokeAcrossTheSheetSplitsItExactlyAlongThePath) {
  Fixture f(0.3, 3);
  // Oblique, so it crosses springs at arbitrary parameters (edge–edge cases).
  const Vec3 a(-0.3, 0.7, 0.0), b(kSheetW + 0.3, 2.2, 0.0);
  const auto r = f.cutter.sweep(vertical(a.x(), a.y()), vertical(b.x(), b.y()));
  ASSERT_TRUE(r.status) << r.status.message();
  EXPECT_GT(r.springs_split + r.snapped, 15u);
  EXPECT_GT(r.springs_opened, 15u);
  f.expect_valid_and_exact("straight");
  EXPECT_EQ(components(f.s), 2u) << "a stroke across the whole sheet must part it";
  EXPECT_LE(hausdorff(f.s, {a, b}), 0.1 * kSheetCell);
}

TEST(Cut, APartialStrokeEndsInsideTrianglesAndKeepsTheSheetWhole) {
  Fixture f(0.3, 5);
  const Vec3 a(1.03, 1.11, 0.0), b(2.91, 1.87, 0.0);
  const auto r = f.cutter.sweep(vertical(a.x(), a.y()), vertical(b.x(), b.y()));
  ASSERT_TRUE(r.status) << r.status.message();
  EXPECT_EQ(r.end_points, 2u) << "the blade at its start and end poses each leave a cut end inside the sheet";
  f.expect_valid_and_exact("partial");
  EXPECT_EQ(components(f.s), 1u);
  EXPECT_LE(hausdorff(f.s, {a, b}), 0.1 * kSheetCell);
}

TEST(Cut, AStrokeWhollyInsideOneTriangleOpensASlit) {
  Fixture f;
  // Cell (5, 4) spans x 1.25..1.5, y 1.0..1.25; pick a short stroke near the centre of a triangle.
  const Vec3 a(1.40, 1.05, 0.0), b(1.45, 1.09, 0.0);
  const auto tris0 = f.s.triangle_count();
  const auto r = f.cutter.sweep(vertical(a.x(), a.y()), vertical(b.x(), b.y()));
  ASSERT_TRUE(r.status) << r.status.message();
  EXPECT_EQ(r.end_points, 2u);
  EXPECT_GT(f.s.triangle_count(), tris0);
  EXPECT_GE(r.springs_opened, 2u);
  f.expect_valid_and_exact("inside one triangle");
  EXPECT_LE(hausdorff(f.s, {a, b}), 0.1 * kSheetCell);
}

TEST(Cut, VertexToVertexAlongGridLinesGrazesExistingSprings) {
  Fixture f;
  // Along y = 1.5 (a row of grid vertices): no spring is crossed, the springs along it are opened.
  const Vec3 a(-0.2, 1.5, 0.0), b(kSheetW + 0.2, 1.5, 0.0);
  const auto verts0 = f.s.vertex_count();
  const auto r = f.cutter.sweep(vertical(a.x(), a.y()), vertical(b.x(), b.y()));
  ASSERT_TRUE(r.status) << r.status.message();
  EXPECT_EQ(r.springs_split, 0u);
  EXPECT_EQ(r.springs_opened, static_cast<std::uint32_t>(kSheetCols));
  EXPECT_EQ(f.s.vertex_count(), verts0 + kSheetCols + 1) << "each vertex on the line gets a copy";
  f.expect_valid_and_exact("grazing");
  EXPECT_EQ(components(f.s), 2u);
  EXPECT_LE(hausdorff(f.s, {a, b}), 1e-9);
}

TEST(Cut, EdgeVertexAndVertexInteriorCasesStayAccurate) {
  Fixture f;
  // The diagonal from (0, 0) through grid vertices (i, i) crosses every other cell's diagonal
  // spring at a vertex and the others' springs at their middles.
  const Vec3 a(0.5, 0.5, 0.0), b(2.125, 2.375, 0.0);  // starts at a vertex, ends inside a triangle
  const auto r = f.cutter.sweep(vertical(a.x(), a.y()), vertical(b.x(), b.y()));
  ASSERT_TRUE(r.status) << r.status.message();
  f.expect_valid_and_exact("edge-vertex");
  EXPECT_EQ(components(f.s), 1u);
  EXPECT_LE(hausdorff(f.s, {a, b}), 0.1 * kSheetCell);
}

TEST(Cut, ACurvedStrokeInManySmallSweepsFollowsTheArc) {
  Fixture f(0.25, 9);
  std::vector<Vec3> path;
  const Vec3 c(2.0, -0.5, 0.0);
  const double radius = 2.6;
  for (int i = 0; i <= 24; ++i) {
    const double ang = std::numbers::pi * (0.25 + 0.5 * i / 24.0);
    path.emplace_back(c + radius * Vec3(std::cos(ang), std::sin(ang), 0.0));
  }
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    const auto r = f.cutter.sweep(vertical(path[i].x(), path[i].y()), vertical(path[i + 1].x(), path[i + 1].y()));
    ASSERT_TRUE(r.status) << r.status.message();
    const auto report = check_surface(f.s);
    ASSERT_TRUE(report.ok()) << "after sweep " << i << ": " << report.summary();
  }
  f.expect_valid_and_exact("curved");
  EXPECT_LE(hausdorff(f.s, path), 0.1 * kSheetCell);
}

TEST(Cut, ABladeDippingIntoTheSheetCutsOnlyWhereItPassesThrough) {
  Fixture f;
  // The blade's lower end goes below the sheet only over x in [1, 3]: the cut ends where its
  // path crosses the sheet (a cut end made by the path of the blade's end, not by its pose).
  const BladeEdge from{Vec3(0.5, 1.6, 0.25), Vec3(0.5, 1.6, 1.0)};
  const BladeEdge to{Vec3(3.5, 1.6, -0.25), Vec3(3.5, 1.6, 1.0)};
  const auto r = f.cutter.sweep(from, to);
  ASSERT_TRUE(r.status) << r.status.message();
  f.expect_valid_and_exact("dipping");
  EXPECT_EQ(components(f.s), 1u);
  EXPECT_LE(hausdorff(f.s, {Vec3(2.0, 1.6, 0.0), Vec3(3.5, 1.6, 0.0)}), 0.1 * kSheetCell);
}

TEST(Cut, NothingSnapsFartherThanTheDocumentedTolerance) {
  Fixture f(0.3, 11);
  const Vec3 a(-0.2, 0.4, 0.0), b(kSheetW + 0.2, 2.6, 0.0);
  ASSERT_TRUE(f.cutter.sweep(vertical(a.x(), a.y()), vertical(b.x(), b.y())).status);
  // Every vertex of the new boundary lies on the path within max(band, snap_fraction × cell
  // diagonal) (the jittered cells' springs are at most ~1.6 cells long).
  const double tol = f.cutter.settings().snap_fraction * 1.6 * std::sqrt(2.0) * kSheetCell;
  for (const auto& seg : new_boundary(f.s, kSheetW, kSheetH)) {
    EXPECT_LE(distance_point_polyline(seg.a, {a, b}), tol);
    EXPECT_LE(distance_point_polyline(seg.b, {a, b}), tol);
  }
}

TEST(Cut, RepeatedCrossingStrokesKeepTheMeshValid) {
  Fixture f(0.3, 13);
  for (int i = 0; i < 6; ++i) {
    const double y = 0.4 + 0.45 * i;
    ASSERT_TRUE(f.cutter.sweep(vertical(0.3, y), vertical(3.7, 3.0 - y)).status);
    const auto report = check_surface(f.s);
    ASSERT_TRUE(report.ok()) << "stroke " << i << ": " << report.summary();
  }
  f.expect_valid_and_exact("crossing strokes");
}

TEST(Cut, InvalidRequestsAreRefusedAndChangeNothing) {
  Fixture f;
  const auto version = f.s.topology_version();
  const auto nan = std::nan("");
  auto r = f.cutter.sweep(vertical(nan, 1.0), vertical(2.0, 1.0));
  EXPECT_FALSE(r.status);
  EXPECT_NE(r.status.message().find("non-finite"), std::string::npos);
  r = f.cutter.sweep({Vec3(1, 1, 0), Vec3(1, 1, 0)}, vertical(2.0, 1.0));
  EXPECT_FALSE(r.status);
  EXPECT_NE(r.status.message().find("degenerate blade"), std::string::npos);
  r = f.cutter.sweep(vertical(1.0, 1.0), vertical(1.0, 1.0));
  EXPECT_FALSE(r.status);
  EXPECT_NE(r.status.message().find("degenerate sweep"), std::string::npos);
  EXPECT_EQ(f.s.topology_version(), version);

  // Cutting a removed handle.
  const std::uint32_t e = f.s.find_edge(20, 21);
  const EdgeId id = f.s.edge_id(e);
  ASSERT_TRUE(f.s.split_edge(id, 0.5).status);
  const auto v2 = f.s.topology_version();
  EXPECT_FALSE(f.s.split_edge(id, 0.5).status);
  EXPECT_FALSE(f.s.disconnect_edge(id).status);
  EXPECT_FALSE(f.s.split_edge(f.s.edge_id(f.s.find_edge(30, 31)), 1.0).status);
  EXPECT_FALSE(f.s.split_triangle(TriangleId{0, 99}, {0.3, 0.3, 0.4}).status);
  EXPECT_FALSE(f.s.remove_triangle(TriangleId{0, 99}).status);
  EXPECT_EQ(f.s.topology_version(), v2);
  // A blade that misses the tissue changes nothing either.
  ASSERT_TRUE(f.cutter.sweep({Vec3(1, 1, 1), Vec3(1, 1, 2)}, {Vec3(2, 1, 1), Vec3(2, 1, 2)}).status);
  EXPECT_EQ(f.s.topology_version(), v2);
}

TEST(Cut, FullPoolsAreRefusedBeforeAnythingChanges) {
  SurfaceDescription d = sheet(kSheetW, kSheetH, kSheetCols, kSheetRows);
  d.capacity.growth_fraction = 0.0;
  d.capacity.minimum_extra = 4;
  Surface s(d);
  Cutter cutter(s);
  const auto version = s.topology_version();
  const auto r = cutter.sweep(vertical(-0.2, 0.7), vertical(kSheetW + 0.2, 2.3));
  EXPECT_FALSE(r.status);
  EXPECT_NE(r.status.message().find("pools full"), std::string::npos);
  EXPECT_EQ(s.topology_version(), version);
}

TEST(SidewaysBlade, CutsInStrokesAlongItsTipPath) {
  Fixture f(0.2, 17);
  SidewaysBlade blade(f.cutter, 0.4, 0.3);
  std::uint32_t strokes = 0;
  // The edge hangs down through the sheet from 0.2 mm above it.
  const Vec3 down(0, 0, -1);
  for (int i = 0; i <= 40; ++i) {
    const Vec3 tip(0.8 + 2.4 * i / 40.0, 1.3, 0.2);
    const auto r = blade.move_to(tip, down);
    ASSERT_TRUE(r.status) << r.status.message();
    if (r.springs_opened > 0) ++strokes;
  }
  ASSERT_TRUE(blade.end_stroke().status);
  EXPECT_GE(strokes, 6u);
  f.expect_valid_and_exact("sideways blade");
  EXPECT_EQ(components(f.s), 1u);
  EXPECT_LE(hausdorff(f.s, {Vec3(0.8, 1.3, 0), Vec3(3.2, 1.3, 0)}), 0.1 * kSheetCell);
  EXPECT_FALSE(blade.move_to(Vec3(std::nan(""), 0, 0), down).status);
}

TEST(Scissors, CutBetweenTheBladesAsTheyClose) {
  Fixture f(0.2, 19);
  Scissors scissors(f.cutter, 1.5);
  // Pivot beside the sheet's left edge, blades in the plane y = 1.5... i.e. the blade plane is
  // spanned by the bisector (+x) and z: the tissue (z = 0) between the blades is cut along y = 1.45.
  const Vec3 pivot(-0.1, 1.45, 0.0), bisector(1, 0, 0), normal(0, 1, 0);
  double opening = 0.8;
  ASSERT_TRUE(scissors.set_pose(pivot, bisector, normal, opening).status);
  const auto verts0 = f.s.vertex_count();
  while (opening > 0.0) {
    opening = std::max(0.0, opening - 0.1);
    const auto r = scissors.set_pose(pivot, bisector, normal, opening);
    ASSERT_TRUE(r.status) << r.status.message();
    const auto report = check_surface(f.s);
    ASSERT_TRUE(report.ok()) << report.summary();
  }
  EXPECT_GT(f.s.vertex_count(), verts0);
  f.expect_valid_and_exact("scissors");
  EXPECT_LE(hausdorff(f.s, {Vec3(0, 1.45, 0), Vec3(1.4, 1.45, 0)}), 0.1 * kSheetCell);
  // Opening again cuts nothing.
  const auto version = f.s.topology_version();
  ASSERT_TRUE(scissors.set_pose(pivot, bisector, normal, 0.8).status);
  EXPECT_EQ(f.s.topology_version(), version);
}

// Real-time: once the cutter exists, strokes that take fresh pool slots (new vertices, springs,
// triangles) take no page faults: the pools and scratch were written at construction
// (core/common/prefault.hpp). Before, each stroke here took tens of first-touch faults (~10 µs each).
TEST(Cut, StrokesTakeNoPageFaults) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer maps its shadow memory on first touch";
#endif
  auto minor_faults = [] {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return u.ru_minflt;
  };
  Surface s(sheet(12.0, 12.0, 96, 96));
  Cutter cutter(s);
  const std::uint32_t slots0 = s.vertex_slots();
  auto stroke = [&](int i) {
    const double x = 0.37 + 0.61 * i;
    return cutter.sweep(vertical(x, 0.4), vertical(x + 0.2, 11.6));
  };
  ASSERT_TRUE(stroke(0).status);  // the first call may touch the code's own pages
  const long before = minor_faults();
  for (int i = 1; i < 18; ++i) ASSERT_TRUE(stroke(i).status);
  const long after = minor_faults();
  EXPECT_GT(s.vertex_slots(), slots0 + 17 * 100u);  // the strokes took many fresh slots
  EXPECT_EQ(after - before, 0) << "page faults during 17 strokes";
}
