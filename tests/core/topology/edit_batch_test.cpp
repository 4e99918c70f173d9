// Surface::EditBatch: edits made inside a batch recompute masses and stiffnesses once, at its end.
// The result must be the same, bit for bit, as the same edits made one at a time, and both must
// match the definitions (mass = areal density × adjacent rest area / 3 + extra mass; stiffness =
// membrane modulus × adjacent rest area / |base rest vector|², Van Gelder), computed here from
// the public topology without the Surface's own update functions.
#include <gtest/gtest.h>

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

double stiffness_by_definition(const Surface& s, std::uint32_t e) {
  double area = 0.0;
  for (auto t : s.edge_triangles(e)) {
    if (t != kNone) area += s.triangle_rest_area(t);
  }
  // Traction stays 1 here, so the rest vector is the base rest vector.
  return s.material().membrane_modulus_pa_mm * area / s.edge_rest_vector(e).squaredNorm();
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
    for (std::uint32_t e = 0; e < batched.edge_slots(); ++e) {
      ASSERT_EQ(batched.edge_alive(e), one_by_one.edge_alive(e));
      if (!batched.edge_alive(e)) continue;
      EXPECT_EQ(batched.edge_stiffness(e), one_by_one.edge_stiffness(e)) << "seed " << seed << " spring " << e;
      EXPECT_NEAR(batched.edge_stiffness(e), stiffness_by_definition(batched, e), 1e-9 * batched.edge_stiffness(e))
          << "seed " << seed << " spring " << e;
    }
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
