// Criteria on real scenes (build_scene): each goes from unmet to met when the tissue it is about is
// removed, released, cut, lasered, drained or flattened, and its value matches a reference worked out
// independently (the vitrector's own accounting, the guide's arc lengths, max_retina_lift_mm).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/metrics/session_metrics.hpp"
#include "core/topology/cut.hpp"
#include "core/topology/vitrector.hpp"
#include "core/tissue/surface_validity.hpp"

namespace vitreo::core {
namespace {

constexpr double kDt = 1e-3;

// A small eye with one of everything: a tear (so the retina starts lifted), a detachment, an
// epiretinal membrane, a cut path and a laser ring, and every criterion about them.
SceneDescription case_scene(bool gel) {
  SceneDescription d;
  d.name = "metrics";
  d.anatomy.retina_vertices = 6000;
  d.anatomy.gel_shells = gel ? 2 : 0;
  d.texture_size_px = 64;
  d.materials = default_materials();
  d.tears.push_back({"u", {60.0, 120.0}, 2.5, 3.5, 0.8});
  d.detachments.push_back({"fluid", {60.0, 300.0}, 20.0, 150.0});
  MembraneSpec erm;
  erm.name = "erm";
  erm.center = {8.0, 0.0};
  erm.size_mm = 3.0;
  d.membranes.push_back(erm);
  GuideSpec line;
  line.name = "line";
  line.kind = GuideKind::kCutPath;
  line.points = {{40.0, 200.0}, {45.0, 220.0}, {40.0, 240.0}};
  d.guides.push_back(line);
  GuideSpec ring;
  ring.name = "ring";
  ring.kind = GuideKind::kLaserRing;
  ring.center = {35.0, 60.0};
  ring.radius_mm = 1.5;
  d.guides.push_back(ring);
  d.criteria = {{CriterionKind::kMembraneRemoved, "erm", 0.9}, {CriterionKind::kMembraneReleased, "erm", 0.9},
                {CriterionKind::kPathCut, "line", 0.8},       {CriterionKind::kLaserCoverage, "ring", 0.8},
                {CriterionKind::kDrained, "fluid", 0.05},     {CriterionKind::kRetinaFlat, "", 0.3},
                {CriterionKind::kTimeLimit, "", 60.0}};
  if (gel) {
    d.criteria.push_back({CriterionKind::kGelRemoved, "", 0.3});
    d.criteria.push_back({CriterionKind::kGelRemoved, "core", 0.3});
  }
  return d;
}

Scene build(bool gel = false) { return build_scene(case_scene(gel), {false, false}); }

const CriterionProgress& find(const std::vector<CriterionProgress>& all, CriterionKind k) {
  for (const auto& c : all) {
    if (c.kind == k) return c;
  }
  ADD_FAILURE() << "no criterion " << to_string(k);
  return all.front();
}

TEST(Criteria, NothingIsMetAtTheStartExceptTheTimeLimit) {
  Scene scene = build(true);
  SessionMetrics m(scene, nullptr);
  for (const auto& c : m.criteria()) {
    if (c.kind == CriterionKind::kTimeLimit) {
      EXPECT_TRUE(c.met);
      EXPECT_EQ(c.progress, 1.0);
    } else {
      EXPECT_FALSE(c.met) << to_string(c.kind);
      EXPECT_EQ(c.progress, 0.0) << to_string(c.kind);
    }
  }
  EXPECT_FALSE(m.complete());
  const ScoreCard& s = m.score();
  ASSERT_NE(s.find("target_achievement"), nullptr);
  EXPECT_EQ(s.find("target_achievement")->value, 0.0);
  EXPECT_EQ(s.find("efficiency")->value, 0.0);  // nothing done yet
}

TEST(Criteria, MembraneRemovedAndReleasedFollowTheVitrector) {
  Scene scene = build();
  SessionMetrics m(scene, nullptr);
  const BuiltMembrane& erm = scene.membranes[0];
  Surface& ms = scene.world.surface(erm.surface);
  const double area0 = ms.total_rest_area();
  const Vec3 c = scene.eye.wall_point(8.0 * std::numbers::pi / 180.0, 0.0);

  // A small bite out of the middle: partly removed and released, neither met.
  VitrectorSettings vs;
  vs.field_radius_mm = 20.0;
  vs.removal_radius_mm = 1.2;
  Vitrector bite(ms, vs);
  ASSERT_TRUE(bite.set_pose(c - 0.5 * c.normalized(), c.normalized()));
  const VitrectorStepResult r1 = bite.cut_now();
  ASSERT_TRUE(r1.status) << r1.status.message();
  ASSERT_GT(r1.removed_area_mm2, 0.0);
  auto removed = find(m.criteria(), CriterionKind::kMembraneRemoved);
  EXPECT_NEAR(removed.value, r1.removed_area_mm2 / area0, 1e-12);
  EXPECT_FALSE(removed.met);
  const auto released = find(m.criteria(), CriterionKind::kMembraneReleased);
  EXPECT_GT(released.value, 0.0);
  EXPECT_LT(released.value, 0.9);
  EXPECT_FALSE(released.met);
  EXPECT_EQ(m.tissue().membrane_attachments, erm.attachment_count);
  EXPECT_NEAR(m.tissue().membrane_area_removed_mm2, r1.removed_area_mm2, 1e-12);

  // The rest of it: all removed, every attachment lost its membrane end.
  vs.removal_radius_mm = 9.0;
  Vitrector all(ms, vs);
  ASSERT_TRUE(all.set_pose(c - 6.0 * c.normalized(), c.normalized()));
  const VitrectorStepResult r2 = all.cut_now();
  ASSERT_TRUE(r2.status) << r2.status.message();
  removed = find(m.criteria(), CriterionKind::kMembraneRemoved);
  EXPECT_NEAR(removed.value, (r1.removed_area_mm2 + r2.removed_area_mm2) / area0, 1e-12);
  EXPECT_NEAR(removed.value, 1.0, 1e-9);
  EXPECT_TRUE(removed.met);
  EXPECT_TRUE(find(m.criteria(), CriterionKind::kMembraneReleased).met);
  EXPECT_EQ(find(m.criteria(), CriterionKind::kMembraneReleased).value, 1.0);
  // After the next step the world itself marks the attachments broken; the measure stays.
  scene.world.step(kDt);
  EXPECT_EQ(find(m.criteria(), CriterionKind::kMembraneReleased).value, 1.0);
  for (std::uint32_t a = erm.first_attachment; a < erm.first_attachment + erm.attachment_count; ++a) {
    EXPECT_FALSE(scene.world.attachment_intact(a));
  }
}

// The gel's rest area from its triangles' rest corners (half the cross product), all of it or only
// the triangles whose rest centroid lies more than `deeper_than` inside the wall (judged by the
// wall's radius in that direction) and, when `posterior`, behind the globe's centre along z.
double gel_rest_area(const TissueWorld& w, const Surface& g, double deeper_than, bool posterior = false) {
  double sum = 0.0;
  for (std::uint32_t t = 0; t < g.triangle_slots(); ++t) {
    if (!g.triangle_alive(t)) continue;
    const auto tv = g.triangle_vertices(t);
    const Vec3 a = g.rest_position(tv[0]), b = g.rest_position(tv[1]), c = g.rest_position(tv[2]);
    const Vec3 centroid = (a + b + c) / 3.0;
    const Vec3 d = centroid - w.wall().center();
    if (w.wall().radius_toward(d) - d.norm() <= deeper_than) continue;
    if (posterior && d.z() >= 0.0) continue;
    sum += 0.5 * (b - a).cross(c - a).norm();
  }
  return sum;
}

const CriterionProgress& find_target(const std::vector<CriterionProgress>& all, CriterionKind k, const std::string& target) {
  for (const auto& c : all) {
    if (c.kind == k && c.target == target) return c;
  }
  ADD_FAILURE() << "no criterion " << to_string(k) << " " << target;
  return all.front();
}

TEST(Criteria, GelRemovedIsTheShareOfTheGelRestAreaGoneAndCoreLeavesTheCorticalShell) {
  Scene scene = build(true);
  SessionMetrics m(scene, nullptr);
  Surface& gs = scene.world.surface(scene.gel);
  const double all0 = gel_rest_area(scene.world, gs, -1e9), core0 = gel_rest_area(scene.world, gs, kCoreGelDepth_mm, true);
  // Two shells 2.5 mm apart: the core is the inner one's posterior part.
  ASSERT_GT(core0, 0.1 * all0);
  ASSERT_LT(core0, 0.4 * all0);
  EXPECT_FALSE(find_target(m.criteria(), CriterionKind::kGelRemoved, "").met);
  EXPECT_EQ(find_target(m.criteria(), CriterionKind::kGelRemoved, "core").value, 0.0);
  // The vitrector clips away everything behind z = -4 mm: most of both shells' posterior parts.
  VitrectorSettings vs;
  vs.field_radius_mm = 20.0;
  vs.removal_radius_mm = 15.0;
  Vitrector v(gs, vs);
  ASSERT_TRUE(v.set_pose(Vec3(0.0, 0.0, -4.0), -Vec3::UnitZ()));
  ASSERT_TRUE(v.cut_now().status);
  const double all1 = gel_rest_area(scene.world, gs, -1e9), core1 = gel_rest_area(scene.world, gs, kCoreGelDepth_mm, true);
  ASSERT_LT(all1, 0.9 * all0);
  const auto& all = find_target(m.criteria(), CriterionKind::kGelRemoved, "");
  const auto& core = find_target(m.criteria(), CriterionKind::kGelRemoved, "core");
  EXPECT_NEAR(all.value, 1.0 - all1 / all0, 1e-9);
  EXPECT_NEAR(core.value, 1.0 - core1 / core0, 1e-9);
  EXPECT_GT(core.value, 0.3);  // a part of the core, not all of it
  EXPECT_LT(core.value, 0.95);
  EXPECT_TRUE(all.met);
  EXPECT_TRUE(core.met);
  EXPECT_NEAR(m.tissue().gel_area_removed_mm2, all0 - all1, 1e-6 * all0);
  EXPECT_TRUE(check_surface(gs).ok());
}

TEST(Criteria, GelRemovedCoreIsRefusedWithAnyOtherTarget) {
  SceneDescription d = case_scene(true);
  d.criteria.push_back({CriterionKind::kGelRemoved, "cortex", 0.3});
  EXPECT_THROW((void)build_scene(d, {false, false}), InvalidArgument);
}

TEST(Criteria, PathCutIsTheShareOfTheGuideAlongANewCut) {
  Scene scene = build();
  SessionMetrics m(scene, nullptr);
  const Guide& line = scene.guides[0];
  ASSERT_EQ(line.name, "line");
  Cutter cutter(scene.world.surface(scene.retina));
  // A blade across the retina (radially) swept along the guide.
  const auto blade = [](const Vec3& p) { return BladeEdge{p - 0.6 * p.normalized(), p + 0.6 * p.normalized()}; };
  const std::size_t half = line.polyline_mm.size() / 2;
  double total = 0.0, first = 0.0;
  for (std::size_t k = 0; k + 1 < line.polyline_mm.size(); ++k) {
    const double len = (line.polyline_mm[k + 1] - line.polyline_mm[k]).norm();
    total += len;
    if (k < half) first += len;
  }
  EXPECT_EQ(find(m.criteria(), CriterionKind::kPathCut).value, 0.0);
  // A cut elsewhere (parallel, 15° nearer the pole) makes new boundary but none near the guide.
  constexpr double kDeg = std::numbers::pi / 180.0;
  for (double az = 200.0; az < 240.0; az += 2.0) {
    ASSERT_TRUE(cutter.sweep(blade(scene.eye.wall_point(25.0 * kDeg, az * kDeg)), blade(scene.eye.wall_point(25.0 * kDeg, (az + 2.0) * kDeg))).status);
  }
  EXPECT_EQ(find(m.criteria(), CriterionKind::kPathCut).value, 0.0);
  for (std::size_t k = 0; k < half; ++k) {
    ASSERT_TRUE(cutter.sweep(blade(line.polyline_mm[k]), blade(line.polyline_mm[k + 1])).status);
  }
  auto cut = find(m.criteria(), CriterionKind::kPathCut);
  // The cut part, plus up to the tolerance beyond the crack tip.
  EXPECT_GE(cut.value, first / total - 0.02);
  EXPECT_LE(cut.value, (first + 0.25) / total + 0.02);
  EXPECT_FALSE(cut.met);
  for (std::size_t k = half; k + 1 < line.polyline_mm.size(); ++k) {
    ASSERT_TRUE(cutter.sweep(blade(line.polyline_mm[k]), blade(line.polyline_mm[k + 1])).status);
  }
  cut = find(m.criteria(), CriterionKind::kPathCut);
  EXPECT_GT(cut.value, 0.97);
  EXPECT_TRUE(cut.met);
  EXPECT_TRUE(check_surface(scene.world.surface(scene.retina)).ok());
}

TEST(Criteria, LaserCoverageCountsTheRingUnderAdheredBurns) {
  Scene scene = build();
  const SclerotomyPort* port = nullptr;
  for (const auto& p : scene.eye.ports) {
    if (p.name == "working_2") port = &p;
  }
  ASSERT_NE(port, nullptr);
  InstrumentSceneOptions o;
  o.ports_mm = {port->inner_mm};
  o.retina_surface = scene.retina;
  Simulation sys(scene.world, o, {{InstrumentKind::kEndolaser, Gauge::k23, 0, {}}});
  sys.set_eye_fixture_rotation(Quat::Identity());
  SessionMetrics m(scene, &sys);
  const Guide& ring = scene.guides[1];
  ASSERT_EQ(ring.kind, GuideKind::kLaserRing);
  const double lift = 0.5 * scene.eye.parameters.retina_thickness_mm;  // the guide lies this far inside
  const auto fire = [&](const Vec3& target) {
    const Vec3 dir = (target - o.ports_mm[0]).normalized();
    InstrumentInput in = InstrumentInput::through_port(o.ports_mm[0], dir, 4.0);
    in.laser_power_mw = 800.0;  // 80 mJ: four times the reference energy, a 0.4 mm spot
    in.laser_duration_s = 0.1;
    ASSERT_TRUE(sys.set_input(0, in));
    sys.step(kDt);
    ASSERT_TRUE(m.observe(kDt));
    in.trigger = true;
    ASSERT_TRUE(sys.set_input(0, in));
    sys.step(kDt);
    ASSERT_TRUE(m.observe(kDt));
  };
  const auto on_ring = [&](std::size_t k) { return Vec3(ring.polyline_mm[k] + lift * ring.polyline_mm[k].normalized()); };
  // Half the ring, a spot at every other polyline point (closer than a spot diameter).
  const std::size_t n = ring.polyline_mm.size() - 1;  // closed: the last point is the first
  for (std::size_t k = 0; k <= n / 2; k += 2) fire(on_ring(k));
  ASSERT_EQ(sys.burns().size(), n / 4 + 1);
  for (const auto& b : sys.burns()) {
    EXPECT_TRUE(b.adhered);
    EXPECT_NEAR(b.diameter_mm, 0.4, 1e-9);
  }
  double arc = 0.0, half_arc = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    const double len = (ring.polyline_mm[k + 1] - ring.polyline_mm[k]).norm();
    arc += len;
    if (k < n / 2) half_arc += len;
  }
  // Reference: the half ring plus a spot radius beyond each end.
  auto cov = find(m.criteria(), CriterionKind::kLaserCoverage);
  EXPECT_NEAR(cov.value, (half_arc + 0.4) / arc, 0.05);
  EXPECT_FALSE(cov.met);
  EXPECT_EQ(m.totals().burns_on_target, n / 4 + 1);
  EXPECT_EQ(m.totals().burns_elsewhere, 0u);
  for (std::size_t k = n / 2 + 2; k < n; k += 2) fire(on_ring(k));
  cov = find(m.criteria(), CriterionKind::kLaserCoverage);
  EXPECT_GT(cov.value, 0.97);
  EXPECT_TRUE(cov.met);
  // A stray spot far from the ring counts as elsewhere.
  fire(scene.eye.wall_point(40.0 * std::numbers::pi / 180.0, 150.0 * std::numbers::pi / 180.0));
  EXPECT_EQ(m.totals().burns_elsewhere, 1u);
  EXPECT_EQ(m.totals().count(InstrumentEventKind::kLaserBurn), sys.burns().size());
}

TEST(Criteria, DrainedRetinaFlatAndTimeLimit) {
  Scene scene = build();
  CaseProgress p(scene.world, MetricsCase::from_scene(scene));
  p.evaluate(scene.world, nullptr, 0.0);
  // The tear's flap stands off the wall: the same lift as the scene's own measure.
  auto flat = find(p.criteria(), CriterionKind::kRetinaFlat);
  EXPECT_EQ(flat.value, max_retina_lift_mm(scene));
  EXPECT_GT(flat.value, 0.5);
  EXPECT_FALSE(flat.met);

  const std::uint32_t fluid = scene.detachment_forces[0];
  ASSERT_TRUE(scene.world.set_local_force_scale(fluid, 0.5));
  p.evaluate(scene.world, nullptr, 0.0);
  auto drained = find(p.criteria(), CriterionKind::kDrained);
  EXPECT_EQ(drained.value, 0.5);
  EXPECT_NEAR(drained.progress, 0.5 / 0.95, 1e-12);
  EXPECT_FALSE(drained.met);
  ASSERT_TRUE(scene.world.set_local_force_scale(fluid, 0.0));

  // Lay every free retina vertex on the wall.
  Surface& rs = scene.world.surface(scene.retina);
  const GlobeWall& wall = scene.world.wall();
  for (std::uint32_t v = 0; v < rs.vertex_slots(); ++v) {
    if (!rs.vertex_alive(v) || rs.is_fixed(v)) continue;
    const Vec3 d = rs.position(v).normalized();
    ASSERT_TRUE(rs.set_position(rs.vertex_id(v), d * wall.radius_toward(d)));
  }
  p.evaluate(scene.world, nullptr, 30.0);
  flat = find(p.criteria(), CriterionKind::kRetinaFlat);
  EXPECT_EQ(flat.value, max_retina_lift_mm(scene));
  EXPECT_LT(flat.value, 0.3);
  EXPECT_TRUE(flat.met);
  EXPECT_EQ(flat.progress, 1.0);
  drained = find(p.criteria(), CriterionKind::kDrained);
  EXPECT_TRUE(drained.met);
  EXPECT_EQ(drained.progress, 1.0);

  auto time = find(p.criteria(), CriterionKind::kTimeLimit);
  EXPECT_TRUE(time.met);
  EXPECT_DOUBLE_EQ(time.progress, 0.5);  // half the time left
  p.evaluate(scene.world, nullptr, 61.0);
  time = find(p.criteria(), CriterionKind::kTimeLimit);
  EXPECT_FALSE(time.met);
  EXPECT_EQ(time.progress, 0.0);
}

TEST(Criteria, TargetsReachedCountsTheTargetsInTheirOrder) {
  SceneDescription d = case_scene(false);
  GuideSpec targets;
  targets.name = "targets";
  targets.kind = GuideKind::kTarget;
  targets.points = {{20.0, 0.0}, {30.0, 90.0}, {25.0, 200.0}};
  d.guides.push_back(targets);
  d.criteria = {{CriterionKind::kTargetsReached, "targets", 1.0}};
  Scene scene = build_scene(d, {false, false});
  CaseProgress p(scene.world, MetricsCase::from_scene(scene));
  // Reference positions from the eye's own mapping: the wall under each target, and heights along
  // the direction from the globe's centre.
  const Vec3 c = scene.world.wall().center();
  auto above = [&](const FundusLocation& at, double height_mm, double sideways_mm = 0.0) {
    const Vec3 w = scene.eye.wall_point(at.polar_deg * std::numbers::pi / 180.0, at.azimuth_deg * std::numbers::pi / 180.0);
    const Vec3 in = (c - w).normalized();
    const Vec3 side = in.cross(Vec3::UnitZ()).normalized();
    return Vec3(w + height_mm * in + sideways_mm * side);
  };
  auto value = [&](double t) {
    p.evaluate(scene.world, nullptr, t);
    return p.criteria().front().value;
  };
  EXPECT_EQ(value(0.0), 0.0);
  p.observe_tip(scene.world, above(targets.points[1], 0.5));  // out of turn: nothing
  EXPECT_EQ(value(1.0), 0.0);
  p.observe_tip(scene.world, above(targets.points[0], 0.8));
  EXPECT_DOUBLE_EQ(value(2.0), 1.0 / 3.0);
  p.observe_tip(scene.world, above(targets.points[1], 1.3));  // too high over it
  EXPECT_DOUBLE_EQ(value(3.0), 1.0 / 3.0);
  p.observe_tip(scene.world, above(targets.points[1], 0.9, 0.3));  // inside its ring, low enough
  EXPECT_DOUBLE_EQ(value(4.0), 2.0 / 3.0);
  p.observe_tip(scene.world, above(targets.points[2], 0.5, 0.6));  // beside its ring
  EXPECT_DOUBLE_EQ(value(5.0), 2.0 / 3.0);
  EXPECT_FALSE(p.criteria().front().met);
  p.observe_tip(scene.world, above(targets.points[2], 0.2));
  EXPECT_EQ(value(6.0), 1.0);
  EXPECT_TRUE(p.criteria().front().met);
  // The renderer's progress along the guide: every target reached.
  ASSERT_EQ(p.guide_samples().size(), 1u);
  EXPECT_EQ(p.guide_samples()[0].covered, std::vector<std::uint8_t>(3, 1));
}

TEST(Criteria, TargetsMustExistAndFitTheKind) {
  Scene scene = build();
  MetricsCase c = MetricsCase::from_scene(scene);
  c.criteria = {{CriterionKind::kLaserCoverage, "line", 0.5}};  // a cut path is not a laser ring
  EXPECT_THROW(CaseProgress(scene.world, c), InvalidArgument);
  c.criteria = {{CriterionKind::kDrained, "nowhere", 0.5}};
  EXPECT_THROW(CaseProgress(scene.world, c), InvalidArgument);
  c.criteria = {{CriterionKind::kTargetsReached, "line", 1.0}};  // a cut path has no targets
  EXPECT_THROW(CaseProgress(scene.world, c), InvalidArgument);
  c.criteria = {{CriterionKind::kGelRemoved, "", 0.5}};  // this scene has no gel
  EXPECT_THROW(CaseProgress(scene.world, c), InvalidArgument);
  ProgressOptions bad;
  bad.path_tolerance_mm = 0.0;
  c.criteria.clear();
  EXPECT_THROW(CaseProgress(scene.world, c, bad), InvalidArgument);
}

}  // namespace
}  // namespace vitreo::core
