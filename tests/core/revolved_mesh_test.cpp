#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <utility>

#include "core/common/status.hpp"
#include "core/geometry/revolved_mesh.hpp"

using namespace vitreo::core;

namespace {

// Counts how many triangles use each undirected edge, and how often each directed edge appears.
struct EdgeCensus {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> undirected, directed;
  explicit EdgeCensus(const TriangleMesh& m) {
    for (const auto& t : m.triangles) {
      for (int k = 0; k < 3; ++k) {
        const auto a = t[k], b = t[(k + 1) % 3];
        ++directed[{a, b}];
        ++undirected[{std::min(a, b), std::max(a, b)}];
      }
    }
  }
};

}  // namespace

TEST(RevolvedMesh, ClosedSphereIsWatertightOutwardAndHasTheRightArea) {
  const double r = 5.0;
  const TriangleMesh m = revolve_profile(sphere_arc_profile(r, 0.0, std::numbers::pi, 512), {0.4, 2 * std::numbers::pi});
  const EdgeCensus census(m);
  for (const auto& [edge, count] : census.undirected) EXPECT_EQ(count, 2) << "edge " << edge.first << "-" << edge.second;
  for (const auto& [edge, count] : census.directed) EXPECT_EQ(count, 1) << "inconsistent orientation";
  // Euler characteristic of a sphere: V − E + F = 2.
  EXPECT_EQ(static_cast<long>(m.vertex_count()) - static_cast<long>(census.undirected.size()) +
                static_cast<long>(m.triangle_count()),
            2);
  for (const auto& t : m.triangles) {
    const Vec3 c = (m.positions[t[0]] + m.positions[t[1]] + m.positions[t[2]]) / 3.0;
    const Vec3 n = (m.positions[t[1]] - m.positions[t[0]]).cross(m.positions[t[2]] - m.positions[t[0]]);
    ASSERT_GT(n.dot(c), 0.0) << "normal points inward";
  }
  // A polyhedron inscribed in the sphere has slightly less area: within 1 %.
  EXPECT_NEAR(mesh_area(m), 4 * std::numbers::pi * r * r, 0.01 * 4 * std::numbers::pi * r * r);
  for (const auto& p : m.positions) EXPECT_NEAR(p.norm(), r, 1e-3);
}

TEST(RevolvedMesh, TrianglesAreNearlyEquilateral) {
  const TriangleMesh m = revolve_profile(sphere_arc_profile(12.0, 0.0, 1.9, 110), {0.3, 2 * std::numbers::pi});
  double worst = 1.0;
  for (const auto& t : m.triangles) {
    double lmin = 1e9, lmax = 0;
    for (int k = 0; k < 3; ++k) {
      const double l = (m.positions[t[(k + 1) % 3]] - m.positions[t[k]]).norm();
      lmin = std::min(lmin, l);
      lmax = std::max(lmax, l);
    }
    worst = std::min(worst, lmin / lmax);
  }
  EXPECT_GT(worst, 0.45) << "a sliver triangle would make a stiff, short spring";
}

TEST(RevolvedMesh, VertexCountFollowsTheRequestedDensity) {
  for (int target : {5000, 20000}) {
    const double h = edge_length_for_vertex_count(12.0, 1.9, target);
    const TriangleMesh m = revolve_profile(sphere_arc_profile(12.0, 0.0, 1.9, 110), {h, 2 * std::numbers::pi});
    EXPECT_NEAR(static_cast<double>(m.vertex_count()), target, 0.1 * target);
  }
}

TEST(RevolvedMesh, RejectsBadInput) {
  EXPECT_THROW(revolve_profile({{0, 1}}, {}), InvalidArgument);
  EXPECT_THROW(revolve_profile({{0, 1}, {1, -1}}, {}), InvalidArgument);
  EXPECT_THROW(revolve_profile({{0, 1}, {1, 1}}, {0.0, 1.0}), InvalidArgument);
  EXPECT_THROW(revolve_profile({{0, 1}, {std::nan(""), 1}}, {}), InvalidArgument);
}
