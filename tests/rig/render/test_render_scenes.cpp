// The renderer on synthetic scenes: golden images per case, and the behaviour the surgeons need
// checked directly (dark without the light pipe, disparity sign, burns where the ray hit, shadows,
// detachment, the gas interface, what is re-uploaded).
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <memory>

#include "render_fixture.hpp"
#include "synthetic_scene.hpp"
#include "vitreo/render/egl_context.hpp"
#include "vitreo/render/image_compare.hpp"
#include "vitreo/render/png_io.hpp"
#include "vitreo/render/renderer.hpp"

namespace vr = vitreo::render;
namespace vt = vitreo::render::testing;

namespace {

constexpr int kW = 160, kH = 128;

bool file_exists(const std::string& p) {
  struct stat st {};
  return stat(p.c_str(), &st) == 0;
}

struct Rgb {
  double r = 0, g = 0, b = 0;
  double luma() const { return 0.2126 * r + 0.7152 * g + 0.0722 * b; }
  double spread() const { return std::max({r, g, b}) - std::min({r, g, b}); }  // 0 = grey/white
};

// Mean colour of a (2k+1)² patch around pixel p of one eye's image.
Rgb patch(const vr::Image& img, vr::Vec2 p, int k = 1) {
  Rgb s;
  int n = 0;
  for (int y = static_cast<int>(p.y) - k; y <= static_cast<int>(p.y) + k; ++y) {
    for (int x = static_cast<int>(p.x) - k; x <= static_cast<int>(p.x) + k; ++x) {
      if (x < 0 || y < 0 || x >= img.width || y >= img.height) continue;
      const std::uint8_t* q = &img.rgba[(static_cast<std::size_t>(y) * img.width + x) * 4];
      s.r += q[0];
      s.g += q[1];
      s.b += q[2];
      ++n;
    }
  }
  if (n > 0) {
    s.r /= n;
    s.g /= n;
    s.b /= n;
  }
  return s;
}

class RenderScenes : public vt::RendererFixture<kW, kH> {
 protected:
  static vr::Mesh* mesh(vr::FrameScene& s, std::uint32_t id) {
    for (auto& m : s.meshes)
      if (m.id == id) return &m;
    return nullptr;
  }

  // Golden comparison: RMSE and the fraction of pixels off by more than 24 (of 255) must stay small.
  // Set VITREO_UPDATE_GOLDENS=1 to (re)write the golden instead (see golden/README.md).
  void expect_golden(const vr::Image& actual, const std::string& name) {
    const std::string golden = std::string(VITREO_RENDER_GOLDEN_DIR) + "/" + name + ".png";
    const char* update = std::getenv("VITREO_UPDATE_GOLDENS");
    if (update != nullptr && std::string(update) == "1") {
      vr::write_png(golden, actual);
      std::printf("updated golden %s\n", golden.c_str());
      return;
    }
    ASSERT_TRUE(file_exists(golden)) << "missing golden " << golden << " (regenerate: VITREO_UPDATE_GOLDENS=1)";
    const vr::ImageDiff d = vr::compare_images(actual, vr::read_png(golden), 24);
    std::printf("golden %s: %s\n", name.c_str(), d.summary().c_str());
    RecordProperty("rmse_" + name, std::to_string(d.rmse));
    if (!(d.same_size && d.rmse <= 2.5 && d.fraction_over <= 0.01)) {
      mkdir("golden-actual", 0755);
      const std::string out = "golden-actual/" + name + ".png";
      vr::write_png(out, actual);
      ADD_FAILURE() << "golden " << name << " differs: " << d.summary()
                    << " (limits rmse<=2.5, over(24)<=1%); actual written to " << out;
    }
  }
};

vr::FrameScene burn_scene() {
  vt::SyntheticOptions o;
  o.retina_triangles = 3000;
  vr::FrameScene s = vt::make_scene(o);
  for (auto& m : s.meshes)
    if (m.id == vt::kRetina) m.burns.push_back({vt::retina_point(14, 250), {}, 0.45f, {}});
  return s;
}

}  // namespace

// ---- golden images, one per case ----

TEST_F(RenderScenes, GoldenLitWithInstrumentShadow) {
  vt::SyntheticOptions o;
  o.retina_triangles = 3000;
  expect_golden(render(vt::make_scene(o)).side_by_side(), "lit_instrument");
}

TEST_F(RenderScenes, GoldenDarkWithoutLightPipe) {
  vt::SyntheticOptions o;
  o.retina_triangles = 3000;
  o.light_pipe = false;
  expect_golden(render(vt::make_scene(o)).side_by_side(), "dark");
}

TEST_F(RenderScenes, GoldenDetachedRetina) {
  vt::SyntheticOptions o;
  o.retina_triangles = 3000;
  o.detached = true;
  expect_golden(render(vt::make_scene(o)).side_by_side(), "detached");
}

TEST_F(RenderScenes, GoldenLaserBurn) { expect_golden(render(burn_scene()).side_by_side(), "laser_burn"); }

TEST_F(RenderScenes, GoldenFluidGas) {
  vt::SyntheticOptions o;
  o.retina_triangles = 3000;
  o.gas = true;
  expect_golden(render(vt::make_scene(o)).side_by_side(), "fluid_gas");
}

TEST_F(RenderScenes, GoldenWideAngle) {
  vt::SyntheticOptions o;
  o.retina_triangles = 3000;
  o.wide_angle = true;
  expect_golden(render(vt::make_scene(o)).side_by_side(), "wide_angle");
}

// ---- behaviour ----

TEST_F(RenderScenes, InteriorIsDarkWithoutTheLightPipe) {
  vt::SyntheticOptions o;
  o.retina_triangles = 3000;
  const vr::StereoFrame lit = render(vt::make_scene(o));
  o.light_pipe = false;
  const vr::StereoFrame dark = render(vt::make_scene(o));
  const double dark_mean = vr::mean_luminance(dark.side_by_side());
  const double lit_centre = vr::mean_luminance(lit.eye(0), kW / 4, kH / 4, kW / 2, kH / 2);
  EXPECT_LT(dark_mean, 6.0);                                          // only the dim ambient
  EXPECT_LT(vr::mean_luminance(dark.eye(0), kW / 4, kH / 4, kW / 2, kH / 2), 8.0);
  EXPECT_GT(lit_centre, 40.0);                                        // the same view, lit
}

TEST_F(RenderScenes, FramesCarrySimTimeAndStep) {
  vr::FrameScene s = vt::make_scene({});
  s.sim_time_s = 12.345;
  s.step_index = 12345;
  const vr::StereoFrame f = render(s);
  EXPECT_EQ(f.sim_time_s, 12.345);
  EXPECT_EQ(f.step_index, 12345u);
  EXPECT_EQ(f.eye_width, kW);
  EXPECT_EQ(f.rgba.size(), static_cast<std::size_t>(2 * kW * kH * 4));
}

namespace {
// A small sphere lit by ambient only (no light pipe, no haze): a bright blob on black.
vr::FrameScene blob_scene(vr::Vec3 centre) {
  vr::FrameScene s;
  s.ambient = 1.0f;
  s.haze_density_per_mm = 0.0f;
  s.microscope.zoom = 2.0f;
  auto g = std::make_shared<vr::MeshGeometry>();
  const int n = 12;
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= 2 * n; ++j) {
      const float th = 3.14159265f * i / n, ph = 3.14159265f * j / n;
      const vr::Vec3 d{std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)};
      g->vertices.push_back({centre + d * 0.6f, d, {0, 0}});
    }
  }
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < 2 * n; ++j) {
      const auto a = static_cast<std::uint32_t>(i * (2 * n + 1) + j), b = a + 2 * n + 1;
      g->indices.insert(g->indices.end(), {a, b, a + 1, a + 1, b, b + 1});
    }
  }
  vr::Mesh m;
  m.id = 9;
  m.material = vr::MaterialKind::Static;
  m.geometry = g;
  s.meshes.push_back(m);
  return s;
}

// x centroid of pixels brighter than half the maximum.
double bright_centroid_x(const vr::Image& img) {
  double sum = 0, n = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      if (img.rgba[(static_cast<std::size_t>(y) * img.width + x) * 4] > 120) {
        sum += x + 0.5;
        n += 1;
      }
  return n > 0 ? sum / n : -1.0;
}
}  // namespace

TEST_F(RenderScenes, DisparitySignNearObjectShiftsRightInTheLeftEye) {
  const vr::Vec3 target = vr::Microscope{}.target_mm;
  struct Case {
    float dz;
    int sign;  // of left − right
  };
  for (const Case c : {Case{+5.0f, +1}, Case{-3.5f, -1}, Case{0.0f, 0}}) {
    const vr::Vec3 p = target + vr::Vec3{1.0f, 0.5f, c.dz};
    const vr::FrameScene s = blob_scene(p);
    const vr::StereoFrame f = render(s);
    const double xl = bright_centroid_x(f.eye(0)), xr = bright_centroid_x(f.eye(1));
    ASSERT_GT(xl, 0) << "blob not visible";
    ASSERT_GT(xr, 0) << "blob not visible";
    const double disparity = xl - xr;
    if (c.sign == 0) {
      EXPECT_NEAR(disparity, 0.0, 0.5) << "on the working plane";
    } else {
      EXPECT_GT(disparity * c.sign, 2.0) << "dz=" << c.dz << " disparity=" << disparity;
    }
    // And the blob sits where the camera model projects it.
    EXPECT_NEAR(xl, vt::project_to_pixel(s, 0, p, kW, kH).x, 1.0);
    EXPECT_NEAR(xr, vt::project_to_pixel(s, 1, p, kW, kH).x, 1.0);
  }
}

TEST_F(RenderScenes, LaserBurnAppearsWhitishWhereTheRayHit) {
  vr::FrameScene without = burn_scene();
  mesh(without, vt::kRetina)->burns.clear();
  // The laser fires from the probe through an aim point; the burn lands where that ray meets the retina.
  const vr::Vec3 probe{-2.0f, -3.0f, -2.0f};
  const vr::Vec3 hit = vt::ray_sphere_exit(probe, vt::retina_point(14, 250), vt::kRetinaRadius);
  vr::FrameScene with = without;
  mesh(with, vt::kRetina)->burns.push_back({hit, {}, 0.45f, {}});
  const vr::StereoFrame a = render(without);
  const vr::StereoFrame b = render(with);
  EXPECT_EQ(renderer_->stats().burns_painted, 1u);
  for (int eye = 0; eye < 2; ++eye) {
    const vr::Vec2 px = vt::project_to_pixel(with, eye, hit, kW, kH);
    const Rgb before = patch(a.eye(eye), px), after = patch(b.eye(eye), px);
    EXPECT_GT(after.luma() - before.luma(), 40.0) << "eye " << eye;
    EXPECT_LT(after.spread() / std::max(after.r, 1.0), 0.35) << "burn should be whitish, eye " << eye;
    // 1.5 mm away on the retina nothing changed: the burn is local.
    const vr::Vec3 away = vt::retina_point(14, 250) + vr::Vec3{1.5f, 0.0f, 0.0f};
    const vr::Vec2 px_away = vt::project_to_pixel(with, eye, away, kW, kH);
    EXPECT_LT(std::fabs(patch(b.eye(eye), px_away).luma() - patch(a.eye(eye), px_away).luma()), 3.0);
  }
}

// The simulation hands a burn over as surface coordinates (a triangle and the barycentric point in
// it): painted exactly as the same point given by position (which the renderer must search for),
// and without a search, so a point given this way needs no nearby surface position at all.
TEST_F(RenderScenes, LaserBurnFromSurfaceCoordinatesMatchesTheSearchedOne) {
  vr::FrameScene by_position = burn_scene();
  vr::Mesh& retina = *mesh(by_position, vt::kRetina);
  retina.burns.clear();
  // a triangle of the retina in view (the one nearest the usual burn point) and a point inside it
  const vr::Vec3 target = vt::retina_point(14, 250);
  const auto& geo = *retina.geometry;
  std::size_t best = 0;
  float best_d = 1e30f;
  for (std::size_t t = 0; t < geo.indices.size() / 3; ++t) {
    const vr::Vec3 c = (geo.vertices[geo.indices[3 * t]].position_mm + geo.vertices[geo.indices[3 * t + 1]].position_mm +
                        geo.vertices[geo.indices[3 * t + 2]].position_mm) *
                       (1.0f / 3.0f);
    const float d = vr::dot(c - target, c - target);
    if (d < best_d) best_d = d, best = t;
  }
  const std::array<std::uint32_t, 3> corners{geo.indices[3 * best], geo.indices[3 * best + 1], geo.indices[3 * best + 2]};
  const std::array<float, 3> bc{0.25f, 0.35f, 0.4f};
  const vr::Vec3 point = geo.vertices[corners[0]].position_mm * bc[0] + geo.vertices[corners[1]].position_mm * bc[1] +
                         geo.vertices[corners[2]].position_mm * bc[2];
  vr::FrameScene by_triangle = by_position;
  retina.burns.push_back({point, {}, 0.45f, {}});
  vr::LaserBurn surface_point;
  surface_point.hit_point = vr::LaserBurn::SurfacePoint{corners, bc};
  surface_point.radius_mm = 0.45f;
  mesh(by_triangle, vt::kRetina)->burns.push_back(surface_point);
  vr::FrameScene none = by_triangle;
  mesh(none, vt::kRetina)->burns.clear();
  // burns are painted once into the mesh's burn texture: a frame without any in between starts it clean
  const vr::StereoFrame a = render(by_position);
  const vr::StereoFrame clean = render(none);
  const vr::StereoFrame b = render(by_triangle);
  EXPECT_EQ(renderer_->stats().burns_painted, 2u) << "one in each frame that has a burn (the counts add up)";
  EXPECT_EQ(renderer_->stats().burns_missed, 0u);
  const vr::ImageDiff d = vr::compare_images(a.eye(0), b.eye(0), 8);
  EXPECT_LT(d.rmse, 0.5) << d.summary();
  const vr::Vec2 px = vt::project_to_pixel(by_triangle, 0, point, kW, kH);
  EXPECT_GT(patch(b.eye(0), px).luma() - patch(clean.eye(0), px).luma(), 40.0) << "painted where the point lies";
}

TEST_F(RenderScenes, InstrumentCastsAShadowFromTheLightPipe) {
  vt::SyntheticOptions o;
  o.retina_triangles = 3000;
  vr::FrameScene s = vt::make_scene(o);
  // Where the light through a point of the shaft lands on the retina.
  const vr::Mesh* tool = mesh(s, vt::kInstrument);
  const vr::Vec3 shaft_point = tool->model.transform_point({0, 0, 1.5f});
  const vr::Vec3 shadow = vt::ray_sphere_exit(s.light_pipe->tip_mm, shaft_point, vt::kRetinaRadius);
  const vr::StereoFrame shadowed = render(s);
  mesh(s, vt::kInstrument)->casts_shadow = false;
  const vr::StereoFrame unshadowed = render(s);
  const vr::Vec2 px = vt::project_to_pixel(s, 0, shadow, kW, kH);
  const double in_shadow = patch(shadowed.eye(0), px).luma(), lit = patch(unshadowed.eye(0), px).luma();
  EXPECT_GT(lit, 30.0) << "the shadow point should be in the light cone";
  EXPECT_LT(in_shadow, 0.5 * lit);
}

TEST_F(RenderScenes, DetachedRetinaIsGreyishAndLifted) {
  vt::SyntheticOptions o;
  o.retina_triangles = 3000;
  const vr::FrameScene attached = vt::make_scene(o);
  o.detached = true;
  const vr::FrameScene detached = vt::make_scene(o);
  // Apex of the bulla (see synthetic_scene.cpp): 3 mm in front of the choroid.
  const vr::Vec3 apex = vt::retina_point(28, 70, vt::kRetinaRadius - 3.0f);
  const vr::Vec2 px = vt::project_to_pixel(detached, 0, apex, kW, kH);
  const Rgb a = patch(render(attached).eye(0), px, 2), d = patch(render(detached).eye(0), px, 2);
  EXPECT_LT(d.spread() / d.luma(), 0.6 * a.spread() / a.luma()) << "detached retina should be greyer";
}

TEST_F(RenderScenes, FluidGasInterfaceIsVisible) {
  vt::SyntheticOptions o;
  o.retina_triangles = 3000;
  const vr::FrameScene fluid = vt::make_scene(o);
  o.gas = true;
  const vr::FrameScene gas = vt::make_scene(o);
  // The meniscus: where the interface plane meets the globe wall, on the side toward the viewer's top.
  const float h = o.gas_level_mm, r = std::sqrt(12.0f * 12.0f - h * h) - 0.3f;
  const vr::Vec3 rim{0.0f, r, h};
  const vr::Vec2 px = vt::project_to_pixel(gas, 0, rim, kW, kH);
  const double l_fluid = patch(render(fluid).eye(0), px).luma(), l_gas = patch(render(gas).eye(0), px).luma();
  EXPECT_GT(l_gas - l_fluid, 25.0);
}

TEST_F(RenderScenes, UploadsOnlyWhatChangedAndRemovedTissueIsGone) {
  vt::SyntheticOptions o;
  o.retina_triangles = 3000;
  vr::FrameScene s = vt::make_scene(o);
  const vr::StereoFrame first = render(s);
  const vr::RenderStats after_first = renderer_->stats();
  EXPECT_EQ(after_first.vertex_uploads, s.meshes.size());
  EXPECT_EQ(after_first.texture_uploads, 2u);
  render(s);  // nothing changed
  EXPECT_EQ(renderer_->stats().vertex_uploads, after_first.vertex_uploads);
  EXPECT_EQ(renderer_->stats().index_uploads, after_first.index_uploads);
  EXPECT_EQ(renderer_->stats().texture_uploads, 2u);
  // The retina deforms: new vertex data, same topology.
  auto moved = std::make_shared<vr::MeshGeometry>(*mesh(s, vt::kRetina)->geometry);
  mesh(s, vt::kRetina)->geometry = moved;
  mesh(s, vt::kRetina)->geometry_version++;
  render(s);
  EXPECT_EQ(renderer_->stats().vertex_uploads, after_first.vertex_uploads + 1);
  EXPECT_EQ(renderer_->stats().index_uploads, after_first.index_uploads);
  // The instrument's triangles are removed (topology change): it disappears from the image.
  vr::Mesh* tool = mesh(s, vt::kInstrument);
  const vr::Vec2 px = vt::project_to_pixel(s, 0, tool->model.transform_point({0, 0, 3.0f}), kW, kH);
  auto empty = std::make_shared<vr::MeshGeometry>(*tool->geometry);
  empty->indices.clear();
  tool->geometry = empty;
  tool->topology_version++;
  const vr::StereoFrame gone = render(s);
  EXPECT_EQ(renderer_->stats().index_uploads, after_first.index_uploads + 1);
  const Rgb with_tool = patch(first.eye(0), px, 0), without_tool = patch(gone.eye(0), px, 0);
  EXPECT_GT(std::fabs(with_tool.luma() - without_tool.luma()) + std::fabs(with_tool.r - without_tool.r), 20.0);
}

namespace {
// Sum of absolute horizontal luminance steps over a centred patch: high when sharp.
double detail(const vr::Image& img) {
  double sum = 0;
  for (int y = img.height / 4; y < 3 * img.height / 4; ++y) {
    for (int x = img.width / 4; x < 3 * img.width / 4; ++x) {
      const std::uint8_t* a = &img.rgba[(static_cast<std::size_t>(y) * img.width + x) * 4];
      const std::uint8_t* b = a + 4;
      sum += std::fabs((0.2126 * a[0] + 0.7152 * a[1] + 0.0722 * a[2]) - (0.2126 * b[0] + 0.7152 * b[1] + 0.0722 * b[2]));
    }
  }
  return sum;
}
}  // namespace

TEST_F(RenderScenes, FocusBlursWhatIsOutsideTheFocalPlane) {
  vt::SyntheticOptions o;
  o.retina_triangles = 3000;
  o.instrument = false;
  vr::FrameScene s = vt::make_scene(o);
  const double no_dof = detail(render(s).eye(0));
  s.microscope.depth_of_field = true;
  // Focused on the fundus near the posterior pole (working distance + depth below the target).
  s.microscope.focus_distance_mm = s.microscope.working_distance_mm + (s.microscope.target_mm.z + vt::kRetinaRadius);
  const double focused = detail(render(s).eye(0));
  s.microscope.focus_distance_mm -= 40.0f;  // focus pedal: the sharp plane 40 mm above the fundus
  const vr::StereoFrame defocused_frame = render(s);
  const double defocused = detail(defocused_frame.eye(0));
  EXPECT_GT(focused, 0.8 * no_dof);
  EXPECT_LT(defocused, 0.6 * focused);
  EXPECT_EQ(defocused_frame.step_index, s.step_index);
}

// With a depth of field given (the simulated microscope's, which the focus score uses too), what
// lies within half of it of the focal plane is as sharp as without any blur, and what lies well
// beyond it blurs: the picture agrees with the score.
TEST_F(RenderScenes, WhatLiesWithinTheDepthOfFieldIsSharpAndWhatLiesBeyondBlurs) {
  vt::SyntheticOptions o;
  o.retina_triangles = 3000;
  o.instrument = false;
  vr::FrameScene s = vt::make_scene(o);
  s.microscope.zoom = 4.0f;  // a 7.5 mm field: the fundus in it lies within ±0.3 mm of one depth
  const double no_dof = detail(render(s).eye(0));
  s.microscope.depth_of_field = true;
  s.microscope.depth_of_field_mm = 2.0f;
  s.microscope.aperture_mm = 1000.0f;  // ignored while depth_of_field_mm is set
  const float fundus = s.microscope.working_distance_mm + (s.microscope.target_mm.z + vt::kRetinaRadius);
  s.microscope.focus_distance_mm = fundus - 0.4f;  // the fundus 0.4 mm behind the focal plane: inside ±1 mm
  const double inside = detail(render(s).eye(0));
  s.microscope.focus_distance_mm = fundus - 3.0f;  // 3 mm behind it: three times the half depth
  const double beyond = detail(render(s).eye(0));
  EXPECT_GT(inside, 0.97 * no_dof) << "within the depth of field nothing blurs";
  EXPECT_LT(beyond, 0.8 * no_dof) << "beyond it the fundus blurs";
}

namespace {
// A flat disc (membrane patch) or a sphere (gel body) as extra meshes for the synthetic scene.
vr::MeshGeometryPtr disc_mesh(vr::Vec3 centre, float radius) {
  auto g = std::make_shared<vr::MeshGeometry>();
  g->vertices.push_back({centre, {0, 0, 1}, {0.5f, 0.5f}});
  const int n = 32;
  for (int i = 0; i <= n; ++i) {
    const float a = 6.2831853f * i / n;
    g->vertices.push_back({centre + vr::Vec3{radius * std::cos(a), radius * std::sin(a), 0}, {0, 0, 1}, {0.5f, 0.5f}});
    if (i > 0) g->indices.insert(g->indices.end(), {0u, static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(i + 1)});
  }
  return g;
}
}  // namespace

TEST_F(RenderScenes, MembraneIsWhitishAndGelOnlyVeilsTheFundus) {
  vt::SyntheticOptions o;
  o.retina_triangles = 3000;
  o.instrument = false;
  vr::FrameScene s = vt::make_scene(o);
  const vr::StereoFrame plain = render(s);
  // An epiretinal membrane patch 0.8 mm in front of the retina, inside the light cone.
  const vr::Vec3 centre{1.5f, 1.0f, -11.0f};
  vr::Mesh membrane;
  membrane.id = 20;
  membrane.material = vr::MaterialKind::Membrane;
  membrane.geometry = disc_mesh(centre, 1.2f);
  vr::FrameScene with_membrane = s;
  with_membrane.meshes.push_back(membrane);
  const vr::Vec2 px = vt::project_to_pixel(s, 0, centre, kW, kH);
  const Rgb before = patch(plain.eye(0), px), after = patch(render(with_membrane).eye(0), px);
  EXPECT_LT(after.spread() / after.luma(), 0.6 * before.spread() / before.luma()) << "membrane should be whitish";
  EXPECT_GT(after.luma(), before.luma());
  // Vitreous gel filling the cavity: a faint veil — the fundus detail stays mostly visible.
  vr::Mesh gel;
  gel.id = 21;
  gel.material = vr::MaterialKind::Gel;
  gel.geometry = disc_mesh({0, 0, -6.0f}, 10.0f);
  vr::FrameScene with_gel = s;
  with_gel.meshes.push_back(gel);
  // A whitish veil: the fundus is less saturated, yet its detail stays visible.
  const vr::StereoFrame veiled = render(with_gel);
  const vr::Vec2 mid{kW / 2.0f, kH / 2.0f};
  const Rgb p_plain = patch(plain.eye(0), mid, 20), p_gel = patch(veiled.eye(0), mid, 20);
  EXPECT_LT(p_gel.spread() / p_gel.luma(), 0.97 * p_plain.spread() / p_plain.luma());
  EXPECT_GT(detail(veiled.eye(0)), 0.6 * detail(plain.eye(0)));
}

TEST_F(RenderScenes, BurnGivenAsUvMatchesBurnGivenAsPositionAndResetsWithTheCase) {
  vr::FrameScene s = burn_scene();
  vr::Mesh* retina = mesh(s, vt::kRetina);
  retina->burns.clear();
  const vr::StereoFrame clean = render(s);
  // The synthetic retina's radial uv mapping (synthetic_scene.cpp): r = 0.5·θ/95°, angle φ.
  const float theta = 14.0f, phi = 250.0f * 3.14159265f / 180.0f, r = 0.5f * theta / 95.0f;
  retina->burns = {{vt::retina_point(theta, 250.0f), {}, 0.45f, {}}};
  const vr::Image by_position = render(s).side_by_side();
  vr::FrameScene s_uv = s;
  mesh(s_uv, vt::kRetina)->burns = {{{}, vr::Vec2{0.5f + r * std::cos(phi), 0.5f + r * std::sin(phi)}, 0.45f, {}}};
  // A fresh renderer, so the burn texture starts clean.
  renderer_ = std::make_unique<vr::StereoRenderer>(vr::RenderSettings{kW, kH, 512, 512});
  const vr::Image by_uv = render(s_uv).side_by_side();
  const vr::ImageDiff d = vr::compare_images(by_uv, by_position, 24);
  EXPECT_LT(d.rmse, 1.0) << d.summary();
  EXPECT_GT(vr::compare_images(by_position, clean.side_by_side()).max_abs_diff, 40);  // the burn is there
  // A new case: the burn list starts again empty, and the old burn is gone.
  mesh(s_uv, vt::kRetina)->burns.clear();
  EXPECT_LT(vr::compare_images(render(s_uv).side_by_side(), clean.side_by_side()).rmse, 0.01);
}
