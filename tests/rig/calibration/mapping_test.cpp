// The input mapping's calibrated parts (rig/input): a tip offset in TrackerCalibration, pedal axis
// ranges in PedalMapping, each against a hand computation.
#include <gtest/gtest.h>

#include "rig/input/controls.hpp"
#include "rig/input/port_pivot.hpp"

namespace vitreo::rig {
namespace {

TEST(CalibratedMapping, TipOffsetIsAddedInTheInstrumentFrameBeforeTheRegistration) {
  TrackerCalibration cal;
  cal.tip_offset_mm = core::Vec3(0.0, 0.0, 14.0);
  cal.rig_to_eye = core::Quat(Eigen::AngleAxisd(M_PI / 2, core::Vec3::UnitZ()));  // rig x → eye y
  cal.eye_center_in_rig_mm = core::Vec3(100.0, 0.0, 0.0);
  TrackedPose t;
  t.orientation = core::Quat(Eigen::AngleAxisd(M_PI / 2, core::Vec3::UnitY()));  // instrument z → rig x
  t.tip_mm = core::Vec3(80.0, 0.0, 3.0);  // the marker; the tip is 14 mm further along rig x: (94, 0, 3)
  InstrumentPose out;
  const Port outside{core::Vec3(0, 0, 50), core::Vec3::UnitZ()};  // far away: the pose stays outside
  ASSERT_TRUE(map_through_port(t, outside, core::Quat::Identity(), cal, out));
  // (94, 0, 3) − (100, 0, 0) = (−6, 0, 3) in the rig; turned 90° about z: (0, −6, 3) in the eye.
  EXPECT_NEAR((out.tip_mm - core::Vec3(0.0, -6.0, 3.0)).norm(), 0.0, 1e-9) << out.tip_mm.transpose();
}

TEST(CalibratedMapping, PedalAxisRangesNormaliseTheRawTravel) {
  PedalMapping m;
  m.axis_ranges.push_back({0, 0, 0.1, 0.9, 0.05});
  PedalMapper mapper(m);
  PedalReading r;
  r.pedal_id = 0, r.axis_count = 2, r.axes[1] = 0.0;
  r.axes[0] = 0.9;
  ASSERT_TRUE(mapper.apply(r));
  EXPECT_DOUBLE_EQ(mapper.controls().vacuum_mmhg, m.vacuum_max_mmhg);
  r.axes[0] = 0.13;  // (0.13 − 0.1)/0.8 = 0.0375: inside the dead zone
  ASSERT_TRUE(mapper.apply(r));
  EXPECT_EQ(mapper.controls().vacuum_mmhg, 0.0);
  r.axes[0] = 0.5;  // n = 0.5 → (0.5 − 0.05)/0.95
  ASSERT_TRUE(mapper.apply(r));
  EXPECT_NEAR(mapper.controls().vacuum_mmhg, (0.45 / 0.95) * m.vacuum_max_mmhg, 1e-9);
  r.pedal_id = 1;  // the microscope pedal is not calibrated: raw travel
  r.axes[0] = 0.5;
  ASSERT_TRUE(mapper.apply(r));
  EXPECT_NEAR(mapper.controls().zoom, m.zoom_min + 0.5 * (m.zoom_max - m.zoom_min), 1e-12);
}

}  // namespace
}  // namespace vitreo::rig
