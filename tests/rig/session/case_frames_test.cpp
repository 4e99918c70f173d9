// Every case in scenes/ as the surgeon sees it: the real SimulationModel on the case (a coarse
// retina and small textures to stay quick), the light pipe and the case's first tool placed at fixed
// poses through their trackers and ports, captured at a step boundary (capture_view), turned into a
// FrameScene (FrameBuilder) and rendered as a small stereo frame on Mesa through surfaceless EGL.
//
// Each frame (both eyes) is compared with a checked-in golden (tolerance-based, the metric is
// printed; see golden/README.md to regenerate), and checked against facts that do not depend on the
// golden: the case's region of interest is in the middle of the picture at its start; the light
// pipe lights it (without it the spot is dark); the labels toggle changes the picture only at the
// guides and the labels; the retina's vessel map is what the spot shows (taking the texture away
// changes it); a detached case shows its lifted retina greyer than the same frame with the
// detachment shading off, and an attached case has no lifted retina at all. The cues measured in
// the image (guide, aiming spot, jaws, disparity, gel, rims, microscope) are in view_cues_test.cpp.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

#include "rig/scene_io/case_loader.hpp"
#include "rig/session/case_switcher.hpp"
#include "rig/session/frame_source.hpp"
#include "rig/session/simulation_model.hpp"
#include "fixed_poses.hpp"
#include "image_checks.hpp"
#include "model_inputs.hpp"
#include "synthetic_scene.hpp"
#include "vitreo/render/egl_context.hpp"
#include "vitreo/render/image_compare.hpp"
#include "vitreo/render/png_io.hpp"
#include "vitreo/render/renderer.hpp"

using namespace vitreo;
namespace vr = vitreo::render;

namespace {

constexpr int kW = 160, kH = 128;
const std::string kScenes = std::string(VITREO_SOURCE_DIR) + "/scenes";

struct Rgb {
  double r = 0, g = 0, b = 0;
  double luma() const { return 0.2126 * r + 0.7152 * g + 0.0722 * b; }
  double spread() const { return std::max({r, g, b}) - std::min({r, g, b}); }  // 0 = grey
};

Rgb patch(const vr::Image& img, vr::Vec2 p, int k) {
  Rgb s;
  int n = 0;
  for (int y = static_cast<int>(p.y) - k; y <= static_cast<int>(p.y) + k; ++y) {
    for (int x = static_cast<int>(p.x) - k; x <= static_cast<int>(p.x) + k; ++x) {
      if (x < 0 || y < 0 || x >= img.width || y >= img.height) continue;
      const std::uint8_t* q = &img.rgba[(static_cast<std::size_t>(y) * img.width + x) * 4];
      s.r += q[0], s.g += q[1], s.b += q[2];
      ++n;
    }
  }
  if (n > 0) s.r /= n, s.g /= n, s.b /= n;
  return s;
}

class CaseFrames : public ::testing::TestWithParam<std::string> {
 protected:
  static void SetUpTestSuite() {
    vr::EglOptions o;
    o.honour_environment = false;
    context_ = new vr::EglContext(o);
    renderer_ = new vr::StereoRenderer(vr::RenderSettings{kW, kH, 512, 512});
  }
  static void TearDownTestSuite() {
    delete renderer_;
    delete context_;
    renderer_ = nullptr;
    context_ = nullptr;
  }
  static vr::Image render(const vr::FrameScene& s) {
    vr::StereoFrame f;
    renderer_->render(s, f);
    return f.side_by_side();
  }
  static vr::StereoFrame render_stereo(const vr::FrameScene& s) {
    vr::StereoFrame f;
    renderer_->render(s, f);
    return f;
  }

  static vr::EglContext* context_;
  static vr::StereoRenderer* renderer_;
};
vr::EglContext* CaseFrames::context_ = nullptr;
vr::StereoRenderer* CaseFrames::renderer_ = nullptr;

// What is stored and compared: the stereo frame reduced 2× (box filter) and quantised to steps of 8,
// which keeps each golden a few kilobytes; the tolerance below is far above what that costs.
vr::Image reduced(const vr::Image& full) {
  vr::Image out;
  out.width = full.width / 2;
  out.height = full.height / 2;
  out.rgba.resize(static_cast<std::size_t>(out.width) * out.height * 4);
  for (int y = 0; y < out.height; ++y) {
    for (int x = 0; x < out.width; ++x) {
      for (int k = 0; k < 4; ++k) {
        int sum = 0;
        for (int dy = 0; dy < 2; ++dy) {
          for (int dx = 0; dx < 2; ++dx) sum += full.rgba[(static_cast<std::size_t>(2 * y + dy) * full.width + 2 * x + dx) * 4 + k];
        }
        const int mean = (sum + 2) / 4;
        out.rgba[(static_cast<std::size_t>(y) * out.width + x) * 4 + k] = static_cast<std::uint8_t>(k == 3 ? 255 : std::min(255, (mean + 4) / 8 * 8));
      }
    }
  }
  return out;
}

void expect_golden(const vr::Image& full, const std::string& name) {
  const vr::Image actual = reduced(full);
  const std::string golden = std::string(VITREO_CASE_GOLDEN_DIR) + "/" + name + ".png";
  const char* update = std::getenv("VITREO_UPDATE_GOLDENS");
  if (update != nullptr && std::string(update) == "1") {
    vr::write_png(golden, actual);
    std::printf("updated golden %s\n", golden.c_str());
    return;
  }
  ASSERT_TRUE(std::filesystem::exists(golden)) << "missing golden " << golden << " (regenerate: VITREO_UPDATE_GOLDENS=1)";
  const vr::ImageDiff d = vr::compare_images(actual, vr::read_png(golden), 24);
  std::printf("golden %s: %s\n", name.c_str(), d.summary().c_str());
  ::testing::Test::RecordProperty("rmse_" + name, std::to_string(d.rmse));
  if (!(d.same_size && d.rmse <= 3.0 && d.fraction_over <= 0.015)) {
    mkdir("golden-actual", 0755);
    const std::string out = "golden-actual/" + name + ".png";
    vr::write_png(out, actual);
    ADD_FAILURE() << "golden " << name << " differs: " << d.summary() << " (limits rmse<=3, over(24)<=1.5%); actual written to "
                  << out;
  }
}

}  // namespace

TEST_P(CaseFrames, GoldenAtFixedPosesAndWhatTheFrameMustShow) {
  const std::string name = GetParam();
  rig::testing::CaseUnderTest under_test(kScenes + "/" + name + ".toml", 2000, VITREO_CASE_CACHE_DIR);
  rig::SimulationModel& model = under_test.model;
  const rig::PreparedCase& c = model.current_case();

  // Fixed poses: the light pipe 6 mm into working_2 aimed at the case's region of interest, the
  // first tool 5 mm into working_1 aimed at it too, jaws open (fixed_poses.hpp).
  ASSERT_TRUE(rig::testing::place_at_fixed_poses(model));

  rig::ViewSnapshot view;
  ASSERT_TRUE(rig::capture_view(model, 3, 0.003, view));
  rig::FrameBuilder builder;
  const vr::FrameScene scene = builder.build(view);
  ASSERT_TRUE(scene.light_pipe.has_value()) << "the case offers a light pipe";
  const vr::StereoFrame frame = render_stereo(scene);
  expect_golden(frame.side_by_side(), name);

  // The region of interest is inside the frame, near its centre, at the case's start (the
  // microscope starts centred on it).
  const vr::Image left = frame.eye(0);
  const vr::Vec2 spot = render::testing::project_to_pixel(scene, 0, vr::Vec3{float(c.focus_mm.x()), float(c.focus_mm.y()), float(c.focus_mm.z())}, kW, kH);
  EXPECT_NEAR(spot.x, kW / 2.0f, kW / 10.0f) << "the region of interest is in the middle of the picture";
  EXPECT_NEAR(spot.y, kH / 2.0f, kH / 10.0f);
  // The light pipe lights it: the same frame without the light is far darker there.
  vr::FrameScene unlit = scene;
  unlit.light_pipe.reset();
  unlit.chandelier.reset();
  unlit.labels.clear();
  vr::FrameScene lit_plain = scene;
  lit_plain.labels.clear();
  const vr::Image left_nolabels = render_stereo(lit_plain).eye(0);
  const Rgb lit = patch(left_nolabels, spot, 4), dark = patch(render_stereo(unlit).eye(0), spot, 4);
  std::printf("%s: region of interest at pixel (%.0f, %.0f): luma %.1f lit, %.1f without the light\n", name.c_str(), spot.x, spot.y, lit.luma(),
              dark.luma());
  EXPECT_GT(lit.luma(), 30.0);
  EXPECT_GT(lit.luma(), 3.0 * dark.luma() + 10.0) << "only the light pipe lights the interior";
  // The labels toggle (guides and structure names) changes the picture only at the guides and the
  // labels: the same frame without them differs nowhere else.
  if (!scene.labels.empty()) {
    vr::FrameScene bare = scene;
    bare.labels.clear();
    std::erase_if(bare.meshes, [](const vr::Mesh& m) { return m.material == vr::MaterialKind::Guide; });
    std::vector<vr::Vec2> allowed;
    for (const auto& l : scene.labels) {
      const vr::Vec2 a = render::testing::project_to_pixel(scene, 0, l.anchor_mm, kW, kH);
      // The text starts right of the marker and moves down a line at a time past earlier labels.
      for (int row = 0; row <= static_cast<int>(scene.labels.size()); ++row)
        for (int k = -1; k < static_cast<int>(l.text.size()) + 2; ++k) allowed.push_back({a.x + 6.0f * k, a.y + 10.0f * row});
    }
    for (const auto& m : scene.meshes) {
      if (m.material != vr::MaterialKind::Guide) continue;
      for (const auto& v : m.geometry->vertices) allowed.push_back(render::testing::project_to_pixel(scene, 0, v.position_mm, kW, kH));
    }
    const render::testing::Mask changed = render::testing::diff_mask(left, render_stereo(bare).eye(0), 16);
    std::printf("%s: labels and guides change %d pixels, %.3f of them at a label or a guide\n", name.c_str(), changed.count(),
                changed.fraction_near(allowed, 6.0f));
    EXPECT_GT(changed.count(), 0);
    EXPECT_GT(changed.fraction_near(allowed, 6.0f), 0.97);
  }

  // The vessel map is on the retina: the same frame without it differs in the lit spot.
  vr::FrameScene plain = lit_plain;
  for (auto& m : plain.meshes) {
    if (m.material == vr::MaterialKind::Retina) m.texture = nullptr;
  }
  const vr::Image left_plain = render_stereo(plain).eye(0);
  int changed = 0, lit_pixels = 0;
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      const std::size_t i = (static_cast<std::size_t>(y) * kW + x) * 4;
      if (0.2126 * left_nolabels.rgba[i] + 0.7152 * left_nolabels.rgba[i + 1] + 0.0722 * left_nolabels.rgba[i + 2] < 25.0) continue;
      ++lit_pixels;
      int d = 0;
      for (int k = 0; k < 3; ++k) d = std::max(d, std::abs(int(left_nolabels.rgba[i + k]) - int(left_plain.rgba[i + k])));
      changed += d > 12;
    }
  }
  std::printf("%s: %d of %d lit pixels change without the vessel map\n", name.c_str(), changed, lit_pixels);
  // Vessels are sparse in the periphery (the horseshoe-tear cases look there): ≥ 0.5 % of the lit
  // pixels; posterior views change by 10–30 %.
  EXPECT_GT(changed, std::max(30, lit_pixels / 200)) << "the retina shows its fundus texture (vessels, disc) where it is lit";

  // Detachment: the most lifted retina vertex in the lit cone, against the same frame without
  // the detachment shading.
  const double lift = core::max_retina_lift_mm(model.scene());
  const vr::Mesh* retina = nullptr;
  for (const auto& m : scene.meshes) {
    if (m.material == vr::MaterialKind::Retina) retina = &m;
  }
  ASSERT_NE(retina, nullptr);
  // Over the vertices the triangles draw: slots freed by a collapse stay in the array (at the
  // origin, far from the wall) but no triangle uses them.
  float max_detachment = 0.0f;
  for (const auto i : retina->geometry->indices) max_detachment = std::max(max_detachment, retina->geometry->vertices[i].detachment);
  std::printf("%s: retina lifted up to %.2f mm, detachment shading up to %.2f\n", name.c_str(), lift, max_detachment);
  if (lift < 0.4) {
    EXPECT_LT(max_detachment, 0.5f) << "an attached retina is not shaded as detached";
    return;
  }
  // The shading grows from the retina's own thickness to 0.5 mm beyond it (frame_source.cpp), so a
  // lift of 0.66 mm is shaded 0.82: the most lifted vertex must be shaded (nearly) that much.
  const double thickness = model.scene().description.materials.retina.thickness_mm;
  const float expected = static_cast<float>(std::clamp((lift - thickness) / 0.5, 0.0, 1.0));
  EXPECT_GT(max_detachment, 0.9f * expected) << "a retina lifted " << lift << " mm is shaded as detached";
  const float detached = 0.9f * max_detachment;
  // Pick the detached vertex (shading ≥ 90 % of the most) nearest the light's axis: it is lit.
  const vr::Vec3 apex = scene.light_pipe->tip_mm, axis = normalize(scene.light_pipe->direction);
  vr::Vec3 best{};
  float best_off = 1e9f;
  for (const auto& v : retina->geometry->vertices) {
    if (v.detachment < detached) continue;
    const vr::Vec3 d = v.position_mm - apex;
    const float along = dot(d, axis);
    if (along <= 0) continue;
    const float off = length(d - axis * along) / along;
    if (off < best_off) best_off = off, best = v.position_mm;
  }
  ASSERT_LT(best_off, 1e8f);
  vr::FrameScene flat = render::testing::without_detachment_shading(scene);
  const vr::Vec2 px = render::testing::project_to_pixel(scene, 0, best, kW, kH);
  flat.labels.clear();
  const Rgb shaded = patch(left_nolabels, px, 2), unshaded = patch(render_stereo(flat).eye(0), px, 2);
  std::printf("%s: detached patch spread/luma %.2f vs %.2f without the shading\n", name.c_str(), shaded.spread() / std::max(shaded.luma(), 1.0),
              unshaded.spread() / std::max(unshaded.luma(), 1.0));
  // At the tissue's nominal stiffness the U tear's and the drain exercise's detachments sit on
  // already grey, low-contrast fundus under the light (0.12 vs 0.14, 0.40 vs 0.45 with a 5×5 patch;
  // the traction cases 0.27 vs 0.76 and 0.35 vs 1.21), so the shading must make the patch greyer by
  // at least 8 %, not the 20 % the bullous detachments of the soft solver gave; issue 14 item 5
  // (retuning the cases' detachments) is where this is to come back.
  EXPECT_LT(shaded.spread() / std::max(shaded.luma(), 1.0), 0.92 * unshaded.spread() / std::max(unshaded.luma(), 1.0))
      << "detached retina looks greyer";
}

INSTANTIATE_TEST_SUITE_P(EveryCase, CaseFrames, ::testing::ValuesIn(rig::testing::shipped_case_names()),
                         [](const ::testing::TestParamInfo<std::string>& i) { return i.param; });

// The operator's view toggles reach the picture: wireframe draws the tissue's edges, zoom narrows
// the field (the optic disc moves away from the image centre by the zoom factor).
TEST_F(CaseFrames, WireframeAndZoomChangeThePicture) {
  rig::testing::CaseUnderTest under_test(kScenes + "/exercise_pull_tissue.toml", 2000, VITREO_CASE_CACHE_DIR);
  rig::SimulationModel& model = under_test.model;
  model.step();
  rig::FrameBuilder builder;
  rig::ViewSnapshot v;  // reused, as the session's triple buffer is
  auto frame_of = [&] {
    EXPECT_TRUE(rig::capture_view(model, 1, 0.001, v));
    return builder.build(v);
  };
  auto command = [&](int code, double value) { ASSERT_TRUE(model.apply(rig::testing::command_input(code, value))); };
  const vr::FrameScene base = frame_of();
  command(7, 0);  // toggle wireframe
  const vr::FrameScene wire = frame_of();
  EXPECT_TRUE(wire.wireframe);
  const vr::ImageDiff dw = vr::compare_images(render(wire), render(base));
  std::printf("wireframe vs filled: %s\n", dw.summary().c_str());
  EXPECT_GT(dw.fraction_over, 0.02) << "the wireframe picture differs visibly";
  command(7, 0);
  command(9, 2.0);  // zoom 2×: the zoom motor gets there
  for (int i = 0; i < 2000 && model.microscope().zoom() != 2.0; ++i) model.step();
  const vr::FrameScene zoomed = frame_of();
  EXPECT_FLOAT_EQ(zoomed.microscope.zoom, 2.0f);
  const vr::Vec3 disc{float(model.scene().eye.optic_disc_mm.x()), float(model.scene().eye.optic_disc_mm.y()),
                      float(model.scene().eye.optic_disc_mm.z())};
  const vr::Vec2 c0 = render::testing::project_to_pixel(base, 0, disc, kW, kH);
  const vr::Vec2 c1 = render::testing::project_to_pixel(zoomed, 0, disc, kW, kH);
  const vr::Vec2 mid{kW / 2.0f, kH / 2.0f};
  const double r0 = std::hypot(c0.x - mid.x, c0.y - mid.y), r1 = std::hypot(c1.x - mid.x, c1.y - mid.y);
  EXPECT_NEAR(r1 / r0, 2.0, 0.15) << "zoom 2 doubles image distances from the centre (tan(field/2) halves)";
  EXPECT_GT(vr::compare_images(render(zoomed), render(base)).fraction_over, 0.05);
}

// A laser burn where the aiming beam hit: the endolaser (the laser exercise's tool) fires once
// through the pedal's laser switch; the burn the instrument system records reaches the frame at
// that spot and shows whitish there, against the same frame without it.
TEST_F(CaseFrames, ALaserBurnShowsWhitishWhereTheBeamHit) {
  rig::testing::CaseUnderTest under_test(kScenes + "/exercise_laser_tear.toml", 2000, VITREO_CASE_CACHE_DIR);
  rig::SimulationModel& model = under_test.model;
  const rig::PreparedCase& c = model.current_case();
  ASSERT_FALSE(c.tools.empty());
  ASSERT_EQ(c.tools[0], core::InstrumentKind::kEndolaser);
  // Aim at attached retina beside the fovea (a 0.2 mm burn needs the microscope zoomed in to span
  // a few pixels of this small frame: zoom 4, panned there), with the light pipe on the same spot.
  const core::Vec3 aim = model.scene().eye.wall_point(8.0 * std::numbers::pi / 180.0, std::numbers::pi);
  const core::Vec3 lp = c.tracker_ports[rig::kSecondHandTracker].position_mm;
  const core::Vec3 tp = c.tracker_ports[rig::kToolTracker].position_mm;
  ASSERT_TRUE(model.apply(rig::testing::tracker_sample(rig::kSecondHandTracker, lp + 6.0 * (aim - lp).normalized(), 0.0)));
  ASSERT_TRUE(model.apply(rig::testing::tracker_sample(rig::kToolTracker, tp + 8.0 * (aim - tp).normalized(), 0.0)));
  const telemetry::RecordedInput zoom = rig::testing::command_input(9, 4.0);
  // The microscope over the aim (a pan command from the case's region of interest; the X–Y motor is
  // quickest at low magnification), then zoomed in.
  const core::Vec2 offset = model.scene().eye.fundus_coords(aim) - model.microscope().region_of_interest_mm();
  ASSERT_TRUE(model.apply(rig::testing::command_input(10, offset.x(), offset.y())));
  for (int i = 0; i < 4000 && model.microscope().center_mm() != model.scene().eye.fundus_coords(aim); ++i) model.step();
  ASSERT_TRUE(model.apply(zoom));
  for (int i = 0; i < 4000 && model.microscope().zoom() != 4.0; ++i) model.step();
  rig::FrameBuilder builder;
  rig::ViewSnapshot before_view;
  ASSERT_TRUE(rig::capture_view(model, 1, 0.001, before_view));
  const vr::FrameScene before = builder.build(before_view);
  ASSERT_TRUE(model.apply(test::pedal_switches(1u << 1)));  // laser switch (default mapping: switch 1)
  model.step();
  ASSERT_TRUE(model.apply(test::pedal_switches(0)));
  model.step();
  ASSERT_EQ(model.simulation().burns().size(), 1u) << "one pulse on the rising edge";
  const core::Vec3 hit = model.simulation().burn_position(model.simulation().burns()[0]);
  // The field onto the burn while the coagulation whitens (a few hundred milliseconds).
  const core::Vec2 to_hit = model.scene().eye.fundus_coords(hit) - model.microscope().region_of_interest_mm();
  ASSERT_TRUE(model.apply(rig::testing::command_input(10, to_hit.x(), to_hit.y())));
  for (int i = 0; i < 500; ++i) model.step();
  ASSERT_TRUE(rig::capture_view(model, 3, 0.003, before_view));
  const rig::ViewSnapshot& view = before_view;
  ASSERT_EQ(view.n_burns, 1u);
  vr::FrameScene after = builder.build(view);
  // The burn, not the aiming spot still on it (light added on top) nor the labels.
  std::erase_if(after.meshes, [](const vr::Mesh& m) { return m.material == vr::MaterialKind::Glow; });
  after.labels.clear();
  std::size_t burns = 0;
  for (const auto& m : after.meshes) {
    burns += m.burns.size();
    for (const auto& b : m.burns) {
      EXPECT_TRUE(b.hit_point.has_value()) << "the renderer gets the triangle, not a point to search for";
      EXPECT_FALSE(b.hit_position_mm.has_value());
    }
  }
  EXPECT_EQ(burns, 1u);
  vr::FrameScene cleared = after;
  for (auto& m : cleared.meshes) m.burns.clear();
  const vr::Vec2 px = render::testing::project_to_pixel(after, 0, vr::Vec3{float(hit.x()), float(hit.y()), float(hit.z())}, kW, kH);
  ASSERT_TRUE(px.x >= 0 && px.x < kW && px.y >= 0 && px.y < kH) << "burn at pixel (" << px.x << ", " << px.y << "), zoom "
                                                               << model.microscope().zoom() << ", hit " << (hit - aim).norm() << " mm from the aim";
  EXPECT_LT((hit - aim).norm(), 1.0) << "the beam went where the laser was aimed";
  const Rgb with = patch(render_stereo(after).eye(0), px, 1), without = patch(render_stereo(cleared).eye(0), px, 1);
  std::printf("burn at pixel (%.1f, %.1f): luma %.1f spread %.1f vs %.1f / %.1f without\n", px.x, px.y, with.luma(), with.spread(),
              without.luma(), without.spread());
  EXPECT_GT(with.luma(), without.luma() + 15.0) << "the burn is lighter";
  EXPECT_LT(with.spread() / with.luma(), without.spread() / without.luma()) << "and whiter";
}

// Fluid–air exchange: the pedal's air switch turns the infusion to air, the flute needle aspirates
// (vacuum pedal) and the level falls toward its tip; the frame carries that level to the renderer
// (whose own test, RenderScenes.FluidGasInterfaceIsVisible, shows the interface at the wall; from
// this view, behind the lens, the meniscus lies outside the field).
TEST_F(CaseFrames, FluidAirExchangeLowersTheLevelTheFrameShows) {
  rig::testing::CaseUnderTest under_test(kScenes + "/exercise_drain_tear.toml", 2000, VITREO_CASE_CACHE_DIR);
  rig::SimulationModel& model = under_test.model;
  const rig::PreparedCase& c = model.current_case();
  ASSERT_EQ(c.tools.at(0), core::InstrumentKind::kDrainageNeedle);
  const core::Vec3 tp = c.tracker_ports[rig::kToolTracker].position_mm;
  ASSERT_TRUE(model.apply(rig::testing::tracker_sample(rig::kToolTracker, tp + 12.0 * (c.focus_mm - tp).normalized(), 0.0)));
  auto pedal = [](double vacuum, int switches) {
    telemetry::PedalSample s;
    s.pedal_id = 0;
    s.axis_count = 2;
    s.axes[0] = vacuum;
    s.switches = static_cast<std::uint16_t>(switches);
    telemetry::RecordedInput in;
    in.what = s;
    return in;
  };
  rig::FrameBuilder builder;
  model.step();
  rig::ViewSnapshot v0;
  ASSERT_TRUE(rig::capture_view(model, 1, 0.001, v0));
  const vr::FrameScene fluid = builder.build(v0);
  EXPECT_FALSE(fluid.fluid_gas.has_value()) << "all fluid before the exchange";
  ASSERT_TRUE(model.apply(pedal(0.0, 1 << 3)));  // air on
  ASSERT_TRUE(model.apply(pedal(1.0, 0)));       // full aspiration
  ASSERT_TRUE(model.controls().air_infusion);
  model.step();
  const double top = model.simulation().fluid_level_z_mm();
  for (int i = 0; i < 400; ++i) model.step();
  const double level = model.simulation().fluid_level_z_mm();
  std::printf("fluid level: %.2f mm at the start of the exchange, %.2f mm after 0.4 s of aspiration\n", top, level);
  EXPECT_NEAR(top - level, 0.4 * 2.0, 0.1) << "falls at the aspiration rate (2 mm/s at full vacuum)";
  rig::ViewSnapshot v1;
  ASSERT_TRUE(rig::capture_view(model, 402, 0.402, v1));
  const vr::FrameScene gas = builder.build(v1);
  ASSERT_TRUE(gas.fluid_gas.has_value());
  EXPECT_NEAR(gas.fluid_gas->level_mm, level, 1e-3);
  EXPECT_NEAR(gas.fluid_gas->up.z, 1.0f, 1e-6f) << "gas rises anteriorly (patient supine)";
}
