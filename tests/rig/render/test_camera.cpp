// The stereo microscope's geometry, checked analytically (no GL needed).
#include <gtest/gtest.h>

#include <cmath>

#include "synthetic_scene.hpp"
#include "vitreo/render/camera.hpp"

namespace vr = vitreo::render;
using vr::testing::project_to_pixel;

namespace {
constexpr int kW = 160, kH = 128;

vr::FrameScene scene_with(vr::Microscope m) {
  vr::FrameScene s;
  s.microscope = m;
  return s;
}
}  // namespace

TEST(StereoCamera, NearPointsHaveCrossedDisparityDeepPointsUncrossed) {
  const vr::FrameScene s = scene_with({});
  const vr::Vec3 target = s.microscope.target_mm;
  // Nearer the microscope (+z) than the working plane: further right in the left eye.
  const vr::Vec3 near_p = target + vr::Vec3{0, 0, 5};
  EXPECT_GT(project_to_pixel(s, 0, near_p, kW, kH).x - project_to_pixel(s, 1, near_p, kW, kH).x, 1.0f);
  // Deeper (downward for the supine patient): further left in the left eye.
  const vr::Vec3 deep_p = target + vr::Vec3{0, 0, -3.5f};
  EXPECT_LT(project_to_pixel(s, 0, deep_p, kW, kH).x - project_to_pixel(s, 1, deep_p, kW, kH).x, -0.5f);
  // No vertical parallax.
  EXPECT_NEAR(project_to_pixel(s, 0, near_p, kW, kH).y, project_to_pixel(s, 1, near_p, kW, kH).y, 1e-3f);
}

TEST(StereoCamera, ZeroDisparityOnTheConvergencePlane) {
  vr::Microscope m;
  const vr::FrameScene s = scene_with(m);
  for (const vr::Vec3 p : {m.target_mm, m.target_mm + vr::Vec3{4, -3, 0}}) {
    const auto l = project_to_pixel(s, 0, p, kW, kH), r = project_to_pixel(s, 1, p, kW, kH);
    EXPECT_NEAR(l.x, r.x, 1e-3f);
    EXPECT_NEAR(l.y, r.y, 1e-3f);
  }
  // Converging 5 mm deeper moves the zero-disparity plane there.
  m.convergence_distance_mm = m.working_distance_mm + 5.0f;
  const vr::FrameScene s2 = scene_with(m);
  const vr::Vec3 deeper = m.target_mm - vr::Vec3{0, 0, 5};
  EXPECT_NEAR(project_to_pixel(s2, 0, deeper, kW, kH).x, project_to_pixel(s2, 1, deeper, kW, kH).x, 1e-3f);
  EXPECT_GT(project_to_pixel(s2, 0, m.target_mm, kW, kH).x - project_to_pixel(s2, 1, m.target_mm, kW, kH).x, 0.5f);
}

TEST(StereoCamera, SupineOrientationXRightYUpDepthAway) {
  const vr::FrameScene s = scene_with({});
  const vr::Vec3 t = s.microscope.target_mm;
  const auto centre = project_to_pixel(s, 0, t, kW, kH);
  EXPECT_GT(project_to_pixel(s, 0, t + vr::Vec3{3, 0, 0}, kW, kH).x, centre.x + 5);  // +x to the right
  EXPECT_LT(project_to_pixel(s, 0, t + vr::Vec3{0, 3, 0}, kW, kH).y, centre.y - 5);  // +y up (row 0 = top)
  const vr::StereoViews v = vr::stereo_views(s.microscope, 12.0f, kW, kH);
  EXPECT_GT(v.eye[0].position_mm.z, 100.0f);  // the microscope is above the patient, looking down −z
  EXPECT_FLOAT_EQ(v.forward.z, -1.0f);
  EXPECT_LT(v.eye[0].position_mm.x, v.eye[1].position_mm.x);  // left eye at −x
}

TEST(StereoCamera, ZoomMagnifiesAboutTheTarget) {
  vr::Microscope m;
  const vr::Vec3 off = m.target_mm + vr::Vec3{4, 0, 0};
  const float d1 = project_to_pixel(scene_with(m), 0, off, kW, kH).x - project_to_pixel(scene_with(m), 0, m.target_mm, kW, kH).x;
  m.zoom = 2.0f;
  const float d2 = project_to_pixel(scene_with(m), 0, off, kW, kH).x - project_to_pixel(scene_with(m), 0, m.target_mm, kW, kH).x;
  EXPECT_NEAR(d2 / d1, 2.0f, 1e-3f);
}

TEST(StereoCamera, WideAngleSeesToTheEquator) {
  vr::Microscope m;
  const vr::Vec3 equator{11.5f, 0, 0};
  // The standard view at zoom 2 does not reach the equator; the wide-angle view does.
  m.zoom = 2.0f;
  EXPECT_GT(project_to_pixel(scene_with(m), 0, equator, kW, kH).x, static_cast<float>(kW));
  m.zoom = 1.0f;
  m.wide_angle = true;
  const auto p = project_to_pixel(scene_with(m), 0, equator, kW, kH);
  EXPECT_GT(p.x, 0.0f);
  EXPECT_LT(p.x, static_cast<float>(kW));
  EXPECT_LT(vr::stereo_views(m, 12.0f, kW, kH).eye[0].position_mm.z, 20.0f);
}

// Through the eye's optics from the pupil: the field is centred on the target wherever it lies on
// the fundus, image_up (projected) points up, zoom narrows the field about the target, and without
// the re-inverter the picture turns 180° with the disparity of every point reversed.
TEST(StereoCamera, PupilViewLooksAtTheTargetWithItsUpAndZoom) {
  vr::Microscope m;
  m.wide_angle = true;
  m.view_point_mm = vr::Vec3{0, 0, 4};
  m.wide_field_deg = 40.0f;
  m.target_mm = vr::testing::retina_point(60.0f, 135.0f);
  m.image_up = vr::Vec3{0, 0, 1};  // toward the front of the eye
  const vr::FrameScene s = scene_with(m);
  const auto c = project_to_pixel(s, 0, m.target_mm, kW, kH), cr = project_to_pixel(s, 1, m.target_mm, kW, kH);
  EXPECT_NEAR(c.x, kW / 2.0f, 1e-2f);
  EXPECT_NEAR(c.y, kH / 2.0f, 1e-2f);
  EXPECT_NEAR(cr.x, kW / 2.0f, 1e-2f) << "both eyes converge on the target";
  const vr::Vec3 anterior = vr::testing::retina_point(65.0f, 135.0f);  // nearer the ora
  EXPECT_LT(project_to_pixel(s, 0, anterior, kW, kH).y, c.y - 3) << "the front of the eye is up in the image";
  const vr::Vec3 off = vr::testing::retina_point(60.0f, 140.0f);
  const float d1 = std::hypot(project_to_pixel(s, 0, off, kW, kH).x - c.x, project_to_pixel(s, 0, off, kW, kH).y - c.y);
  m.zoom = 2.5f;
  const vr::FrameScene z = scene_with(m);
  const float d2 = std::hypot(project_to_pixel(z, 0, off, kW, kH).x - c.x, project_to_pixel(z, 0, off, kW, kH).y - c.y);
  EXPECT_NEAR(d2 / d1, 2.5f, 0.05f) << "tan(field/2) / zoom: close to ×zoom for a small offset";
  m.zoom = 1.0f;
  m.image_inverted = true;
  const vr::FrameScene inv = scene_with(m);
  const vr::Vec3 near_p = m.target_mm * 0.7f;
  const float d_up = project_to_pixel(s, 0, near_p, kW, kH).x - project_to_pixel(s, 1, near_p, kW, kH).x;
  const float d_inv = project_to_pixel(inv, 0, near_p, kW, kH).x - project_to_pixel(inv, 1, near_p, kW, kH).x;
  EXPECT_NEAR(d_inv, -d_up, 1e-3f);
  const auto pi = project_to_pixel(inv, 0, anterior, kW, kH), pu = project_to_pixel(s, 0, anterior, kW, kH);
  EXPECT_NEAR(pi.x, kW - pu.x, 1e-2f);
  EXPECT_NEAR(pi.y, kH - pu.y, 1e-2f);
}
