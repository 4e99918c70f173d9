// The surgeon's view of shipped cases through the rig's real path (SimulationModel → capture_view →
// FrameBuilder → StereoRenderer on Mesa): each cue checked for what it must show, measured in the
// image against the simulation's own geometry, and — where a cue can be taken away — the frames
// with and without it differ where it is and only there.
//   - the guide is where the case puts it and turns colour where the laser covered it;
//   - the aiming spot sits at the laser's ray hit;
//   - the forceps' jaw gap in the image follows the handle;
//   - the detached retina is greyer and its disparity says it is nearer than the wall;
//   - the gel's haze is gone where the vitrector removed gel, and only there;
//   - cut and torn edges roll whiter; labels change only their own pixels;
//   - the microscope (pedal joystick, zoom, focus, commands) is simulation state the picture follows;
//   - the vitrector's guillotine flickers across its port at the cut rate.
#include <gtest/gtest.h>

#include <array>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "core/instruments/instrument.hpp"
#include "fixed_poses.hpp"
#include "image_checks.hpp"
#include "rig/session/frame_source.hpp"
#include "synthetic_scene.hpp"
#include "vitreo/render/egl_context.hpp"
#include "vitreo/render/renderer.hpp"

using namespace vitreo;
namespace vr = vitreo::render;
namespace vt = vitreo::render::testing;

namespace {

const std::string kScenes = std::string(VITREO_SOURCE_DIR) + "/scenes";

vr::Vec3 to_r(const core::Vec3& v) { return {float(v.x()), float(v.y()), float(v.z())}; }

class CaseCues : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    vr::EglOptions o;
    o.honour_environment = false;
    context_ = new vr::EglContext(o);
  }
  static void TearDownTestSuite() {
    delete context_;
    context_ = nullptr;
  }
  static vr::StereoFrame render(const vr::FrameScene& s, int w, int h) {
    vr::StereoRenderer r(vr::RenderSettings{w, h, 512, 512});
    vr::StereoFrame f;
    r.render(s, f);
    return f;
  }
  // One snapshot reused, as the session's triple buffer does (a case brings three spare buffers).
  vr::FrameScene capture(rig::SimulationModel& model, rig::FrameBuilder& builder) {
    EXPECT_TRUE(rig::capture_view(model, model.steps(), static_cast<double>(model.steps()) * 1e-3, view_));
    return builder.build(view_);
  }
  rig::ViewSnapshot view_;
  static void step_until(rig::SimulationModel& model, auto done, int limit = 5000) {
    for (int i = 0; i < limit && !done(); ++i) model.step();
  }
  static vr::EglContext* context_;
};
vr::EglContext* CaseCues::context_ = nullptr;

std::unique_ptr<rig::testing::CaseUnderTest> load(const std::string& name) {
  return std::make_unique<rig::testing::CaseUnderTest>(kScenes + "/" + name + ".toml", 2000,
                                                         std::string(VITREO_CASE_CACHE_DIR));
}

}  // namespace

// The laser ring of the laser exercise is drawn where the case defines it (on the fundus around the
// tear), in the guide's colour; the labels toggle takes it away (and only it and the labels); a
// burn placed on the ring turns the part of the ring it covers blue once the criteria are measured.
TEST_F(CaseCues, GuideIsWhereTheCasePutsItAndShowsTheLaseredPart) {
  auto c = load("exercise_laser_tear");
  rig::SimulationModel& model = c->model;
  ASSERT_TRUE(rig::testing::place_at_fixed_poses(model));
  rig::FrameBuilder builder;
  const vr::FrameScene scene = capture(model, builder);
  const core::Guide& ring = model.scene().guides.at(0);
  constexpr int kW = 320, kH = 256;
  const vr::Image with = render(scene, kW, kH).eye(0);
  // Every ring point in the frame shows the guide's yellow (the line is ~3 px wide here).
  int in_frame = 0, yellow = 0;
  std::vector<vr::Vec2> ring_px;
  for (const core::Vec3& p : ring.polyline_mm) {
    const vr::Vec2 px = vt::project_to_pixel(scene, 0, to_r(p), kW, kH);
    if (px.x < 2 || px.y < 2 || px.x > kW - 3 || px.y > kH - 3) continue;
    ring_px.push_back(px);
    ++in_frame;
    const vt::Rgb c0 = vt::patch(with, px, 0);
    yellow += (c0.r > 150 && c0.g > 120 && c0.b < 0.6 * c0.g);
  }
  std::printf("ring: %d of %zu points in the frame, %d of them yellow\n", in_frame, ring.polyline_mm.size(), yellow);
  EXPECT_GE(in_frame, static_cast<int>(ring.polyline_mm.size()) * 9 / 10) << "the whole ring is in view";
  EXPECT_GE(yellow, in_frame * 75 / 100) << "(the laser probe and the labels cover a few)";
  // The labels toggle: the guide and the labels go, nothing else changes.
  ASSERT_TRUE(model.apply(rig::testing::command_input(8)));
  const vr::FrameScene hidden = capture(model, builder);
  EXPECT_TRUE(hidden.labels.empty());
  EXPECT_TRUE(std::none_of(hidden.meshes.begin(), hidden.meshes.end(), [](const vr::Mesh& m) { return m.material == vr::MaterialKind::Guide; }));
  const vr::Image without_guide = render(hidden, kW, kH).eye(0);
  const vt::Mask m = vt::diff_mask(with, without_guide, 16);
  std::vector<vr::Vec2> allowed = ring_px;
  for (const vr::Label& l : scene.labels) {
    const vr::Vec2 a = vt::project_to_pixel(scene, 0, l.anchor_mm, kW, kH);
    for (int k = 0; k < static_cast<int>(l.text.size()) + 2; ++k) allowed.push_back({a.x + 6.0f * k, a.y});
  }
  std::printf("labels toggle: %d pixels changed, %.3f of them on the ring or a label\n", m.count(), m.fraction_near(allowed, 6.0f));
  EXPECT_GT(m.fraction_near(allowed, 6.0f), 0.97) << "the toggle changes the guide and labels only";
  ASSERT_TRUE(model.apply(rig::testing::command_input(8)));

  // Laser a spot on the ring: aim the endolaser at a ring point and fire once.
  const core::Vec3 target = ring.polyline_mm[16];
  const rig::PreparedCase& pc = model.current_case();
  const core::Vec3 tp = pc.tracker_ports[rig::kToolTracker].position_mm;
  ASSERT_TRUE(model.apply(rig::testing::tracker_sample(rig::kToolTracker, target - 4.0 * (target - tp).normalized(), 0.0)));
  model.step();
  ASSERT_TRUE(model.apply(rig::testing::pedal_input(0, 0, 0, 0, 0, 1 << 1)));  // laser switch
  model.step();
  ASSERT_TRUE(model.apply(rig::testing::pedal_input(0, 0, 0, 0, 0, 0)));
  for (int i = 0; i < 400; ++i) model.step();  // the criteria are measured again for the picture
  ASSERT_TRUE(rig::testing::place_at_fixed_poses(model));  // the probe back, its aiming spot off the burn
  ASSERT_EQ(model.simulation().burns().size(), 1u);
  ASSERT_TRUE(model.simulation().burns()[0].adhered) << "attached retina: the burn adheres";
  vr::FrameScene after = capture(model, builder);
  after.microscope.depth_of_field = false;  // the colours of a thin line, not blurred into the burn
  const vr::Mesh* guide = nullptr;
  for (const auto& mesh : after.meshes)
    if (mesh.material == vr::MaterialKind::Guide) guide = &mesh;
  ASSERT_NE(guide, nullptr);
  // Done (highlight 1) exactly along the part of the ring within a spot radius of the burn.
  const core::Vec3 burn = model.simulation().burn_position(model.simulation().burns()[0]);
  const double r = 0.5 * model.simulation().burns()[0].diameter_mm;
  int done_near = 0, done_far = 0;
  for (const auto& v : guide->geometry->vertices) {
    const core::Vec3 p(v.position_mm.x, v.position_mm.y, v.position_mm.z);
    const double d = core::tangential_distance(p, burn, burn);
    if (v.highlight > 0.5) (d <= r + 0.15 ? done_near : done_far)++;
  }
  std::printf("ring vertices shown done: %d near the burn, %d elsewhere\n", done_near, done_far);
  EXPECT_GT(done_near, 0);
  EXPECT_EQ(done_far, 0);
  const vr::Image lasered = render(after, kW, kH).eye(0);
  // Where the ring is done (over the burn: the guide is drawn over the tissue) it is blue now; half
  // a ring away it is yellow.
  vr::Vec3 done_at{};
  int n_done = 0;
  for (const auto& v : guide->geometry->vertices)
    if (v.highlight > 0.5f) done_at = done_at + v.position_mm, ++n_done;
  done_at = done_at * (1.0f / static_cast<float>(n_done));
  const vt::Rgb b = vt::patch(lasered, vt::project_to_pixel(after, 0, done_at, kW, kH), 0);
  const vt::Rgb y = vt::patch(lasered, vt::project_to_pixel(after, 0, to_r(ring.polyline_mm[48]), kW, kH), 0);
  std::printf("ring at the burn: (%.0f %.0f %.0f), across the ring (%.0f %.0f %.0f)\n", b.r, b.g, b.b, y.r, y.g, y.b);
  EXPECT_GT(b.b, b.r + 30.0) << "the lasered part of the ring is blue";
  EXPECT_GT(y.r, y.b + 60.0) << "the rest still yellow";
}

// The aiming spot: where the core's ray from the laser's tip along its shaft meets the retina (an
// independent check that the hit is on that ray and on the tissue), the image shows a green spot —
// in both eyes at that point's own pixel — and the spot is the only thing the aiming spot adds.
TEST_F(CaseCues, AimingSpotSitsAtTheLasersRayHit) {
  auto c = load("exercise_laser_tear");
  rig::SimulationModel& model = c->model;
  const rig::PreparedCase& pc = model.current_case();
  const core::Vec3 aim_at = model.scene().eye.wall_point(64.0 * std::numbers::pi / 180.0, 300.0 * std::numbers::pi / 180.0);
  const core::Vec3 tp = pc.tracker_ports[rig::kToolTracker].position_mm;
  ASSERT_TRUE(model.apply(rig::testing::tracker_sample(rig::kToolTracker, aim_at - 4.5 * (aim_at - tp).normalized(), 0.0)));
  for (int i = 0; i < 3; ++i) model.step();
  const core::InstrumentState& laser = model.simulation().instrument(0);
  ASSERT_EQ(laser.description.kind, core::InstrumentKind::kEndolaser);
  ASSERT_TRUE(laser.aim_hit);
  const core::Vec3 hit = laser.aim_point_mm;
  const core::Vec3 along = hit - laser.frame.tip;
  EXPECT_LT((along - along.dot(laser.frame.u) * laser.frame.u).norm(), 1e-6) << "on the shaft's ray";
  EXPECT_GT(along.dot(laser.frame.u), 0.0);
  const double clearance = model.scene().eye.wall.clearance(hit);
  EXPECT_LT(clearance, 0.5) << "on the retina lying on the wall (clearance " << clearance << " mm)";
  rig::FrameBuilder builder;
  ASSERT_TRUE(model.apply(rig::testing::command_input(8)));  // no labels over the spot
  const vr::FrameScene scene = capture(model, builder);
  // The spot is the glow placed in the eye frame (identity placement) at the hit.
  const vr::FrameScene no_spot = vt::without(scene, [](const vr::Mesh& m) {
    return m.material == vr::MaterialKind::Glow && m.model.m == vr::Mat4::identity().m;
  });
  ASSERT_EQ(no_spot.meshes.size() + 1, scene.meshes.size());
  constexpr int kW = 320, kH = 256;
  const vr::StereoFrame a = render(scene, kW, kH), b = render(no_spot, kW, kH);
  for (int e = 0; e < 2; ++e) {
    const vt::Mask m = vt::diff_mask(a.eye(e), b.eye(e), 20);
    const vr::Vec2 expected = vt::project_to_pixel(scene, e, to_r(hit), kW, kH);
    const vr::Vec2 got = m.centroid();
    std::printf("eye %d: aiming spot at (%.1f, %.1f), the ray hit projects to (%.1f, %.1f), %d pixels\n", e, got.x, got.y, expected.x,
                expected.y, m.count());
    ASSERT_GT(m.count(), 2);
    EXPECT_NEAR(got.x, expected.x, 1.5);
    EXPECT_NEAR(got.y, expected.y, 1.5);
    EXPECT_GT(m.fraction_near({expected}, 5.0f), 0.99) << "the spot adds light there only";
    const vt::Rgb with = vt::patch(a.eye(e), expected, 0), none = vt::patch(b.eye(e), expected, 0);
    EXPECT_GT(with.g - none.g, with.r - none.r) << "green";
  }
}

// The forceps' jaws in the image open and close with the handle: the gap between them measured in
// the picture (the instrument's own pixels: the frame with and without it) is the core's jaw gap
// projected, and shrinks to nothing as the handle closes.
TEST_F(CaseCues, ForcepsJawGapInTheImageFollowsTheHandle) {
  auto c = load("exercise_pull_tissue");
  rig::SimulationModel& model = c->model;
  const rig::PreparedCase& pc = model.current_case();
  ASSERT_EQ(pc.tools.at(0), core::InstrumentKind::kForceps);
  const core::Vec3 tp = pc.tracker_ports[rig::kToolTracker].position_mm;
  const core::Vec3 tip = pc.focus_mm - 1.2 * (pc.focus_mm - tp).normalized();
  ASSERT_TRUE(model.apply(rig::testing::command_input(9, 3.0)));  // zoom in
  ASSERT_TRUE(model.apply(rig::testing::command_input(8)));       // no labels
  step_until(model, [&] { return model.microscope().zoom() == 3.0; });
  constexpr int kW = 320, kH = 256;
  rig::FrameBuilder builder;
  // Roll the forceps so its jaws open across the line of sight (v ⊥ the shaft and the view): the
  // tracker's x axis, across the shaft, sets the roll.
  const core::Vec3 pupil(0.0, 0.0, pc.visuals->camera_z_mm);  // where the picture is seen from
  const core::Vec3 u = (tip - pc.tracker_ports[rig::kToolTracker].position_mm).normalized();
  const core::Vec3 across = u.cross((tip - pupil).normalized()).normalized();
  const core::Quat roll = core::Quat::FromTwoVectors(core::Vec3::UnitX(), across);
  double last_gap = 1e9;
  for (double act : {0.0, 0.5, 1.0}) {
    ASSERT_TRUE(model.apply(rig::testing::tracker_sample(rig::kToolTracker, tip, act, roll)));
    model.step();
    const core::InstrumentState& st = model.simulation().instrument(0);
    vr::FrameScene s = capture(model, builder);
    for (auto& mesh : s.meshes) mesh.casts_shadow = false;  // the jaws' own pixels, not their shadow
    const vr::Image with = render(s, kW, kH).eye(0);
    // The jaws: the tool's second mesh (frame_source ids: 200 + its slot, then its parts in order).
    const vr::Image none = render(vt::without(s, [](const vr::Mesh& m) { return m.id % 1000 == 201; }), kW, kH).eye(0);
    const vt::Mask tool = vt::diff_mask(with, none, 12);
    // In the image: each jaw's pixels on its side of the shaft's axis; the jaw's tip is its pixel
    // farthest from the hinge. Their distance is the opening the surgeon sees.
    const vr::Vec2 h = vt::project_to_pixel(s, 0, to_r(st.tip.hinge), kW, kH);
    const vr::Vec2 ahead = vt::project_to_pixel(s, 0, to_r(st.tip.hinge + st.frame.u), kW, kH);
    const vr::Vec2 axis{ahead.x - h.x, ahead.y - h.y};
    vr::Vec2 far[2] = {h, h};
    float far_d[2] = {0.0f, 0.0f};
    for (int y = 0; y < kH; ++y) {
      for (int x = 0; x < kW; ++x) {
        if (!tool.at(x, y)) continue;
        const float side = axis.x * (y - h.y) - axis.y * (x - h.x);
        const int k = side >= 0.0f ? 0 : 1;
        const float d = std::hypot(x - h.x, y - h.y);
        if (d > far_d[k]) far_d[k] = d, far[k] = {float(x), float(y)};
      }
    }
    const double gap = (far_d[0] > 0.0f && far_d[1] > 0.0f) ? std::hypot(far[0].x - far[1].x, far[0].y - far[1].y) : 0.0;
    // The core's jaws end at parts[1].b and parts[2].b; their outer faces a jaw radius beyond, away
    // from each other (the image's farthest pixels are there).
    const double half = st.description.dimensions.jaw_open_deg * std::numbers::pi / 180.0 * (1.0 - act);
    const double jr = st.description.dimensions.jaw_radius_mm;
    const core::Vec3 out1 = std::cos(half) * st.frame.v - std::sin(half) * st.frame.u;  // jaw 1 opens toward +v
    const core::Vec3 out2 = -std::cos(half) * st.frame.v - std::sin(half) * st.frame.u;
    const vr::Vec2 c1 = vt::project_to_pixel(s, 0, to_r(st.tip.parts[1].b + jr * out1), kW, kH);
    const vr::Vec2 c2 = vt::project_to_pixel(s, 0, to_r(st.tip.parts[2].b + jr * out2), kW, kH);
    const double expected = std::hypot(c1.x - c2.x, c1.y - c2.y);
    std::printf("actuation %.1f: core jaw gap %.3f mm; jaw tips %.1f px apart in the image, the core's jaws' outer tips project %.1f px apart\n", act,
                st.tip.jaw_gap_mm, gap, expected);
    EXPECT_NEAR(gap, expected, 8.0) << "within a jaw's thickness seen obliquely (~0.13 mm here)";
    EXPECT_LE(gap, last_gap) << "closing the handle closes the jaws";
    last_gap = gap;
  }
  EXPECT_LE(last_gap, 10.0) << "closed: the two jaws' tips together";
}

// A bullous detachment: the lifted retina (detachment ≥ 0.9) is greyer than the same frame without
// the detachment shading, and the two eyes place it at a disparity measured by block matching in the
// images that matches the lifted retina's own depth — nearer than the wall beneath it.
TEST_F(CaseCues, DetachedRetinaIsGreyerAndItsDisparitySaysItIsNearer) {
  auto c = load("rhegmatogenous_u_tear");
  rig::SimulationModel& model = c->model;
  ASSERT_TRUE(rig::testing::place_at_fixed_poses(model));
  ASSERT_TRUE(model.apply(rig::testing::command_input(8)));  // labels off: they would be matched too
  rig::FrameBuilder builder;
  vr::FrameScene scene = capture(model, builder);
  scene = vt::without(scene, [](const vr::Mesh& m) { return m.material == vr::MaterialKind::Instrument || m.material == vr::MaterialKind::Glow; });
  scene.microscope.depth_of_field = false;  // sharp in both eyes, for the matching
  constexpr int kW = 320, kH = 256;
  const vr::StereoFrame f = render(scene, kW, kH);
  const vr::Image left = f.eye(0), right = f.eye(1);
  const vr::Mesh* retina = nullptr;
  for (const auto& m : scene.meshes)
    if (m.material == vr::MaterialKind::Retina) retina = &m;
  ASSERT_NE(retina, nullptr);
  // The most textured detached spot in view (block matching needs detail), away from the tear's
  // edges (its flap stands higher than the retina around it).
  std::vector<vr::Vec3> rims;
  for (const auto& v : retina->geometry->vertices)
    if (v.highlight > 0.0f) rims.push_back(v.position_mm);
  vr::Vec3 best{};
  double best_detail = -1.0;
  for (const auto i : retina->geometry->indices) {
    const auto& v = retina->geometry->vertices[i];
    if (v.detachment < 0.9f) continue;
    if (std::any_of(rims.begin(), rims.end(), [&](const vr::Vec3& q) { return length(q - v.position_mm) < 0.8f; })) continue;
    const vr::Vec2 px = vt::project_to_pixel(scene, 0, v.position_mm, kW, kH);
    if (px.x < 25 || px.y < 10 || px.x > kW - 25 || px.y > kH - 10) continue;
    const double d = vt::detail(left, int(px.x) - 4, int(px.y) - 4, int(px.x) + 5, int(px.y) + 5);
    if (d > best_detail) best_detail = d, best = v.position_mm;
  }
  ASSERT_GT(best_detail, 0.0) << "detached retina in view";
  const vr::Vec2 l = vt::project_to_pixel(scene, 0, best, kW, kH), r = vt::project_to_pixel(scene, 1, best, kW, kH);
  // Block matching along the row (sum of squared differences, sub-pixel by a parabola).
  auto ssd = [&](int dx) {
    double s = 0;
    for (int y = -4; y <= 4; ++y)
      for (int x = -4; x <= 4; ++x) {
        const std::uint8_t* p = &left.rgba[(static_cast<std::size_t>(int(l.y) + y) * kW + int(l.x) + x) * 4];
        const std::uint8_t* q = &right.rgba[(static_cast<std::size_t>(int(l.y) + y) * kW + int(l.x) + x - dx) * 4];
        for (int k = 0; k < 3; ++k) s += (p[k] - q[k]) * (p[k] - q[k]);
      }
    return s;
  };
  int arg = 0;
  double lowest = 1e300;
  for (int dx = -15; dx <= 15; ++dx) {
    const double v = ssd(dx);
    if (v < lowest) lowest = v, arg = dx;
  }
  const double s0 = ssd(arg - 1), s1 = ssd(arg), s2 = ssd(arg + 1);
  const double measured = arg + 0.5 * (s0 - s2) / std::max(s0 - 2 * s1 + s2, 1e-9);
  const core::Vec3 p(best.x, best.y, best.z);
  const vr::Vec3 wall = to_r(model.scene().eye.wall.radius_toward(p) * p.normalized());
  const double lifted = l.x - r.x;
  const double on_wall = vt::project_to_pixel(scene, 0, wall, kW, kH).x - vt::project_to_pixel(scene, 1, wall, kW, kH).x;
  std::printf("detached retina %.2f mm off the wall: disparity measured %.2f px, its depth gives %.2f px, the wall's %.2f px\n",
              model.scene().eye.wall.clearance(p), measured, lifted, on_wall);
  EXPECT_GT(lifted - on_wall, 1.0) << "the lift is large enough to be seen in depth";
  EXPECT_NEAR(measured, lifted, 0.75);
  EXPECT_GT(measured, on_wall + 0.5 * (lifted - on_wall)) << "nearer than the wall (crossed disparity)";
  // Greyer than the same frame without the detachment shading.
  const vr::FrameScene flat = vt::without_detachment_shading(scene);
  const vt::Rgb shaded = vt::patch(left, l, 2), unshaded = vt::patch(render(flat, kW, kH).eye(0), l, 2);
  std::printf("detached patch saturation %.2f vs %.2f without the shading\n", shaded.spread() / shaded.luma(), unshaded.spread() / unshaded.luma());
  EXPECT_LT(shaded.spread() / shaded.luma(), 0.8 * unshaded.spread() / unshaded.luma());
}

// Gel removal is visible: the vitrector's removal (core/topology, what the instrument system hands
// it at each cut) takes a patch out of the stained gel over the region of interest; the frame after
// shows less of the white haze exactly where gel was removed, and is unchanged away from it.
// (The removal is driven directly, port after port across the patch: whether suction brings gel
// to a given port in a given number of steps is the tissue's business, tested in core/.)
TEST_F(CaseCues, GelHazeIsGoneWhereTheVitrectorRemovedGel) {
  auto c = load("exercise_remove_gel");
  rig::SimulationModel& model = c->model;
  const rig::PreparedCase& pc = model.current_case();
  const std::uint32_t gel = model.scene().gel;
  ASSERT_NE(gel, core::kNone);
  ASSERT_TRUE(model.apply(rig::testing::command_input(8)));  // no labels
  ASSERT_TRUE(rig::testing::place_at_fixed_poses(model));
  const core::Surface& g0 = model.world().surface(gel);
  const std::uint32_t triangles_before = g0.triangle_count();
  // The inner shell's vertex nearest the region of interest's direction.
  core::Vec3 target = core::Vec3::Zero();
  double best = 1e9;
  for (std::uint32_t v = 0; v < g0.vertex_slots(); ++v) {
    if (!g0.vertex_alive(v)) continue;
    const core::Vec3 p = g0.position(v);
    const double off = (p.normalized() - pc.focus_mm.normalized()).norm() + 0.05 * std::abs(p.norm() - 8.0);
    if (off < best) best = off, target = p;
  }
  rig::FrameBuilder builder;
  const vr::FrameScene before = capture(model, builder);
  auto alive_points = [&](const core::Surface& g) {  // corners of the live triangles
    std::vector<core::Vec3> out;
    for (std::uint32_t t = 0; t < g.triangle_slots(); ++t) {
      if (!g.triangle_alive(t)) continue;
      for (const auto v : g.triangle_vertices(t)) out.push_back(g.position(v));
    }
    return out;
  };
  const std::vector<core::Vec3> gel_before = alive_points(g0);
  std::vector<std::array<core::Vec3, 3>> triangles0(g0.triangle_slots());  // each live triangle's corners
  std::vector<core::TriangleId> ids0;
  for (std::uint32_t t = 0; t < g0.triangle_slots(); ++t) {
    if (!g0.triangle_alive(t)) continue;
    ids0.push_back(g0.triangle_id(t));
    for (int k = 0; k < 3; ++k) triangles0[t][static_cast<std::size_t>(k)] = g0.position(g0.triangle_vertices(t)[static_cast<std::size_t>(k)]);
  }
  // Ports facing the shell from inside, one cut each, spiralling out from the target vertex to 1 mm
  // (the cutter bites from tissue already at its port outward, as a surgeon works a gel edge).
  const core::Vec3 outward = target.normalized();
  const core::Vec3 e1 = outward.cross(core::Vec3::UnitZ()).normalized(), e2 = outward.cross(e1);
  core::RemovalRequest cut;
  cut.port_normal = outward;
  cut.removal_radius_mm = model.simulation().options().vitrector.removal_radius_mm;
  cut.suction_radius_mm = model.simulation().options().vitrector.field_radius_mm;
  cut.vacuum = 1.0;
  cut.cut_rate_cpm = model.simulation().options().vitrector.cut_rate_cpm;
  cut.dt_s = 2.0 * 60.0 / cut.cut_rate_cpm;  // a cut in each request
  for (int pass = 0; pass < 2; ++pass) {
    for (double radius = 0.0; radius <= 1.0 + 1e-9; radius += 0.15) {
      const int around = std::max(1, static_cast<int>(std::ceil(2.0 * std::numbers::pi * radius / 0.15)));
      for (int k = 0; k < around; ++k) {
        const double a = 2.0 * std::numbers::pi * k / around;
        cut.port_center_mm = target + radius * (std::cos(a) * e1 + std::sin(a) * e2) - 0.1 * outward;
        pc.topology->remove(model.world(), cut);
      }
    }
  }
  ASSERT_TRUE(pc.topology->last_error().is_ok()) << pc.topology->last_error().message();
  model.step();
  const core::Surface& g1 = model.world().surface(gel);
  std::printf("gel triangles: %u before, %u after the vitrector\n", triangles_before, g1.triangle_count());
  ASSERT_GT(pc.topology->removed_mass_g(), 0.0) << "the vitrector removed gel";
  // Where it cut: the patch of the shell within the last port's reach (1 mm + the cutter's radius).
  const vr::FrameScene after = capture(model, builder);
  constexpr int kW = 320, kH = 256;
  auto gel_only = [](vr::FrameScene s) {  // the retina and choroid beneath, the gel: nothing moving in front
    s.microscope.depth_of_field = false;
    return vt::without(s, [](const vr::Mesh& m) { return m.material == vr::MaterialKind::Instrument || m.material == vr::MaterialKind::Glow ||
                                                      (m.material == vr::MaterialKind::Static && m.id % 1000 > 50); });
  };
  const vr::Image a = render(gel_only(before), kW, kH).eye(0), b = render(gel_only(after), kW, kH).eye(0);
  // The gel is aspirated in whole triangles (core/topology/vitrector.hpp): the patch reaches as far as
  // the farthest corner of a triangle that went.
  double reach_mm = 0.0;
  for (const core::TriangleId id : ids0) {
    if (g1.triangle_alive(id.index) && g1.triangle_id(id.index).generation == id.generation) continue;
    for (const core::Vec3& p : triangles0[id.index]) reach_mm = std::max(reach_mm, (p - target).norm());
  }
  ASSERT_GT(reach_mm, 0.0);
  const vr::Vec2 centre = vt::project_to_pixel(before, 0, to_r(target), kW, kH);
  float reach_px = 0.0f;
  for (int k = 0; k < 16; ++k) {
    const double t = 2.0 * std::numbers::pi * k / 16;
    const vr::Vec2 q = vt::project_to_pixel(before, 0, to_r(target + reach_mm * (std::cos(t) * e1 + std::sin(t) * e2)), kW, kH);
    reach_px = std::max(reach_px, std::hypot(q.x - centre.x, q.y - centre.y));
  }
  const vt::Mask m = vt::diff_mask(a, b, 10);
  const vt::Rgb p0 = vt::patch(a, centre, 3), p1 = vt::patch(b, centre, 3);
  std::printf("gel removed %.3g g; at the cut: whiteness %.1f -> %.1f; %d pixels changed, %.3f of them within %.0f px of it\n",
              pc.topology->removed_mass_g(), p0.luma() - p0.spread(), p1.luma() - p1.spread(), m.count(), m.fraction_near({centre}, reach_px + 2.0f),
              reach_px);
  EXPECT_LT(p1.luma() - p1.spread(), p0.luma() - p0.spread() - 3.0) << "less white haze where the gel went";
  EXPECT_GT(m.count(), 20);
  EXPECT_GT(m.fraction_near({centre}, reach_px + 2.0f), 0.97) << "and the haze stays where the gel stays";
}

// Cut edges and tears roll and show whiter: the laser exercise's flat U tear, on attached retina —
// the rim shading (its vertices' highlight) makes the edge whiter, and changes the picture along the
// tear's edge only.
TEST_F(CaseCues, TornEdgeRollsWhiterAlongItsEdgeOnly) {
  auto c = load("exercise_laser_tear");
  rig::SimulationModel& model = c->model;
  ASSERT_TRUE(rig::testing::place_at_fixed_poses(model));
  ASSERT_TRUE(model.apply(rig::testing::command_input(8)));
  rig::FrameBuilder builder;
  vr::FrameScene scene = capture(model, builder);
  scene = vt::without(scene, [](const vr::Mesh& m) { return m.material == vr::MaterialKind::Instrument || m.material == vr::MaterialKind::Glow; });
  vr::FrameScene plain = scene;
  std::vector<vr::Vec3> rim, band;
  double edge_mm = 0.0;
  for (auto& m : plain.meshes) {
    if (m.material != vr::MaterialKind::Retina) continue;
    auto g = std::make_shared<vr::MeshGeometry>(*m.geometry);
    for (const auto i : g->indices) {
      if (g->vertices[i].highlight > 0.9f) rim.push_back(g->vertices[i].position_mm);
      if (g->vertices[i].highlight > 0.0f) band.push_back(g->vertices[i].position_mm);
    }
    for (std::size_t t = 0; t + 2 < g->indices.size(); t += 3)
      edge_mm += length(g->vertices[g->indices[t]].position_mm - g->vertices[g->indices[t + 1]].position_mm);
    edge_mm /= static_cast<double>(g->indices.size() / 3);
    for (auto& v : g->vertices) {
      if (v.highlight > 0.0f) v.position_mm = v.position_mm + normalize(v.position_mm) * (0.08f * v.highlight);  // unrolled
      v.highlight = 0.0f;
    }
    m.geometry = g;
  }
  ASSERT_GT(rim.size(), 6u) << "the tear's edge is marked";
  constexpr int kW = 320, kH = 256;
  const vr::Image a = render(scene, kW, kH).eye(0), b = render(plain, kW, kH).eye(0);
  std::vector<vr::Vec2> edge, shaded;
  for (const vr::Vec3& p : rim) edge.push_back(vt::project_to_pixel(scene, 0, p, kW, kH));
  for (const vr::Vec3& p : band) shaded.push_back(vt::project_to_pixel(scene, 0, p, kW, kH));
  // The shading reaches one triangle in from the edge: as far as a mesh edge, projected.
  const vr::Vec2 e0 = vt::project_to_pixel(scene, 0, rim[0], kW, kH);
  const vr::Vec2 e1 = vt::project_to_pixel(scene, 0, rim[0] + normalize(cross(rim[0], vr::Vec3{0, 0, 1})) * static_cast<float>(edge_mm), kW, kH);
  const float reach_px = std::hypot(e1.x - e0.x, e1.y - e0.y) + 3.0f;
  const vt::Mask m = vt::diff_mask(a, b, 10);
  double lighter = 0;
  int n = 0;
  for (const vr::Vec2& e : edge) {
    if (e.x < 2 || e.y < 2 || e.x > kW - 3 || e.y > kH - 3) continue;
    lighter += vt::patch(a, e, 0).luma() - vt::patch(b, e, 0).luma();
    ++n;
  }
  ASSERT_GT(n, 3);
  std::printf("tear edge: %d points in view, %.1f lighter on average; %d pixels changed, %.3f within %.0f px of the shaded band\n", n,
              lighter / n, m.count(), m.fraction_near(shaded, reach_px), reach_px);
  EXPECT_GT(lighter / n, 20.0);
  EXPECT_GT(m.fraction_near(shaded, reach_px), 0.97);
}

// The microscope is simulation state: the pedal's joystick moves the field at its speed, its zoom
// axis drives the zoom motor, focus and pan commands move focus and field; the frame follows (the
// region of interest moves across the picture the opposite way, magnification scales distances,
// focus blurs what it leaves); two models fed the same inputs agree bit for bit, and the state hash
// sees the microscope.
TEST_F(CaseCues, MicroscopeIsSimulationStateThePictureFollows) {
  auto c1 = load("exercise_pull_tissue");
  auto c2 = load("exercise_pull_tissue");
  rig::SimulationModel& model = c1->model;
  rig::SimulationModel& twin = c2->model;
  rig::FrameBuilder builder;
  ASSERT_TRUE(model.apply(rig::testing::command_input(8)));  // no labels (sharp text would hide the blur)
  ASSERT_TRUE(twin.apply(rig::testing::command_input(8)));
  const vr::FrameScene start = capture(model, builder);
  const vr::Vec3 roi = to_r(model.current_case().focus_mm);
  constexpr int kW = 320, kH = 256;
  const vr::Vec2 c0 = vt::project_to_pixel(start, 0, roi, kW, kH);
  EXPECT_NEAR(c0.x, kW / 2.0f, 3.0f) << "starts centred on the region of interest";
  EXPECT_NEAR(c0.y, kH / 2.0f, 3.0f);
  auto both = [&](const telemetry::RecordedInput& in) {
    EXPECT_TRUE(model.apply(in));
    EXPECT_TRUE(twin.apply(in));
  };
  const std::uint64_t h0 = model.state_hash();
  // Joystick full right for half a second: the field moves 4 mm (pan speed 8 mm/s at zoom 1).
  both(rig::testing::pedal_input(1, 0.0, 0.5, 1.0, 0.5));
  for (int i = 0; i < 500; ++i) model.step(), twin.step();
  both(rig::testing::pedal_input(1, 0.0, 0.5, 0.5, 0.5));
  EXPECT_NE(model.state_hash(), h0);
  EXPECT_NEAR((model.microscope().center_mm() - model.microscope().region_of_interest_mm()).x(), 0.5 * 8.0, 0.01);
  const vr::FrameScene panned = capture(model, builder);
  const vr::Vec2 c1p = vt::project_to_pixel(panned, 0, roi, kW, kH);
  EXPECT_LT(c1p.x, c0.x - 40.0f) << "the field moved right: the region of interest slides left";
  EXPECT_NEAR(c1p.y, c0.y, 12.0f);
  // A pan command back to the region (the X–Y motor travels there).
  both(rig::testing::command_input(10, 0.0, 0.0));
  step_until(model, [&] { return (model.microscope().center_mm() - model.microscope().region_of_interest_mm()).norm() < 1e-9; });
  step_until(twin, [&] { return (twin.microscope().center_mm() - twin.microscope().region_of_interest_mm()).norm() < 1e-9; });
  // The zoom axis of the pedal: full travel → the rig's zoom_max (4), reached by the motor.
  both(rig::testing::pedal_input(1, 1.0, 0.5, 0.5, 0.5));
  step_until(model, [&] { return model.microscope().zoom() == 4.0; });
  step_until(twin, [&] { return twin.microscope().zoom() == 4.0; });
  const vr::FrameScene zoomed = capture(model, builder);
  const vr::Vec3 disc = to_r(model.scene().eye.optic_disc_mm);
  const vr::Vec2 d0 = vt::project_to_pixel(start, 0, disc, kW, kH), d1 = vt::project_to_pixel(zoomed, 0, disc, kW, kH);
  const vr::Vec2 r1 = vt::project_to_pixel(zoomed, 0, roi, kW, kH);
  const double before_px = std::hypot(d0.x - c0.x, d0.y - c0.y), after_px = std::hypot(d1.x - r1.x, d1.y - r1.y);
  std::printf("disc from the field centre: %.1f px at zoom 1, %.1f px at zoom 4\n", before_px, after_px);
  EXPECT_GT(after_px / before_px, 3.0) << "zoom magnifies about the field centre";
  // Focus toward the microscope: within the depth of field the score calls the fundus in focus and
  // the picture is as sharp; at the focus's end of travel (3 mm, beyond the 1.7 mm depth of field at
  // zoom 4) both say it is not.
  const vr::Image sharp = render(zoomed, kW, kH).eye(0);
  const double depth = model.microscope().depth_of_field_mm();
  const core::Vec3 centre_on_fundus = model.microscope().view(model.scene().eye).target_mm;  // the retina's face there
  auto focus_to = [&](double mm) {
    both(rig::testing::command_input(11, mm));
    step_until(model, [&] { return model.microscope().focus_mm() == mm; });
    step_until(twin, [&] { return twin.microscope().focus_mm() == mm; });
    return render(capture(model, builder), kW, kH).eye(0);
  };
  const vr::Image inside = focus_to(0.4 * depth);
  const bool scored_inside = model.microscope().view(model.scene().eye).in_focus(centre_on_fundus);
  const vr::Image blurred = focus_to(3.0);
  const bool scored_beyond = model.microscope().view(model.scene().eye).in_focus(centre_on_fundus);
  const double ds = vt::detail(sharp, kW / 2 - 60, kH / 2 - 50, kW / 2 + 60, kH / 2 + 50);
  const double di = vt::detail(inside, kW / 2 - 60, kH / 2 - 50, kW / 2 + 60, kH / 2 + 50);
  const double db = vt::detail(blurred, kW / 2 - 60, kH / 2 - 50, kW / 2 + 60, kH / 2 + 50);
  std::printf("depth of field %.2f mm; detail at the field centre: %.0f in focus, %.0f focused %.2f mm above, %.0f 3 mm above\n",
              depth, ds, di, 0.4 * depth, db);
  EXPECT_TRUE(scored_inside);
  EXPECT_GT(di, 0.97 * ds) << "within the depth of field the picture stays sharp";
  EXPECT_FALSE(scored_beyond);
  EXPECT_LT(db, 0.95 * ds) << "beyond it the picture blurs (3.5 half-depths: a 3 px circle of confusion at this size)";
  EXPECT_EQ(model.state_hash(), twin.state_hash()) << "the same inputs give the same microscope, bit for bit";
  // Wide angle and its re-inverter, shading: toggles that reach the frame.
  both(rig::testing::command_input(13));
  both(rig::testing::command_input(14));
  both(rig::testing::command_input(12));
  const vr::FrameScene wide = capture(model, builder);
  EXPECT_TRUE(wide.microscope.image_inverted);
  EXPECT_TRUE(wide.flat_shading);
  EXPECT_NEAR(wide.microscope.wide_field_deg, model.microscope().settings().wide_field_deg, 1e-3);
  EXPECT_EQ(model.state_hash(), twin.state_hash());
}

// The vitrector's guillotine crosses its port once per cut: while the pedal cuts, the port's cover
// differs from one moment of the cycle to another; without vacuum the port stays open.
TEST_F(CaseCues, VitrectorPortFlickersAtTheCutRate) {
  auto c = load("exercise_remove_gel");
  rig::SimulationModel& model = c->model;
  ASSERT_TRUE(rig::testing::place_at_fixed_poses(model));
  rig::FrameBuilder builder;
  // How much of the port the guillotine covers in a frame: its mesh's length along the shaft over
  // the port's (frame_source ids: the vitrector's third mesh; 0 when absent).
  auto cover = [](const vr::FrameScene& s) {
    for (const auto& m : s.meshes) {
      if (m.id % 1000 != 202 || m.material != vr::MaterialKind::Instrument) continue;
      float lo = 1e9f, hi = -1e9f;
      for (const auto& v : m.geometry->vertices) lo = std::min(lo, v.position_mm.z), hi = std::max(hi, v.position_mm.z);
      return (hi - lo) / 0.4f;
    }
    return 0.0f;
  };
  EXPECT_EQ(cover(capture(model, builder)), 0.0f) << "no vacuum: the port is open";
  ASSERT_TRUE(model.apply(rig::testing::pedal_input(0, 0.5, 1.0, 0, 0)));
  const double rate_hz = model.controls().cut_rate_cpm / 60.0;
  ASSERT_GT(rate_hz, 0.0);
  // Frames a few milliseconds apart, across several cycles: the cover moves through the cycle.
  float least = 1.0f, most = 0.0f;
  for (int k = 0; k < 24; ++k) {
    for (int i = 0; i < 3; ++i) model.step();
    const float now = cover(capture(model, builder));
    least = std::min(least, now), most = std::max(most, now);
  }
  std::printf("cut rate %.0f/s: the guillotine covers %.2f to %.2f of the port across frames\n", rate_hz, least, most);
  EXPECT_LT(least, 0.35) << "open at some moments";
  EXPECT_GT(most, 0.65) << "covered at others";
}
