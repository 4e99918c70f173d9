// The view's cues on synthetic scenes, each checked for what it must show and that it changes the
// picture where it should and only there: labels at their structure's depth, the wide-angle
// system's inverted image, flat shading, burns whitening with time, guide progress, light added
// by glowing meshes (aiming spot), the chandelier, a membrane lit edge-on, and the instructor's
// view (composition and its own shared-memory ring).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>
#include <thread>

#include "image_checks.hpp"
#include "render_fixture.hpp"
#include "synthetic_scene.hpp"
#include "vitreo/render/egl_context.hpp"
#include "vitreo/render/frame_ring.hpp"
#include "vitreo/render/image_compare.hpp"
#include "vitreo/render/instructor_view.hpp"
#include "vitreo/render/render_thread.hpp"
#include "vitreo/render/renderer.hpp"

namespace vr = vitreo::render;
namespace vt = vitreo::render::testing;

namespace {

constexpr int kW = 200, kH = 160;

using ViewCues = vt::RendererFixture<kW, kH>;

vr::FrameScene base_scene() {
  vt::SyntheticOptions o;
  o.retina_triangles = 3000;
  o.instrument = false;
  return vt::make_scene(o);
}

vr::Mesh* find(vr::FrameScene& s, std::uint32_t id) {
  for (auto& m : s.meshes)
    if (m.id == id) return &m;
  return nullptr;
}

// A ribbon along the retina at polar angle `theta` between azimuths a0 and a1 (degrees), lifted off
// it, `done` along its first `done_fraction`.
vr::MeshGeometryPtr ribbon(float theta, float a0, float a1, float done_fraction) {
  auto g = std::make_shared<vr::MeshGeometry>();
  const int n = 40;
  for (int i = 0; i <= n; ++i) {
    const float a = a0 + (a1 - a0) * static_cast<float>(i) / n;
    const float h = static_cast<float>(i) <= done_fraction * n ? 1.0f : 0.0f;
    for (float dt : {-1.5f, 1.5f}) {
      const vr::Vec3 p = vt::retina_point(theta + dt, a, vt::kRetinaRadius - 0.06f);
      g->vertices.push_back({p, -normalize(p), {}, 0.0f, h});
    }
    if (i > 0) {
      const auto b = static_cast<std::uint32_t>(2 * (i - 1));
      g->indices.insert(g->indices.end(), {b, b + 2, b + 1, b + 1, b + 2, b + 3});
    }
  }
  return g;
}

}  // namespace

TEST_F(ViewCues, LabelsSitBesideTheirStructureAtItsDepthAndChangeNothingElse) {
  vr::FrameScene plain = base_scene();
  const vr::Vec3 anchor = vt::retina_point(12.0f, 200.0f);
  vr::FrameScene labelled = plain;
  labelled.labels.push_back({anchor, "FOVEA", {1.0f, 1.0f, 0.2f}});
  const vr::StereoFrame a = render(plain), b = render(labelled);
  for (int e = 0; e < 2; ++e) {
    const vr::Vec2 at = vt::project_to_pixel(labelled, e, anchor, kW, kH);
    const vt::Mask m = vt::diff_mask(a.eye(e), b.eye(e), 20);
    ASSERT_GT(m.count(), 40) << "the label is drawn";
    // Everything it changed is its marker and its text, which starts just right of the marker.
    int outside = 0;
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kW; ++x)
        if (m.at(x, y) && (x < at.x - 4 || x > at.x + 6 + 6 * 5 + 2 || std::abs(y - at.y) > 6)) ++outside;
    EXPECT_EQ(outside, 0) << "eye " << e << ": only the label's own pixels change";
    // The marker's bright dot sits on the anchor.
    EXPECT_GT(vt::patch(b.eye(e), at, 0).luma(), vt::patch(a.eye(e), at, 0).luma() + 60.0);
  }
  // Carried at the anchor's depth: the label's shift between the eyes is the anchor's disparity.
  const vt::Mask l = vt::diff_mask(a.eye(0), b.eye(0), 20), r = vt::diff_mask(a.eye(1), b.eye(1), 20);
  const float disparity = vt::project_to_pixel(labelled, 0, anchor, kW, kH).x - vt::project_to_pixel(labelled, 1, anchor, kW, kH).x;
  EXPECT_NEAR(l.centroid().x - r.centroid().x, disparity, 1.0f);
}

TEST_F(ViewCues, WideAngleWithoutReinverterShowsTheImageTurnedWithDepthReversed) {
  vr::FrameScene upright = base_scene();
  upright.microscope.wide_angle = true;
  vr::FrameScene inverted = upright;
  inverted.microscope.image_inverted = true;
  const vr::StereoFrame u = render(upright), i = render(inverted);
  for (int e = 0; e < 2; ++e) {
    // Each eyepiece shows its own view turned 180°...
    const vr::ImageDiff turned = vr::compare_images(i.eye(e), vt::rotate180(u.eye(e)), 24);
    const vr::ImageDiff same = vr::compare_images(i.eye(e), u.eye(e), 24);
    std::printf("eye %d: inverted vs upright turned: %s; vs upright: %s\n", e, turned.summary().c_str(), same.summary().c_str());
    EXPECT_LT(turned.rmse, 2.0);
    EXPECT_GT(same.rmse, 10.0 * turned.rmse);
  }
  // ...so a point nearer the viewer than the convergence plane has its disparity reversed.
  const vr::Vec3 near_point = upright.microscope.target_mm * 0.6f;
  const float du = vt::project_to_pixel(upright, 0, near_point, kW, kH).x - vt::project_to_pixel(upright, 1, near_point, kW, kH).x;
  const float di = vt::project_to_pixel(inverted, 0, near_point, kW, kH).x - vt::project_to_pixel(inverted, 1, near_point, kW, kH).x;
  EXPECT_GT(std::abs(du), 0.5f);
  EXPECT_NEAR(di, -du, 1e-3f) << "pseudoscopic: nearer looks deeper";
}

TEST_F(ViewCues, FlatShadingShowsTheFacetsOfTheSameSilhouette) {
  vt::SyntheticOptions o;
  o.retina_triangles = 300;  // coarse: facets a few pixels across
  o.instrument = false;
  vr::FrameScene smooth = vt::make_scene(o);
  for (auto& m : smooth.meshes) m.texture = nullptr;  // shading only
  vr::FrameScene flat = smooth;
  flat.flat_shading = true;
  const vr::Image s = render(smooth).eye(0), f = render(flat).eye(0);
  // Kinks in brightness (second differences) inside the lit fundus: smooth shading and the light's
  // falloff change gradually; flat shading jumps at every triangle edge.
  auto steps = [](const vr::Image& img) {
    int n = 0;
    auto luma = [&](int x, int y) {
      const std::uint8_t* p = &img.rgba[(static_cast<std::size_t>(y) * img.width + x) * 4];
      return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    };
    for (int y = kH / 2 - 40; y < kH / 2 + 40; ++y)
      for (int x = kW / 2 - 50; x < kW / 2 + 50; ++x)
        n += std::abs(luma(x - 1, y) - 2.0 * luma(x, y) + luma(x + 1, y)) >= 4.0 || std::abs(luma(x, y - 1) - 2.0 * luma(x, y) + luma(x, y + 1)) >= 4.0;
    return n;
  };
  const int ss = steps(s), sf = steps(f);
  std::printf("brightness kinks: smooth %d, flat %d\n", ss, sf);
  EXPECT_GT(sf, 2 * ss + 50) << "flat shading shows the triangles' edges";
  EXPECT_EQ(vt::diff_mask(s, f, 0).count() > 0, true);
}

TEST_F(ViewCues, LaserBurnsWhitenOverAFewHundredMilliseconds) {
  const vr::Vec3 hit = vt::retina_point(14.0f, 250.0f);
  double last = -1.0;
  double at_zero = 0.0, at_end = 0.0;
  for (float age : {0.0f, 0.03f, 0.1f, 0.2f, 0.6f}) {
    // A fresh renderer each time: the burn is painted as white as its age (it only ever whitens).
    vr::StereoRenderer r(vr::RenderSettings{kW, kH, 512, 512});
    vr::FrameScene s = base_scene();
    find(s, vt::kRetina)->burns.push_back({hit, {}, 0.5f, {}, age});
    vr::StereoFrame f;
    r.render(s, f);
    const double l = vt::patch(f.eye(0), vt::project_to_pixel(s, 0, hit, kW, kH), 1).luma();
    std::printf("burn age %.2f s: luma %.1f\n", age, l);
    if (age == 0.0f) at_zero = l;
    at_end = l;
    EXPECT_GE(l, last - 0.5) << "whiter with age";
    last = l;
  }
  vr::FrameScene none = base_scene();
  const double unburnt = vt::patch(render(none).eye(0), vt::project_to_pixel(none, 0, hit, kW, kH), 1).luma();
  EXPECT_NEAR(at_zero, unburnt, 2.0) << "no whitening at the instant of the pulse";
  EXPECT_GT(at_end, unburnt + 40.0) << "white after a few hundred milliseconds";
  // One renderer watching the same burn age: it whitens across frames.
  vr::FrameScene s = base_scene();
  find(s, vt::kRetina)->burns.push_back({hit, {}, 0.5f, {}, 0.02f});
  const double early = vt::patch(render(s).eye(0), vt::project_to_pixel(s, 0, hit, kW, kH), 1).luma();
  find(s, vt::kRetina)->burns.back().age_s = 0.5f;
  const double late = vt::patch(render(s).eye(0), vt::project_to_pixel(s, 0, hit, kW, kH), 1).luma();
  EXPECT_GT(late, early + 25.0);
}

TEST_F(ViewCues, GuideShowsItsDonePartInAnotherColourOnlyAlongItself) {
  vr::FrameScene plain = base_scene();
  vr::FrameScene guided = plain;
  vr::Mesh g;
  g.id = 50;
  g.material = vr::MaterialKind::Guide;
  g.geometry = ribbon(18.0f, 150.0f, 250.0f, 0.5f);
  guided.meshes.push_back(g);
  const vr::Image a = render(plain).eye(0), b = render(guided).eye(0);
  std::vector<vr::Vec2> line;
  for (int i = 0; i <= 40; ++i) line.push_back(vt::project_to_pixel(guided, 0, vt::retina_point(18.0f, 150.0f + 100.0f * i / 40, vt::kRetinaRadius), kW, kH));
  const vt::Mask m = vt::diff_mask(a, b, 20);
  ASSERT_GT(m.count(), 60);
  EXPECT_GT(m.fraction_near(line, 3.0f), 0.98) << "the guide changes the picture along itself only";
  // Pending part: the guide's yellow; done part: blue.
  const vt::Rgb pending = vt::patch(b, line[36], 0), done = vt::patch(b, line[4], 0);
  std::printf("pending (%.0f %.0f %.0f) done (%.0f %.0f %.0f)\n", pending.r, pending.g, pending.b, done.r, done.g, done.b);
  EXPECT_GT(pending.r, pending.b + 80.0);
  EXPECT_GT(pending.g, pending.b + 60.0);
  EXPECT_GT(done.b, done.r + 60.0);
}

TEST_F(ViewCues, GlowAddsLightWhereItIsAndNowhereElse) {
  vr::FrameScene plain = base_scene();
  vr::FrameScene lit = plain;
  const vr::Vec3 at = vt::retina_point(20.0f, 40.0f, vt::kRetinaRadius - 0.05f);
  vr::Mesh spot;
  spot.id = 60;
  spot.material = vr::MaterialKind::Glow;
  spot.tint = {0.35f, 1.0f, 0.3f};
  spot.opacity = 2.5f;
  auto g = std::make_shared<vr::MeshGeometry>();
  const vr::Vec3 n = -normalize(at), t1 = normalize(cross(n, {0, 0, 1})), t2 = cross(n, t1);
  g->vertices.push_back({at, n, {}, 0.0f, 1.0f});
  for (int i = 0; i <= 16; ++i) {
    const float a = 6.2831853f * static_cast<float>(i) / 16.0f;
    g->vertices.push_back({at + (t1 * std::cos(a) + t2 * std::sin(a)) * 0.3f, n, {}, 0.0f, 0.0f});
    if (i > 0) g->indices.insert(g->indices.end(), {0u, static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(i + 1)});
  }
  spot.geometry = g;
  lit.meshes.push_back(spot);
  const vr::Image a = render(plain).eye(0), b = render(lit).eye(0);
  const vr::Vec2 px = vt::project_to_pixel(lit, 0, at, kW, kH);
  const vt::Mask m = vt::diff_mask(a, b, 8);
  ASSERT_GT(m.count(), 3);
  EXPECT_GT(m.fraction_near({px}, 5.0f), 0.99);
  const vt::Rgb with = vt::patch(b, px, 0), without = vt::patch(a, px, 0);
  EXPECT_GT(with.g, without.g + 60.0) << "green light added at the spot";
  EXPECT_GE(with.r, without.r) << "added, never darkening";
}

TEST_F(ViewCues, ChandelierLightsTheFundusWithoutAndBesideTheLightPipe) {
  vr::FrameScene dark = base_scene();
  dark.light_pipe.reset();
  vr::FrameScene chandelier = dark;
  const vr::Vec3 tip = vt::retina_point(100.0f, 90.0f, 11.0f);
  chandelier.chandelier = vr::LightPipe{tip, vt::retina_point(0, 0) - tip, 70.0f, 0.8f, 22.0f};
  vr::FrameScene both = base_scene();
  both.chandelier = chandelier.chandelier;
  const vr::Image d = render(dark).eye(0), c = render(chandelier).eye(0), b = render(both).eye(0), p = render(base_scene()).eye(0);
  const vr::Vec2 centre{kW / 2.0f, kH / 2.0f};
  EXPECT_GT(vt::patch(c, centre, 4).luma(), vt::patch(d, centre, 4).luma() + 25.0) << "the chandelier alone lights the pole";
  EXPECT_GT(vt::patch(b, centre, 4).luma(), vt::patch(p, centre, 4).luma() + 5.0) << "and adds to the light pipe";
}

TEST_F(ViewCues, MembraneSeenEdgeOnToTheLightIsNotDark) {
  // A membrane standing off the retina, its plane containing the light's direction: no light falls
  // on either face, yet fibrous tissue scatters it and looks white-grey, not black (the traction
  // membrane the issue saw dark).
  vr::FrameScene s = base_scene();
  const vr::LightPipe& lp = *s.light_pipe;
  const vr::Vec3 c = lp.tip_mm + normalize(lp.direction) * 6.0f;
  const vr::Vec3 along = normalize(lp.direction), side = normalize(cross(along, vr::Vec3{0, 0, 1})), n = cross(along, side);
  auto g = std::make_shared<vr::MeshGeometry>();
  for (float a : {-1.0f, 1.0f})
    for (float b : {-1.0f, 1.0f}) g->vertices.push_back({c + along * (1.5f * a) + side * (0.0f * b) + n * (1.5f * b), side, {0.5f, 0.5f}});
  g->indices = {0, 1, 3, 0, 3, 2};
  vr::Mesh m;
  m.id = 70;
  m.material = vr::MaterialKind::Membrane;
  m.geometry = g;
  m.casts_shadow = false;
  s.meshes.push_back(m);
  vr::FrameScene lit_face = s;
  auto g2 = std::make_shared<vr::MeshGeometry>(*g);
  for (auto& v : g2->vertices) v.normal = -along;  // same sheet, lit face-on
  lit_face.meshes.back().geometry = g2;
  const vr::Vec2 px = vt::project_to_pixel(s, 0, c, kW, kH);
  const double edge_on = vt::patch(render(s).eye(0), px, 1).luma(), face_on = vt::patch(render(lit_face).eye(0), px, 1).luma();
  std::printf("membrane luma: lit edge-on %.1f, face-on %.1f\n", edge_on, face_on);
  EXPECT_GT(edge_on, 0.3 * face_on);
}

TEST_F(ViewCues, InstructorViewIsTheLeftEyeWithScoreForceAndEventsOverIt) {
  vr::FrameScene s = base_scene();
  const vr::StereoFrame f = render(s);
  vr::InstructorOverlay o;
  o.lines = {"CASE  T 12.0 S  SCORE 47", "TARGET 30  EFFICIENCY 80"};
  o.retina_force_un = 1500.0f;
  o.force_limit_un = 3000.0f;
  o.events = {"11.5 S EXCESSIVE RETINA FORCE"};
  const vr::Image img = vr::compose_instructor_view(f, o);
  const vr::Image left = f.eye(0);
  ASSERT_EQ(img.width, left.width);
  const vr::InstructorLayout l = vr::instructor_layout(img.width, img.height, o);
  // Outside the panel, the force bar with its caption and the events column, nothing changed.
  const vt::Mask m = vt::diff_mask(img, left, 0);
  int stray = 0;
  for (int y = 0; y < img.height; ++y) {
    for (int x = 0; x < img.width; ++x) {
      if (!m.at(x, y)) continue;
      const bool panel = x >= l.panel_x && x < l.panel_x + l.panel_w && y >= l.panel_y && y < l.panel_y + l.panel_h;
      const bool bar = y >= l.bar_y - 2 * l.scale && y < l.bar_y + l.bar_h + 2 * l.scale;
      const bool events = x >= img.width / 2 && y < l.panel_y + 3 * l.line_height;
      if (!panel && !bar && !events) ++stray;
    }
  }
  EXPECT_EQ(stray, 0);
  // The bar is filled in proportion to the force (it spans 1.5× the limit): half the limit → a third.
  auto filled = [&](const vr::Image& im) {
    int n = 0;
    for (int x = l.bar_x; x < l.bar_x + l.bar_w; ++x) {
      const std::uint8_t* p = &im.rgba[(static_cast<std::size_t>(l.bar_y + l.bar_h / 2) * im.width + x) * 4];
      n += (p[1] > 150 && p[0] < 150) ? 1 : 0;  // green: below half the limit… at the limit amber
    }
    return n;
  };
  o.retina_force_un = 1400.0f;
  const int third = filled(vr::compose_instructor_view(f, o));
  EXPECT_NEAR(third, l.bar_w * 1400.0 / 4500.0, 2.0);
  // Text is there: the panel holds light pixels (glyph ink), the plain eye's corner does not.
  int ink = 0;
  for (int y = l.panel_y; y < l.panel_y + l.panel_h; ++y)
    for (int x = l.panel_x; x < l.panel_x + l.panel_w; ++x) ink += img.rgba[(static_cast<std::size_t>(y) * img.width + x) * 4 + 1] > 200;
  EXPECT_GT(ink, 100);
}

TEST(InstructorRing, CarriesTheSurgeonsLeftEyeWithTheOverlayForAnotherProcess) {
  const std::string name = "/vitreo-test-instructor-" + std::to_string(::getpid());
  vr::RenderThreadOptions opt;
  opt.egl.honour_environment = false;
  opt.render = {kW, kH, 256, 256};
  opt.instructor_ring_name = name;
  vr::RenderThread thread(opt);
  vr::FrameScene s = base_scene();
  s.step_index = 777;
  s.instructor = vr::InstructorOverlay{{"SCORE 63"}, 4000.0f, 3000.0f, {"1.0 S LENS TOUCH"}};
  thread.publish(s);
  vr::FrameRingReader reader(name);
  EXPECT_EQ(reader.header().width, static_cast<std::uint32_t>(kW)) << "one picture, not a stereo pair";
  EXPECT_EQ(reader.header().eye_width, static_cast<std::uint32_t>(kW));
  vr::RingFrame got;
  for (int i = 0; i < 400 && !reader.read_latest(got); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ASSERT_EQ(got.step_index, 777u);
  // The same picture the composition gives for that frame.
  vitreo::render::EglOptions o;
  o.honour_environment = false;
  vr::EglContext ctx(o);
  vr::StereoRenderer r(vr::RenderSettings{kW, kH, 256, 256});
  vr::StereoFrame f;
  r.render(s, f);
  const vr::Image expected = vr::compose_instructor_view(f, *s.instructor);
  const vr::ImageDiff d = vr::compare_images(vr::Image{got.width, got.height, got.rgba}, expected, 8);
  std::printf("instructor ring vs composed: %s\n", d.summary().c_str());
  EXPECT_LT(d.rmse, 1.0);
  const vr::ImageDiff plain = vr::compare_images(vr::Image{got.width, got.height, got.rgba}, f.eye(0), 8);
  EXPECT_GT(plain.fraction_over, 0.02) << "the overlay is in the ring's frames";
}
