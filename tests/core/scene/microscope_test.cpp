// The microscope as simulation state: starting centred on the region of interest, motors that reach
// their targets at the documented speeds (checked against closed-form times), X–Y speed falling
// with magnification, limits, the wide-angle system's inversion, and determinism of the state hash.
#include <gtest/gtest.h>

#include <cmath>

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
}

}  // namespace
}  // namespace vitreo::core
