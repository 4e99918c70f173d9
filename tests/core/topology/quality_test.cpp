// The mesh cleanup (core/topology/quality.hpp) and the primitives it is built on
// (Surface::collapse_edge, Surface::dissolve_triangle): mass and rest area exact, rest vectors still
// equal to the rest-position differences, handles of everything not removed unchanged, the rules
// for fixed vertices and extra mass, refusals that change nothing, and slivers made on purpose
// removed down to the documented floor.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/tissue/surface_validity.hpp"
#include "core/topology/quality.hpp"
#include "topology_test_util.hpp"
#include "../test_meshes.hpp"

using namespace vitreo::core;
using namespace vitreo::core::test;

namespace {

constexpr double kW = 3.0, kH = 2.0;
constexpr int kCols = 12, kRows = 8;

// Everything a refused request must leave as it was.
struct Digest {
  std::uint64_t version;
  std::uint32_t vertices, edges, triangles;
  double mass, area, positions;
  bool operator==(const Digest&) const = default;
};
Digest digest(const Surface& s) {
  double p = 0.0;
  for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) {
    if (s.vertex_alive(v)) p += s.position(v).sum() * (v + 1) + s.velocity(v).sum();
  }
  return {s.topology_version(), s.vertex_count(), s.edge_count(), s.triangle_count(), s.total_mass(), s.total_rest_area(), p};
}

// An interior spring of the sheet whose two ends are interior too.
std::uint32_t interior_spring(const Surface& s) {
  for (std::uint32_t e = 0; e < s.edge_slots(); ++e) {
    if (!s.edge_alive(e) || s.edge_triangles(e)[1] == kNone) continue;
    const auto [a, b] = s.edge_vertices(e);
    if (!s.is_boundary_vertex(a) && !s.is_boundary_vertex(b) && s.rest_position(a).x() > 1.0) return e;
  }
  return kNone;
}

}  // namespace

TEST(CollapseEdge, KeepsMassAreaRestShapeAndEveryOtherHandle) {
  SurfaceDescription d = sheet(kW, kH, kCols, kRows, 0.3, 5);
  d.extra_vertex_mass_g.assign(d.mesh.positions.size(), 0.0);
  Surface s0(d);
  const std::uint32_t e = interior_spring(s0);
  ASSERT_NE(e, kNone);
  const auto [keep, gone] = s0.edge_vertices(e);
  d.extra_vertex_mass_g[gone] = 1e-6;  // a bead on the vertex that goes: its mass moves to keep
  Surface s(d);
  const double mass0 = s.total_mass(), area0 = s.total_rest_area();
  std::vector<VertexId> handles;
  for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) handles.push_back(s.vertex_id(v));
  const Vec3 keep_at = s.position(keep);
  const auto r = s.collapse_edge(s.edge_id(e), keep);
  ASSERT_TRUE(r.status) << r.status.message();
  EXPECT_EQ(r.removed_vertex, gone);
  EXPECT_EQ(r.triangles_removed, 2u);
  EXPECT_NEAR(s.total_mass(), mass0, 1e-12 * mass0);
  EXPECT_NEAR(s.total_rest_area(), area0, 1e-12 * area0);
  EXPECT_NEAR(s.extra_mass(keep), 1e-6, 1e-18);
  EXPECT_LT(max_rest_vector_error(s), 1e-12) << "re-homed springs: rest vectors by vector addition";
  EXPECT_EQ(s.position(keep), keep_at);
  for (std::uint32_t v = 0; v < handles.size(); ++v) EXPECT_EQ(s.is_current(handles[v]), v != gone) << v;
  const auto report = check_surface(s, ValidityLimits{});
  EXPECT_TRUE(report.ok()) << report.summary();
}

TEST(CollapseEdge, InvalidOrUnsafeRequestsAreRefusedAndChangeNothing) {
  Surface s(sheet(kW, kH, kCols, kRows, 0.3, 5));
  const std::uint32_t e = interior_spring(s);
  ASSERT_NE(e, kNone);
  const auto [a, b] = s.edge_vertices(e);
  const Digest before = digest(s);
  EXPECT_FALSE(s.collapse_edge(EdgeId{e, s.edge_id(e).generation + 1}, a).status) << "stale handle";
  EXPECT_FALSE(s.collapse_edge(s.edge_id(e), (a + 1 == b) ? a + 2 : a + 1).status) << "keep not an end";
  // A fixed vertex is never the one removed (unless the kept one is fixed too).
  ASSERT_TRUE(s.set_fixed(s.vertex_id(b), true));
  const Digest fixed_before = digest(s);
  const auto r = s.collapse_edge(s.edge_id(e), a);
  EXPECT_FALSE(r.status);
  EXPECT_NE(r.status.message().find("fixed"), std::string::npos);
  EXPECT_EQ(digest(s), fixed_before);
  ASSERT_TRUE(s.set_fixed(s.vertex_id(b), false));
  // An interior spring between two boundary vertices would pinch the sheet: refused, and a
  // boundary vertex is not pulled inward.
  for (std::uint32_t f = 0; f < s.edge_slots(); ++f) {
    if (!s.edge_alive(f)) continue;
    const auto [p, q] = s.edge_vertices(f);
    const bool pb = s.is_boundary_vertex(p), qb = s.is_boundary_vertex(q);
    const Digest d0 = digest(s);
    if (pb && qb && s.edge_triangles(f)[1] != kNone) {
      const auto rr = s.collapse_edge(s.edge_id(f), p);
      EXPECT_FALSE(rr.status);
      EXPECT_NE(rr.status.message().find("pinch"), std::string::npos);
    } else if (pb != qb) {
      EXPECT_FALSE(s.collapse_edge(s.edge_id(f), pb ? q : p).status) << "boundary vertex removed for an interior one";
    }
    EXPECT_EQ(digest(s), d0);
  }
  // Refusals leave even the velocities and the topology version as they were.
  ASSERT_TRUE(s.set_fixed(s.vertex_id(b), true));
  ASSERT_TRUE(s.set_fixed(s.vertex_id(b), false));
  EXPECT_EQ(digest(s).positions, before.positions);
}

TEST(DissolveTriangle, MovesTheAreaToTheNeighbourAndRefusesNonNeighbours) {
  Surface s(sheet(kW, kH, kCols, kRows, 0.3, 6));
  const double mass0 = s.total_mass(), area0 = s.total_rest_area();
  const std::uint32_t e = interior_spring(s);
  const auto et = s.edge_triangles(e);
  const double receiver_area = s.triangle_rest_area(et[1]) + s.triangle_rest_area(et[0]);
  // Two triangles far apart share no spring.
  const Digest before = digest(s);
  std::uint32_t far = kNone;
  for (std::uint32_t t = 0; t < s.triangle_slots() && far == kNone; ++t) {
    bool shares = false;
    for (auto f : s.triangle_edges(t)) shares = shares || s.edge_triangles(f)[0] == et[0] || s.edge_triangles(f)[1] == et[0];
    if (!shares && t != et[0]) far = t;
  }
  EXPECT_FALSE(s.dissolve_triangle(s.triangle_id(et[0]), s.triangle_id(far)));
  EXPECT_EQ(digest(s), before);
  ASSERT_TRUE(s.dissolve_triangle(s.triangle_id(et[0]), s.triangle_id(et[1])));
  EXPECT_FALSE(s.triangle_alive(et[0]));
  EXPECT_NEAR(s.triangle_rest_area(et[1]), receiver_area, 1e-15);
  EXPECT_NEAR(s.total_mass(), mass0, 1e-12 * mass0);
  EXPECT_NEAR(s.total_rest_area(), area0, 1e-12 * area0);
  const auto report = check_surface(s);
  EXPECT_TRUE(report.ok()) << report.summary();
}

TEST(MeshQuality, RemovesSliversDownToTheFloorWithExactMassAndKeepsAnchors) {
  // A sheet with slivers made on purpose: an interior vertex 1 µm from its right neighbour (short
  // springs, needles) and another 60 % of the way to its upper neighbour and 0.5 µm aside (short
  // springs elsewhere in the sheet).
  SurfaceDescription d = sheet(kW, kH, kCols, kRows);
  const auto at = [&](int i, int j) { return static_cast<std::uint32_t>(j * (kCols + 1) + i); };
  d.mesh.positions[at(4, 3)] = d.mesh.positions[at(5, 3)] + Vec3(-0.001, 0.0, 0.0);
  d.mesh.positions[at(8, 5)] = d.mesh.positions[at(8, 6)] + Vec3(0.0005, -0.0015, 0.0);
  Surface s(d);
  // The vertex next to the short springs is an anchor: the rule keeps it.
  ASSERT_TRUE(s.set_fixed(s.vertex_id(at(5, 3)), true));
  const QualitySettings q;
  ASSERT_FALSE(check_surface(s, quality_limits(q)).ok()) << "the sheet must start with slivers";
  const double mass0 = s.total_mass(), area0 = s.total_rest_area();
  const VertexId anchor = s.vertex_id(at(5, 3));
  const Vec3 anchor_at = s.position(at(5, 3));
  MeshQuality quality(s, q);
  const auto r = quality.clean_all();
  EXPECT_GE(r.collapses + r.dissolved, 2u);
  EXPECT_EQ(r.unresolved, 0u);
  EXPECT_EQ(r.fragments_removed, 0u);
  const auto report = check_surface(s, quality_limits(q));
  EXPECT_TRUE(report.ok()) << report.summary();
  EXPECT_NEAR(s.total_mass(), mass0, 1e-12 * mass0);
  EXPECT_NEAR(s.total_rest_area(), area0, 1e-12 * area0);
  EXPECT_TRUE(s.is_current(anchor));
  EXPECT_TRUE(s.is_fixed(anchor.index));
  EXPECT_EQ(s.position(anchor.index), anchor_at);
  EXPECT_EQ(s.topology_version() > 0, true);
  // A second pass finds nothing left to do.
  const auto again = quality.clean_all();
  EXPECT_EQ(again.collapses + again.dissolved + again.unresolved, 0u);
}
