#include <gtest/gtest.h>

#include <iterator>

#include <fstream>

#include <cmath>
#include <numbers>

#include "rig/input/controls.hpp"
#include "rig/input/port_pivot.hpp"

using namespace vitreo;
using core::Quat;
using core::Vec3;

namespace {
// A port on the temporal pars plana: 11 mm from the centre, 30° anterior of the equator.
rig::Port temporal_port() {
  const double a = 30.0 * std::numbers::pi / 180.0;
  rig::Port p;
  p.outward = Vec3(-std::cos(a), 0.0, std::sin(a));
  p.position_mm = 11.0 * p.outward;
  return p;
}
Quat shaft_along(const Vec3& dir) { return Quat::FromTwoVectors(Vec3::UnitZ(), dir.normalized()); }
}  // namespace

TEST(PortPivot, TheShaftRunsFromThePortThroughTheTip) {
  const rig::Port port = temporal_port();
  rig::TrackedPose t;
  t.tip_mm = Vec3(2.0, 1.0, -3.0);
  t.orientation = shaft_along(t.tip_mm - port.position_mm);
  t.actuation = 0.4;
  rig::InstrumentPose pose;
  ASSERT_TRUE(rig::map_through_port(t, port, Quat::Identity(), {}, pose));
  EXPECT_TRUE(pose.inserted);
  EXPECT_NEAR((pose.tip_mm - t.tip_mm).norm(), 0.0, 1e-12);
  EXPECT_NEAR(pose.insertion_mm, (t.tip_mm - port.position_mm).norm(), 1e-12);
  EXPECT_NEAR((pose.axis - (t.tip_mm - port.position_mm).normalized()).norm(), 0.0, 1e-12);
  EXPECT_DOUBLE_EQ(pose.actuation, 0.4);
}

TEST(PortPivot, ATipOutsideTheEyeIsNotInserted) {
  const rig::Port port = temporal_port();
  rig::TrackedPose t;
  t.tip_mm = port.position_mm + 2.0 * port.outward;
  rig::InstrumentPose pose;
  ASSERT_TRUE(rig::map_through_port(t, port, Quat::Identity(), {}, pose));
  EXPECT_FALSE(pose.inserted);
  EXPECT_EQ(pose.insertion_mm, 0.0);
}

TEST(PortPivot, RotatingTheEyeTurnsItUnderAStillInstrument) {
  // The surgeon rolls the eye 10° about x; an instrument held still in the rig is, in the eye's
  // own frame, turned by −10°.
  const rig::Port port = temporal_port();
  rig::TrackedPose t;
  t.tip_mm = Vec3(0.0, 2.0, -4.0);
  const Quat eye(Eigen::AngleAxisd(10.0 * std::numbers::pi / 180.0, Vec3::UnitX()));
  rig::InstrumentPose pose;
  ASSERT_TRUE(rig::map_through_port(t, port, eye, {}, pose));
  EXPECT_NEAR((pose.tip_mm - eye.conjugate() * t.tip_mm).norm(), 0.0, 1e-12);
}

TEST(PortPivot, TwistAboutTheShaftIsTheRoll) {
  const rig::Port port = temporal_port();
  rig::TrackedPose t;
  t.tip_mm = Vec3(1.0, -1.0, -2.0);
  const Vec3 axis = (t.tip_mm - port.position_mm).normalized();
  t.orientation = shaft_along(axis);
  rig::InstrumentPose base, turned;
  ASSERT_TRUE(rig::map_through_port(t, port, Quat::Identity(), {}, base));
  t.orientation = Quat(Eigen::AngleAxisd(0.5, axis)) * t.orientation;
  ASSERT_TRUE(rig::map_through_port(t, port, Quat::Identity(), {}, turned));
  double d = turned.roll_rad - base.roll_rad;
  d = std::atan2(std::sin(d), std::cos(d));
  EXPECT_NEAR(d, 0.5, 1e-9);
}

TEST(PortPivot, NonFiniteOrNonUnitInputIsRefused) {
  rig::InstrumentPose pose;
  pose.insertion_mm = 7.0;
  rig::TrackedPose t;
  t.tip_mm = Vec3(std::nan(""), 0, 0);
  EXPECT_FALSE(rig::map_through_port(t, temporal_port(), Quat::Identity(), {}, pose));
  t.tip_mm = Vec3::Zero();
  t.orientation = Quat(2.0, 0.0, 0.0, 0.0);
  EXPECT_FALSE(rig::map_through_port(t, temporal_port(), Quat::Identity(), {}, pose));
  EXPECT_EQ(pose.insertion_mm, 7.0) << "a refused sample leaves the pose as it was";
}

TEST(Pedals, TravelSetsVacuumAndCutRateAndSwitchesAct) {
  rig::PedalMapper m;
  rig::PedalReading r;
  r.pedal_id = 0;
  r.axis_count = 2;
  r.axes[0] = 0.5;
  r.axes[1] = 1.0;
  ASSERT_TRUE(m.apply(r));
  EXPECT_DOUBLE_EQ(m.controls().vacuum_mmhg, 325.0);
  EXPECT_DOUBLE_EQ(m.controls().cut_rate_cpm, 10000.0);
  r.switches = 1u << 2;  // instrument change: counted once per press
  ASSERT_TRUE(m.apply(r));
  ASSERT_TRUE(m.apply(r));
  r.switches = 0;
  ASSERT_TRUE(m.apply(r));
  r.switches = (1u << 2) | (1u << 1);
  ASSERT_TRUE(m.apply(r));
  EXPECT_EQ(m.controls().instrument_changes, 2u);
  EXPECT_TRUE(m.controls().laser_fire);
  EXPECT_FALSE(m.controls().pick_out) << "the laser's switch is not the pick's";
  r.switches = 1u << 4;  // the light pipe's pick: out while held
  ASSERT_TRUE(m.apply(r));
  EXPECT_TRUE(m.controls().pick_out);
  EXPECT_FALSE(m.controls().laser_fire);
  r.switches = 0;
  ASSERT_TRUE(m.apply(r));
  EXPECT_FALSE(m.controls().pick_out);
  r.switches = (1u << 2) | (1u << 1);
  r.axes[0] = 0.0;
  ASSERT_TRUE(m.apply(r));
  EXPECT_EQ(m.controls().cut_rate_cpm, 0.0) << "no cutting without suction";
}

TEST(Pedals, MicroscopePedalZoomsFocusesAndStepsTheLight) {
  rig::PedalMapper m;
  rig::PedalReading r;
  r.pedal_id = 1;
  r.axis_count = 2;
  r.axes[0] = 1.0;
  r.axes[1] = 0.25;
  r.switches = 1;  // light up
  ASSERT_TRUE(m.apply(r));
  EXPECT_DOUBLE_EQ(m.controls().zoom, 4.0);
  EXPECT_DOUBLE_EQ(m.controls().focus_offset_mm, -1.5);
  EXPECT_NEAR(m.controls().light_level, 0.8, 1e-12);
  EXPECT_EQ(m.controls().pan_x, 0.0) << "a pedal without joystick axes leaves the field still";
  EXPECT_EQ(m.controls().pan_y, 0.0);
}

TEST(Pedals, MicroscopeJoystickHasADeadBandAndFullDeflection) {
  rig::PedalMapper m;
  rig::PedalReading r;
  r.pedal_id = 1;
  r.axis_count = 4;
  r.axes[0] = 0.0;
  r.axes[1] = 0.5;
  r.axes[2] = 0.52;  // inside the dead band (0.08 of the half travel)
  r.axes[3] = 0.0;   // full deflection down
  ASSERT_TRUE(m.apply(r));
  EXPECT_EQ(m.controls().pan_x, 0.0);
  EXPECT_DOUBLE_EQ(m.controls().pan_y, -1.0);
  r.axes[2] = 0.77;  // half way between the dead band's edge (0.54) and the end
  ASSERT_TRUE(m.apply(r));
  EXPECT_NEAR(m.controls().pan_x, 0.5, 1e-12);
}

TEST(Pedals, ABrokenPedalCannotOpenTheVacuum) {
  rig::PedalMapper m;
  rig::PedalReading r;
  r.axis_count = 2;
  r.axes[0] = std::nan("");
  EXPECT_FALSE(m.apply(r));
  r.axes[0] = 1.5;
  EXPECT_FALSE(m.apply(r));
  EXPECT_EQ(m.controls().vacuum_mmhg, 0.0);
}

TEST(Pedals, MappingConfigurationIsValidatedWithLineNumbers) {
  const auto m = rig::parse_pedal_mapping("[pedals]\nvacuum_max_mmhg = 500\ncut_rate_axis = -1\n", "rig.toml");
  EXPECT_EQ(m.vacuum_max_mmhg, 500.0);
  EXPECT_EQ(m.cut_rate_axis, -1);
  try {
    rig::parse_pedal_mapping("[pedals]\nvacuum_max_mmhg = 500\nvacum_axis = 1\n", "rig.toml");
    FAIL() << "unknown key accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("rig.toml:3: pedals.vacum_axis: unknown key"), std::string::npos) << e.what();
  }
  EXPECT_THROW(rig::parse_pedal_mapping("[pedals]\nvacuum_max_mmhg = 5000\n", "x"), std::runtime_error);
  EXPECT_THROW(rig::parse_pedal_mapping("[pedals]\nvacuum_axis = 0.5\n", "x"), std::runtime_error);
  EXPECT_THROW(rig::parse_pedal_mapping("[pedals\n", "x"), std::runtime_error);
}

// Issue 20: one switch for both laser and reflux was accepted (every laser shot would reflux too).
TEST(Pedals, ASwitchOrAxisDoingTwoJobsIsRefusedWithBothNames) {
  auto refused = [](const std::string& toml, const char* says) {
    try {
      rig::parse_pedal_mapping(toml, "rig.toml");
      ADD_FAILURE() << "accepted: " << toml;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
    }
  };
  refused("[pedals]\nlaser_switch = 0\n", "pedals.reflux_switch and pedals.laser_switch are the same switch (0)");
  refused("[pedals]\nair_switch = 2\n", "pedals.instrument_switch and pedals.air_switch are the same switch (2)");
  refused("[pedals]\npick_switch = 1\n", "pedals.laser_switch and pedals.pick_switch are the same switch (1)");
  refused("[pedals]\npick_switch = 16\n", "pedals.pick_switch: 16");
  refused("[pedals]\ncut_rate_axis = 0\n", "pedals.vacuum_axis and pedals.cut_rate_axis are the same axis (0)");
  refused("[pedals]\nlight_down_switch = 0\n", "the same switch");
  refused("[pedals]\nfocus_axis = 0\n", "the same axis");
  refused("[pedals]\nmicroscope_pedal_id = 0\n", "the same pedal id");
  // "none" (-1) may repeat; the shipped rig file is consistent.
  EXPECT_NO_THROW(rig::parse_pedal_mapping("[pedals]\nreflux_switch = -1\nlaser_switch = -1\n", "rig.toml"));
  std::ifstream f(std::string(VITREO_SOURCE_DIR) + "/rig/config/default-rig.toml");
  const std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  ASSERT_FALSE(text.empty());
  EXPECT_NO_THROW(rig::parse_pedal_mapping(text, "default-rig.toml"));
}

// toml++ 3.3.0's undefined behaviour (rig/files/toml_guard.hpp) is kept away from pedal files too.
TEST(Pedals, TextTomlPlusPlusWouldMisbehaveOnIsRefusedWithItsLine) {
  for (const char* bad : {"[&x]\n", "[pedals]\nfo \xc2\xb5 = 1\n", "[[[a]]]\n"}) {
    try {
      rig::parse_pedal_mapping(bad, "rig.toml");
      ADD_FAILURE() << "accepted: " << bad;
    } catch (const std::runtime_error& e) {
      EXPECT_EQ(std::string(e.what()).rfind("rig.toml:", 0), 0u) << e.what();
      EXPECT_NE(std::string(e.what()).find("column"), std::string::npos) << e.what();
    }
  }
}
