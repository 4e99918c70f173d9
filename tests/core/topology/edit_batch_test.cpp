// Surface::EditBatch: edits made inside a batch recompute masses and stiffnesses once, at its end.
// The result must be the same, bit for bit, as the same edits made one at a time, and both must
// match the definitions (mass = areal density × adjacent rest area / 3 + extra mass; stiffness =
// the constant-strain triangle's energy lumped on its springs, see stiffness_by_definition), computed
// here from the public topology without the Surface's own update functions.
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <cstdint>
#include <random>
#include <string>

#include "core/tissue/surface.hpp"
#include "core/tissue/surface_validity.hpp"
#include "topology_test_util.hpp"

using namespace vitreo::core;
using namespace vitreo::core::test;

namespace {

// The same random edits on any surface built from the same description: splits of springs and
// triangles, cuts opened spring by spring, triangles removed, springs collapsed. Every choice
// depends only on topology and rest data, which batching does not delay, so both surfaces see the
// same sequence.
void random_edits(Surface& s, unsigned seed, int count) {
  std::mt19937 rng(seed);
  auto pick = [&](std::uint32_t n) { return std::uniform_int_distribution<std::uint32_t>(0, n - 1)(rng); };
  auto unit = [&] { return std::uniform_real_distribution<double>(0.2, 0.8)(rng); };
  for (int i = 0; i < count; ++i) {
    const std::uint32_t kind = pick(5);
    if (kind == 0) {
      const std::uint32_t e = pick(s.edge_slots());
      if (s.edge_alive(e)) (void)s.split_edge(s.edge_id(e), unit());
    } else if (kind == 1) {
      const std::uint32_t t = pick(s.triangle_slots());
      if (s.triangle_alive(t)) {
        const double a = unit(), b = unit() * (1.0 - a);
        (void)s.split_triangle(s.triangle_id(t), {a, b, 1.0 - a - b});
      }
    } else if (kind == 2) {
      const std::uint32_t e = pick(s.edge_slots());
      if (s.edge_alive(e) && s.edge_triangles(e)[1] != kNone) {
        const auto ends = s.edge_vertices(e);
        if (s.disconnect_edge(s.edge_id(e)).status) {
          for (auto v : ends) (void)s.separate_vertex_fans(s.vertex_id(v));
        }
      }
    } else if (kind == 3) {
      const std::uint32_t t = pick(s.triangle_slots());
      if (s.triangle_alive(t) && s.triangle_count() > 100) (void)s.remove_triangle(s.triangle_id(t));
    } else {
      const std::uint32_t e = pick(s.edge_slots());
      if (s.edge_alive(e)) (void)s.collapse_edge(s.edge_id(e), s.edge_vertices(e)[0]);
    }
  }
}

double mass_by_definition(const Surface& s, std::uint32_t v) {
  double area = 0.0;
  s.for_each_triangle_of(v, [&](std::uint32_t t, std::uint32_t) { area += s.triangle_rest_area(t) / 3.0; });
  return s.material().areal_density_g_per_mm2() * area + s.extra_mass(v);
}

// The linear-elastic energy of a triangle (membrane modulus E·t, Poisson ratio 1/3, plane stress)
// whose rest edge lengths are `rest` and whose edges are stretched to `rest × (1 + strain)`: the
// triangle laid out in its plane from its lengths, F from the edge vectors, Green strain.
double triangle_energy(double et, const std::array<double, 3>& rest, const std::array<double, 3>& strain) {
  const auto layout = [](double a, double b, double c) {  // edges 0 = p0p1 (a), 1 = p1p2 (b), 2 = p2p0 (c)
    const double x = (a * a + c * c - b * b) / (2.0 * a);
    Eigen::Matrix2d d;
    d << a, x, 0.0, std::sqrt(std::max(c * c - x * x, 0.0));
    return d;  // columns p1 − p0, p2 − p0
  };
  const Eigen::Matrix2d dm = layout(rest[0], rest[1], rest[2]);
  const Eigen::Matrix2d ds =
      layout(rest[0] * (1 + strain[0]), rest[1] * (1 + strain[1]), rest[2] * (1 + strain[2]));
  const Eigen::Matrix2d f = ds * dm.inverse();
  const Eigen::Matrix2d green = 0.5 * (f.transpose() * f - Eigen::Matrix2d::Identity());
  const double area = 0.5 * dm.determinant();
  const double nu = 1.0 / 3.0, lambda = et * nu / (1.0 - nu * nu), mu = et / (2.0 * (1.0 + nu));
  return area * (0.5 * lambda * green.trace() * green.trace() + mu * (green * green).trace());
}

// Whether a triangle's three rest lengths make a triangle of its rest area (Heron): edits that
// re-home springs (collapses) can leave rest vectors that do not close, where "the triangle's
// continuum energy" has no single meaning and only the batch identity is checked.
bool rest_shape_closes(const Surface& s, std::uint32_t t) {
  const auto te = s.triangle_edges(t);
  const double a = s.edge_rest_vector(te[0]).norm(), b = s.edge_rest_vector(te[1]).norm(),
               c = s.edge_rest_vector(te[2]).norm(), p = 0.5 * (a + b + c);
  const double heron = std::sqrt(std::max(0.0, p * (p - a) * (p - b) * (p - c)));
  return std::abs(heron - s.triangle_rest_area(t)) <= 1e-9 * s.triangle_rest_area(t);
}

// A spring's stiffness by the definition in surface.cpp (triangle_spring_share), computed another
// way: each triangle gives the spring k ℓ² = ∂W/∂δ at a uniform small stretch δ = (s, s, s), by
// central differences of the triangle's continuum energy, at least a tenth of Van Gelder's E·t·A.
double stiffness_by_definition(const Surface& s, std::uint32_t e) {
  const double et = s.material().membrane_modulus_pa_mm;
  const double len2 = s.edge_rest_vector(e).squaredNorm();  // traction stays 1: the base rest vector
  double k = 0.0;
  for (auto t : s.edge_triangles(e)) {
    if (t == kNone) continue;
    const auto te = s.triangle_edges(t);
    std::array<double, 3> rest{};
    std::size_t which = 0;
    for (std::size_t i = 0; i < 3; ++i) {
      rest[i] = s.edge_rest_vector(te[i]).norm();
      if (te[i] == e) which = i;
    }
    const double u = 1e-4, eps = 1e-6;
    std::array<double, 3> plus{u, u, u}, minus{u, u, u};
    plus[which] += eps;
    minus[which] -= eps;
    const double row = (triangle_energy(et, rest, plus) - triangle_energy(et, rest, minus)) / (2.0 * eps * u);
    k += std::max(row, 0.1 * et * s.triangle_rest_area(t)) / len2;

  }
  return k;
}

}  // namespace

TEST(EditBatch, EditsInABatchEndExactlyAsTheSameEditsOneAtATime) {
  const SurfaceDescription d = sheet(kSheetW, kSheetH, kSheetCols, kSheetRows, 0.3, 5);
  for (unsigned seed = 1; seed <= 8; ++seed) {
    Surface one_by_one(d), batched(d);
    const std::uint32_t slots0 = one_by_one.vertex_slots(), triangles0 = one_by_one.triangle_count();
    random_edits(one_by_one, seed, 120);
    ASSERT_GT(one_by_one.vertex_slots(), slots0 + 20) << "seed " << seed << ": too few edits took";
    ASSERT_NE(one_by_one.triangle_count(), triangles0);
    bool stale_inside = false;
    {
      const Surface::EditBatch batch(batched);
      random_edits(batched, seed, 120);
      // The batch defers the work: some vertex near the edits is not up to date yet.
      for (std::uint32_t v = 0; v < batched.vertex_slots() && !stale_inside; ++v) {
        stale_inside = batched.vertex_alive(v) && batched.mass(v) != mass_by_definition(batched, v);
      }
    }
    EXPECT_TRUE(stale_inside) << "seed " << seed << ": nothing was deferred";
    ASSERT_EQ(batched.vertex_slots(), one_by_one.vertex_slots()) << "seed " << seed;
    ASSERT_EQ(batched.edge_slots(), one_by_one.edge_slots()) << "seed " << seed;
    ASSERT_EQ(batched.topology_version(), one_by_one.topology_version()) << "seed " << seed;
    for (std::uint32_t v = 0; v < batched.vertex_slots(); ++v) {
      ASSERT_EQ(batched.vertex_alive(v), one_by_one.vertex_alive(v));
      if (!batched.vertex_alive(v)) continue;
      EXPECT_EQ(batched.mass(v), one_by_one.mass(v)) << "seed " << seed << " vertex " << v;
      EXPECT_EQ(batched.inverse_mass(v), one_by_one.inverse_mass(v)) << "seed " << seed << " vertex " << v;
      EXPECT_EQ(batched.vertex_rest_area(v), one_by_one.vertex_rest_area(v)) << "seed " << seed << " vertex " << v;
      EXPECT_NEAR(batched.mass(v), mass_by_definition(batched, v), 1e-12 * batched.mass(v)) << "vertex " << v;
    }
    std::uint32_t checked = 0;
    for (std::uint32_t e = 0; e < batched.edge_slots(); ++e) {
      ASSERT_EQ(batched.edge_alive(e), one_by_one.edge_alive(e));
      if (!batched.edge_alive(e)) continue;
      EXPECT_EQ(batched.edge_stiffness(e), one_by_one.edge_stiffness(e)) << "seed " << seed << " spring " << e;
      bool closes = true;
      for (auto t : batched.edge_triangles(e)) closes = closes && (t == kNone || rest_shape_closes(batched, t));
      if (!closes) continue;
      ++checked;
      EXPECT_NEAR(batched.edge_stiffness(e), stiffness_by_definition(batched, e), 1e-3 * batched.edge_stiffness(e))
          << "seed " << seed << " spring " << e;
    }
    EXPECT_GT(checked, batched.edge_count() * 3 / 4) << "seed " << seed << ": most springs keep a closed rest shape";
    const auto report = check_surface(batched, ValidityLimits{});
    EXPECT_TRUE(report.ok()) << "seed " << seed << ": " << report.summary();
  }
}

TEST(EditBatch, NestedBatchesRecomputeWhenTheOutermostCloses) {
  Surface s(sheet(kSheetW, kSheetH, kSheetCols, kSheetRows));
  const std::uint32_t e = s.find_edge(6 * (kSheetCols + 1) + 8, 6 * (kSheetCols + 1) + 9);
  ASSERT_NE(e, kNone);
  std::uint32_t m = kNone;
  {
    const Surface::EditBatch outer(s);
    {
      const Surface::EditBatch inner(s);
      const auto r = s.split_edge(s.edge_id(e), 0.5);
      ASSERT_TRUE(r.status);
      m = r.vertex;
    }
    EXPECT_EQ(s.mass(m), 0.0) << "still inside the outer batch";
  }
  EXPECT_GT(s.mass(m), 0.0);
  EXPECT_NEAR(s.mass(m), mass_by_definition(s, m), 1e-12 * s.mass(m));
  EXPECT_TRUE(check_surface(s, ValidityLimits{}).ok());
}
