// The microscope as simulation state: starting centred on the region of interest, motors that reach
// their targets at the documented speeds (checked against closed-form times), X–Y speed falling
// with magnification, limits, the wide-angle system's inversion, and determinism of the state hash;
// the view on an eye (field and depth of field) against positions and Berek's formula worked by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

#include "core/anatomy/eye_model.hpp"
#include "core/common/status.hpp"
#include "core/scene/microscope.hpp"

namespace vitreo::core {
namespace {

constexpr double kDt = 1e-3;

int steps_until(Microscope& m, const MicroscopeInput& in, auto done, int limit = 100000) {
  for (int i = 0; i < limit; ++i) {
    if (done()) return i;
    m.step(kDt, in);
  }
  return limit;
}

TEST(Microscope, StartsCentredOnTheRegionOfInterestInFocusAtLowestZoom) {
  MicroscopeSettings s;
  const Microscope m(s, Vec2(-7.5, 12.0));
  EXPECT_EQ(m.center_mm(), Vec2(-7.5, 12.0));
  EXPECT_EQ(m.zoom(), s.zoom_min);
  EXPECT_EQ(m.focus_mm(), 0.0);
  EXPECT_FALSE(m.wide_angle());
  EXPECT_TRUE(m.reinverter());
  EXPECT_DOUBLE_EQ(m.field_deg(), s.field_deg);
}

TEST(Microscope, ZoomTravelsInLogMagnificationAtItsRate) {
  MicroscopeSettings s;
  Microscope m(s, Vec2::Zero());
  m.set_zoom(4.0);
  const int n = steps_until(m, {}, [&] { return m.zoom() == 4.0; });
  // ln(4)/rate seconds, to within a step.
  EXPECT_NEAR(n * kDt, std::log(4.0) / s.zoom_rate_per_s, 1.5 * kDt);
  m.set_zoom(1000.0);  // clamped to the range
  steps_until(m, {}, [&] { return m.zoom() == s.zoom_max; });
  EXPECT_EQ(m.zoom(), s.zoom_max);
  EXPECT_DOUBLE_EQ(m.field_deg(), s.field_deg / s.zoom_max);
  m.set_zoom(std::nan(""));  // ignored
  m.step(kDt, {});
  EXPECT_EQ(m.zoom(), s.zoom_max);
}

TEST(Microscope, FocusMovesAtItsSpeedWithinItsRange) {
  MicroscopeSettings s;
  Microscope m(s, Vec2::Zero());
  m.set_focus(1.6);
  const int n = steps_until(m, {}, [&] { return m.focus_mm() == 1.6; });
  EXPECT_NEAR(n * kDt, 1.6 / s.focus_speed_mm_s, 1.5 * kDt);
  m.set_focus(-100.0);
  steps_until(m, {}, [&] { return m.focus_mm() == -0.5 * s.focus_range_mm; });
  EXPECT_EQ(m.focus_mm(), -0.5 * s.focus_range_mm);
}

TEST(Microscope, JoystickPansAtASpeedThatFallsWithMagnification) {
  MicroscopeSettings s;
  for (double zoom : {1.0, 2.0, 5.0}) {
    Microscope m(s, Vec2(1.0, 2.0));
    m.set_zoom(zoom);
    steps_until(m, {}, [&] { return m.zoom() == zoom; });
    MicroscopeInput right;
    right.pan = Vec2(1.0, 0.0);
    for (int i = 0; i < 500; ++i) m.step(kDt, right);  // half a second, full deflection
    EXPECT_NEAR(m.center_mm().x() - 1.0, 0.5 * s.pan_speed_mm_s / zoom, 1e-9) << "zoom " << zoom;
    EXPECT_NEAR(m.center_mm().y(), 2.0, 1e-12);
    // Released: it stops where it is.
    const Vec2 held = m.center_mm();
    for (int i = 0; i < 100; ++i) m.step(kDt, {});
    EXPECT_EQ(m.center_mm(), held);
  }
}

TEST(Microscope, CommandedPanTravelsToTheOffsetAndStaysOnTheFundus) {
  MicroscopeSettings s;
  Microscope m(s, Vec2(3.0, -4.0));
  m.pan_to(Vec2(2.0, 0.0));
  const int n = steps_until(m, {}, [&] { return m.center_mm() == Vec2(5.0, -4.0); });
  EXPECT_NEAR(n * kDt, 2.0 / s.pan_speed_mm_s, 1.5 * kDt);
  m.pan_to(Vec2(500.0, 0.0));  // beyond the travel: stops at its edge
  steps_until(m, {}, [&] { return false; }, 20000);
  EXPECT_NEAR(m.center_mm().norm(), s.pan_travel_mm, 1e-9);
  MicroscopeInput out;
  out.pan = Vec2(1.0, 0.0);
  for (int i = 0; i < 2000; ++i) m.step(kDt, out);
  EXPECT_LE(m.center_mm().norm(), s.pan_travel_mm + 1e-9);
}

TEST(Microscope, WideAngleImageIsInvertedOnlyWithoutTheReinverter) {
  MicroscopeSettings s;
  Microscope m(s, Vec2::Zero());
  EXPECT_FALSE(m.image_inverted());
  m.toggle_wide_angle();
  EXPECT_DOUBLE_EQ(m.field_deg(), s.wide_field_deg);
  EXPECT_FALSE(m.image_inverted()) << "re-inverter engaged by default";
  m.toggle_reinverter();
  EXPECT_TRUE(m.image_inverted());
  m.toggle_wide_angle();
  EXPECT_FALSE(m.image_inverted()) << "the standard view is upright without a re-inverter";
}

TEST(Microscope, SameInputsSameHashAndEveryStateChangesIt) {
  MicroscopeSettings s;
  auto run = [&](double pan_y) {
    Microscope m(s, Vec2(1.0, 1.0));
    m.set_zoom(3.0);
    m.set_focus(0.7);
    MicroscopeInput in;
    in.pan = Vec2(0.3, pan_y);
    for (int i = 0; i < 300; ++i) m.step(kDt, in);
    StateHasher h;
    m.hash_into(h);
    return h.value();
  };
  EXPECT_EQ(run(-0.2), run(-0.2));
  EXPECT_NE(run(-0.2), run(-0.21));
  Microscope a(s, Vec2::Zero()), b(s, Vec2::Zero());
  b.toggle_reinverter();
  StateHasher ha, hb;
  a.hash_into(ha);
  b.hash_into(hb);
  EXPECT_NE(ha.value(), hb.value());
}

// A small eye: the view needs its landmarks, not a fine retina.
const EyeModel& small_eye() {
  static const EyeModel eye = [] {
    EyeParameters p;
    p.retina_vertices = 500;
    p.gel_shells = 0;
    return build_eye_model(p);
  }();
  return eye;
}

// Centred on the posterior pole, the view looks straight down −z from just behind the lens at the
// retina over the pole; a tip belongs to the field while its angle off that axis is within the
// field's half angle (tan 20° at zoom 1 through the contact lens, over the zoom).
TEST(Microscope, ViewOnThePoleHoldsTipsWithinTheFieldAngle) {
  const EyeModel& eye = small_eye();
  const double eye_z = eye.lens_center_z_mm - 0.5 * eye.parameters.lens_thickness_mm - 0.5;
  const double retina_z = -eye.wall.radius_toward(-Vec3::UnitZ()) + eye.parameters.retina_thickness_mm;
  for (const double zoom : {1.0, 2.5}) {
    Microscope m(MicroscopeSettings{}, Vec2::Zero());
    m.set_zoom(zoom);
    steps_until(m, {}, [&] { return m.zoom() == zoom; });
    const MicroscopeView v = m.view(eye);
    EXPECT_NEAR((v.eye_point_mm - Vec3(0, 0, eye_z)).norm(), 0.0, 1e-12);
    EXPECT_NEAR((v.target_mm - Vec3(0, 0, retina_z)).norm(), 0.0, 1e-9);
    EXPECT_NEAR((v.axis - Vec3(0, 0, -1)).norm(), 0.0, 1e-9);
    const double half_tan = std::tan(20.0 * std::numbers::pi / 180.0) / zoom;
    // A tip 3 mm above the retina, at 0.5 and 1.5 field radii to the nasal side and upward.
    const double z = retina_z + 3.0, depth = eye_z - z;
    EXPECT_NEAR(v.field_radius(Vec3(0.5 * half_tan * depth, 0, z)), 0.5, 1e-9);
    EXPECT_TRUE(v.in_field(Vec3(0, 0.99 * half_tan * depth, z)));
    EXPECT_FALSE(v.in_field(Vec3(0, 1.01 * half_tan * depth, z)));
    EXPECT_NEAR(v.field_radius(Vec3(0, -1.5 * half_tan * depth, z)), 1.5, 1e-9);
    EXPECT_EQ(v.field_radius(Vec3(0, 0, eye_z + 1.0)), std::numeric_limits<double>::infinity()) << "behind the eye point";
  }
}

// Panned 4 mm nasally along the fundus: the field centre is the wall point 4 mm of arc from the
// pole (polar angle 4 / R on a sphere of the wall's radius there), one retina thickness inside.
TEST(Microscope, PanMovesTheFieldCentreAlongTheFundus) {
  const EyeModel& eye = small_eye();
  Microscope m(MicroscopeSettings{}, Vec2::Zero());
  m.pan_to(Vec2(4.0, 0.0));
  steps_until(m, {}, [&] { return m.center_mm() == Vec2(4.0, 0.0); });
  const MicroscopeView v = m.view(eye);
  const Vec3 wall = eye.wall_point(eye.polar_at_arc(4.0), 0.0);
  EXPECT_NEAR((v.target_mm - (wall - 0.25 * wall.normalized())).norm(), 0.0, 1e-9);
  EXPECT_GT(v.target_mm.x(), 3.5);  // nasal (+x), about 4 mm from the axis on a 11 mm wall
  EXPECT_LT(v.target_mm.x(), 4.0);
  EXPECT_NEAR(v.field_radius(v.target_mm), 0.0, 1e-9);
  EXPECT_GT(v.field_radius(eye.fovea_mm), 0.3) << "the pole is now off centre";
  EXPECT_NEAR(v.up.dot(v.axis), 0.0, 1e-12);
  EXPECT_GT(v.up.y(), 0.99) << "fundus +y is the image's up";
}

// Berek's visual depth of field, T = n [λ/(2 NA²) + 0.34 mm/(NA M)], worked by hand for the
// defaults (NA 0.025, 4× at zoom 1, n = 1.336, λ = 0.55 µm): 1.336 · (0.44 + 3.4) = 5.13024 mm at
// zoom 1, 1.336 · (0.44 + 0.85) = 1.72344 mm at zoom 4; the wide-angle view's lateral
// magnification tan 20° / tan 55° multiplies it by (tan 55° / tan 20°)². The focal plane lies on
// the retina at the field centre (focus 0), or focus mm in front of it; a tip is in focus within
// half the depth of field of it.
TEST(Microscope, DepthOfFieldIsBereksAndBoundsTheFocus) {
  const EyeModel& eye = small_eye();
  MicroscopeSettings s;
  EXPECT_NEAR(depth_of_field_mm(s, 1.0, false), 5.13024, 1e-9);
  EXPECT_NEAR(depth_of_field_mm(s, 4.0, false), 1.72344, 1e-9);
  const double ratio = std::tan(55.0 * std::numbers::pi / 180.0) / std::tan(20.0 * std::numbers::pi / 180.0);
  EXPECT_NEAR(depth_of_field_mm(s, 1.0, true), 5.13024 * ratio * ratio, 1e-9);
  EXPECT_GT(depth_of_field_mm(s, 1.0, true), 24.0) << "the wide-angle view holds the whole eye in focus";

  Microscope m(s, Vec2::Zero());
  const double retina_z = -eye.wall.radius_toward(-Vec3::UnitZ()) + eye.parameters.retina_thickness_mm;
  const double half = 0.5 * 5.13024;
  MicroscopeView v = m.view(eye);
  EXPECT_NEAR(v.depth_of_field_mm, 5.13024, 1e-9);
  EXPECT_TRUE(v.in_focus(Vec3(0, 0, retina_z + half - 0.01)));
  EXPECT_FALSE(v.in_focus(Vec3(0, 0, retina_z + half + 0.01)));
  EXPECT_NEAR(v.defocus_mm(Vec3(0, 0, retina_z + 2.0)), -2.0, 1e-9) << "in front of the focal plane";
  // Focus 2 mm toward the microscope: the plane rises off the retina with it.
  m.set_focus(2.0);
  steps_until(m, {}, [&] { return m.focus_mm() == 2.0; });
  v = m.view(eye);
  EXPECT_NEAR(v.defocus_mm(Vec3(0, 0, retina_z + 2.0)), 0.0, 1e-9);
  EXPECT_TRUE(v.in_focus(Vec3(0, 0, retina_z + 2.0 + half - 0.01)));
  EXPECT_FALSE(v.in_focus(Vec3(0, 0, retina_z + 2.0 - half - 0.01)));
}

TEST(Microscope, RefusesBadSettings) {
  MicroscopeSettings s;
  s.zoom_max = 0.5;
  EXPECT_THROW(Microscope(s, Vec2::Zero()), InvalidArgument);
  s = {};
  s.field_deg = 180.0;
  EXPECT_THROW(Microscope(s, Vec2::Zero()), InvalidArgument);
  s = {};
  s.pan_speed_mm_s = std::nan("");
  EXPECT_THROW(Microscope(s, Vec2::Zero()), InvalidArgument);
  s = {};
  s.numerical_aperture = 0.0;
  EXPECT_THROW(Microscope(s, Vec2::Zero()), InvalidArgument);
}

}  // namespace
}  // namespace vitreo::core
