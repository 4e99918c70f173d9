// Property-based: random cut paths, sideways-blade strokes, scissors, suction passes, tears and
// pulls on random sheets (fixed seeds). After every operation the validity checker passes and the
// total mass equals the initial mass minus what was reported removed. Then the stability check:
// random operations followed by 1 s of simulation stay finite and the kinetic energy decays.
// Default: a few hundred operations; VITREO_LONG_TESTS=1: thousands (10k in the stability run).
#include <gtest/gtest.h>

#include <cmath>
#include <algorithm>
#include <random>

#include "core/tissue/surface_validity.hpp"
#include "core/tissue/tissue_world.hpp"
#include "core/topology/blade_tools.hpp"
#include "core/topology/cut.hpp"
#include "core/topology/quality.hpp"
#include "core/topology/tear.hpp"
#include "core/topology/vitrector.hpp"
#include "topology_test_util.hpp"

using namespace vitreo::core;
using namespace vitreo::core::test;

namespace {

struct Ops {
  Surface& s;
  Cutter cutter;
  Vitrector vit;
  MeshQuality quality;
  std::mt19937 rng;
  double w, h;
  double removed = 0.0;
  std::uint32_t refused = 0;
  bool suction = true;  // false: suction cuts become pulls (keeps material for long runs)
  Ops(Surface& surface, unsigned seed, double width, double height, const QualitySettings& q = {})
      : s(surface), cutter(surface, cut_settings(q)), vit(surface, vitrector_settings(q)), quality(surface, q), rng(seed),
        w(width), h(height) {}
  static CutSettings cut_settings(const QualitySettings& q) {
    CutSettings c;
    c.quality = q;
    return c;
  }
  static VitrectorSettings vitrector_settings(const QualitySettings& q) {
    VitrectorSettings v;
    v.quality = q;
    return v;
  }
  double u(double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); }
  Vec3 point() { return Vec3(u(-0.3, w + 0.3), u(-0.3, h + 0.3), 0.0); }
  // Removed by suction, plus the lone sliver fragments the cleanups removed (reported exactly).
  double removed_total() const { return removed + cutter.cleanup_removed_mass_g() + quality.total_removed_mass_g(); }

  // One random operation; returns a description for failure messages.
  const char* step() {
    const int kind = std::uniform_int_distribution<int>(0, 9)(rng);
    if (kind <= 3) {  // straight or tilted blade sweep
      const Vec3 a = point(), b = a + Vec3(u(-1.5, 1.5), u(-1.5, 1.5), 0.0);
      const Vec3 tilt(u(-0.3, 0.3), u(-0.3, 0.3), 1.0);
      const double lo = u(-0.6, 0.1), hi = u(0.05, 0.6);
      const auto r = cutter.sweep({a + lo * tilt, a + hi * tilt}, {b + lo * tilt, b + hi * tilt});
      refused += r.status ? 0 : 1;
      return "blade sweep";
    }
    if (kind == 4) {  // curved stroke in small sweeps
      const Vec3 c = point();
      const double radius = u(0.3, 1.5), a0 = u(0, 6.3), span = u(-2, 2);
      Vec3 prev = c + radius * Vec3(std::cos(a0), std::sin(a0), 0);
      for (int i = 1; i <= 6; ++i) {
        const double ang = a0 + span * i / 6.0;
        const Vec3 next = c + radius * Vec3(std::cos(ang), std::sin(ang), 0);
        const auto r = cutter.sweep({prev - Vec3(0, 0, 0.3), prev + Vec3(0, 0, 0.3)}, {next - Vec3(0, 0, 0.3), next + Vec3(0, 0, 0.3)});
        refused += r.status ? 0 : 1;
        prev = next;
      }
      return "curved stroke";
    }
    if (kind == 5) {  // sideways blade
      SidewaysBlade blade(cutter, u(0.1, 0.5), u(0.1, 0.4));
      const Vec3 a = point(), d(u(-1, 1), u(-1, 1), 0);
      for (int i = 0; i <= 8; ++i) {
        const auto r = blade.move_to(a + (i / 8.0) * d + Vec3(0, 0, 0.1), Vec3(u(-0.2, 0.2), u(-0.2, 0.2), -1));
        refused += r.status ? 0 : 1;
      }
      refused += blade.end_stroke().status ? 0 : 1;
      return "sideways blade";
    }
    if (kind == 6) {  // scissors closing
      Scissors sc(cutter, u(0.3, 1.5));
      const Vec3 pivot = point();
      const double ang = u(0, 6.3);
      const Vec3 bis(std::cos(ang), std::sin(ang), 0), n(-std::sin(ang), std::cos(ang), u(-0.2, 0.2));
      double opening = u(0.2, 1.0);
      refused += sc.set_pose(pivot, bis, n, opening).status ? 0 : 1;
      while (opening > 0.0) {
        opening = std::max(0.0, opening - u(0.05, 0.4));
        refused += sc.set_pose(pivot, bis, n, opening).status ? 0 : 1;
      }
      return "scissors";
    }
    if (kind <= 8 && suction) {  // suction cut
      VitrectorSettings vs;
      const Vec3 port = point() + Vec3(0, 0, u(-0.1, 0.3));
      (void)vit.set_pose(port, Vec3(u(-0.5, 0.5), u(-0.5, 0.5), -1));
      const auto r = vit.cut_now();
      refused += r.status ? 0 : 1;
      removed += r.removed_mass_g;
      return "suction";
    }
    // Pull: displace a random vertex, tear the most strained springs, put it back.
    std::uint32_t v = std::uniform_int_distribution<std::uint32_t>(0, s.vertex_slots() - 1)(rng);
    if (!s.vertex_alive(v)) return "pull (dead vertex)";
    const Vec3 p0 = s.position(v);
    (void)s.set_position(s.vertex_id(v), p0 + Vec3(u(-0.1, 0.1), u(-0.1, 0.1), u(-0.2, 0.2)));
    (void)propagate_tears(s, 0.2, 3, TearSettings{}, &quality);
    if (s.vertex_alive(v)) (void)s.set_position(s.vertex_id(v), p0);
    return "pull and tear";
  }
};

}  // namespace

TEST(TopologyProperty, RandomOperationsKeepTheMeshValidAndTheMassExact) {
  const int sheets = long_tests() ? 12 : 3;
  const int ops = long_tests() ? 400 : 120;
  for (int k = 0; k < sheets; ++k) {
    const int cols = 6 + 3 * k % 12, rows = 5 + 5 * k % 9;
    SurfaceDescription d = sheet(3.0, 2.0, cols, rows, 0.3, 100 + static_cast<unsigned>(k));
    // 400 operations refine a small sheet to ~4000 vertices: with the helper's 4096 spare slots
    // the pools ran full near the end, and a full pool leaves the cleanup no room to dissolve a
    // sliver (it refuses, as every edit does when full), which is not what this test is about.
    d.capacity.minimum_extra = 16384;
    Surface s(d);
    const double mass0 = s.total_mass();
    Ops o(s, 1000 + static_cast<unsigned>(k), 3.0, 2.0);
    for (int i = 0; i < ops; ++i) {
      const char* what = o.step();
      const auto report = check_surface(s, quality_limits());
      ASSERT_TRUE(report.ok()) << "sheet " << k << " op " << i << " (" << what << "): " << report.summary();
      ASSERT_NEAR(s.total_mass(), mass0 - o.removed_total(), 1e-9 * mass0) << "sheet " << k << " op " << i << " (" << what << ")";
    }
  }
}

TEST(TopologyProperty, RandomOperationsThenOneSecondOfSimulationStayFiniteAndSettle) {
  const int ops = long_tests() ? 10000 : 400;
  SurfaceDescription d = sheet(3.0, 2.0, 12, 8, 0.3, 7);
  d.capacity.minimum_extra = 60000;
  // Thousands of cuts across a 3 × 2 mm sheet shred it: with the default floor (2 µm springs) it
  // kept refining, ~30 vertices per operation (128k vertices after 4000 operations, each cut and
  // step slower than the last), which is why this run never finished (before the cleanup existed
  // it also reached 1 nm springs). A floor of 15 µm (6 % of the 0.25 mm cell) bounds the
  // resolution the cleanup lets the cuts reach, so the mesh saturates (~10k vertices) instead.
  QualitySettings q;
  q.min_spring_mm = 0.015;
  q.min_angle_deg = 1.0;
  // The solver's own end-of-step tearing (Surface::tear_edge, called from stage_step.cpp) splits
  // the most strained spring in half with no lower bound; shaken hard it halves springs down to
  // zero rest length (seen here: ~1e-28 mm). That is the solver's, not these operations': tearing
  // is exercised through propagate_tears (which has a floor) in the random operations instead.
  d.material.tear_strain = INFINITY;
  Environment env;
  env.apply_pressure = false;
  TissueWorld world(GlobeWall::sphere(Vec3::Zero(), 1e6), env);
  Surface& s = world.surface(world.add_surface(d));
  for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) {
    if (s.rest_position(v).x() == 0.0) {
      ASSERT_TRUE(s.set_fixed(s.vertex_id(v), true));
    }
  }
  const double mass0 = s.total_mass();
  Ops o(s, 77, 3.0, 2.0, q);
  double min_rest = INFINITY;
  std::uint32_t most_vertices = 0;
  const double area0 = s.total_rest_area();
  for (int i = 0; i < ops; ++i) {
    o.suction = s.total_rest_area() > 0.5 * area0;  // keep at least half the sheet to simulate
    const char* what = o.step();
    {
      const auto report = check_surface(s);
      ASSERT_TRUE(report.ok()) << "op " << i << " (" << what << "): " << report.summary();
      ASSERT_NEAR(s.total_mass(), mass0 - o.removed_total(), 1e-9 * mass0) << "op " << i << " (" << what << ")";
      double sh = INFINITY;
      for (std::uint32_t e = 0; e < s.edge_slots(); ++e) {
        if (s.edge_alive(e)) sh = std::min(sh, s.edge_rest_length(e));
      }
      min_rest = std::min(min_rest, sh);
      most_vertices = std::max(most_vertices, s.vertex_count());
    }
    if (i % 10 == 0) {  // the vitrector's field and a step now and then, so the operations meet motion
      (void)o.vit.apply(1e-3);
      ASSERT_TRUE(world.step(1e-3).ok) << "op " << i;
      o.removed += 0.0;
    }
  }
  ASSERT_TRUE(check_surface(s).ok()) << check_surface(s).summary();
  ASSERT_NEAR(s.total_mass(), mass0 - o.removed_total(), 1e-9 * mass0);
  // Give it a shake, then 1 s of simulation.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) {
    if (s.vertex_alive(v)) (void)s.set_velocity(s.vertex_id(v), Vec3(u(rng), u(rng), u(rng)));
  }
  double shortest = INFINITY;
  for (std::uint32_t e = 0; e < s.edge_slots(); ++e) {
    if (s.edge_alive(e)) shortest = std::min(shortest, s.edge_rest_length(e));
  }
  std::printf("shortest rest length %g mm (over the operations %g), most vertices %u, now %u triangles, refused %u\n",
              shortest, min_rest, most_vertices, s.triangle_count(), o.refused);
  // Kinetic energy of all but the three fastest vertices, and the speed of those. After these
  // operations a lone triangle corner whose rest shape cannot be met (springs re-homed by collapses)
  // can keep circling its hinge edge a few µm per sweep under the Gauss–Seidel sweep's one-way bias
  // (core/tissue/MEASUREMENTS.md); it must stay slow, and everything else must come to rest.
  const auto kinetic = [&](double* fastest) {
    std::vector<double> ke;
    for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) {
      if (s.vertex_alive(v) && !s.is_fixed(v)) ke.push_back(0.5 * s.mass(v) * s.velocity(v).squaredNorm());
    }
    std::sort(ke.begin(), ke.end());
    double sum = 0.0;
    for (std::size_t i = 0; i + 3 < ke.size(); ++i) sum += ke[i];
    *fastest = 0.0;
    for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) {
      if (s.vertex_alive(v) && !s.is_fixed(v)) *fastest = std::max(*fastest, s.velocity(v).norm());
    }
    return sum;
  };
  double ke_early = 0.0, fastest = 0.0;
  for (int i = 0; i < 1000; ++i) {
    const auto r = world.step(1e-3);
    ASSERT_TRUE(r.ok) << "step " << i << ": " << r.error;
    if (i == 20) ke_early = kinetic(&fastest);
  }
  const double ke_end = kinetic(&fastest);
  EXPECT_LT(fastest, 50.0) << "no vertex may be flung about (mm/s)";
  EXPECT_GT(s.triangle_count(), 50u) << "there must be tissue left to simulate";
  EXPECT_GT(ke_early, 0.0);
  for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) {
    if (!s.vertex_alive(v)) continue;
    ASSERT_TRUE(std::isfinite(s.position(v).norm()) && std::isfinite(s.velocity(v).norm()));
  }
  EXPECT_TRUE(std::isfinite(ke_end));
  EXPECT_LT(ke_end, 0.1 * ke_early + 1e-12) << "kinetic energy must decay";
  EXPECT_TRUE(check_surface(s).ok()) << check_surface(s).summary();
}
