#pragma once
// Tracked instrument → instrument in the eye, pivoting about its sclerotomy port.
//
// An instrument through a trocar can only extend, swing about the port and twist (thesis ch. 2.6.1,
// Figure 13). The tracker reports the instrument's tip and orientation in the rig frame; we move
// that into the eye frame (the mock eyeball may be rotated in its socket, which turns the eye
// under the instruments) and rebuild the shaft as the line from the port through the tip, so the
// simulated instrument obeys the port constraint even when the tracker is a little off.
#include "core/common/types.hpp"

namespace vitreo::rig {

// A sclerotomy port in the eye frame (origin at the globe centre, +z anterior).
struct Port {
  core::Vec3 position_mm = core::Vec3::Zero();
  core::Vec3 outward = core::Vec3::UnitZ();  // unit normal of the globe at the port, pointing out
};

// Where the eye sits in the rig when the fixture reads zero rotation: rig frame → eye frame.
// vitreo-calibrate measures both (rig/calibration/): the registration gives rig_to_eye and the eye's
// centre, the instrument's pivot calibration its tip offset.
struct TrackerCalibration {
  core::Quat rig_to_eye = core::Quat::Identity();
  core::Vec3 eye_center_in_rig_mm = core::Vec3::Zero();
  // From the point the tracker reports to the real tip, in the instrument's frame (the tracked
  // marker sits up the shaft): tip = reported + orientation · tip_offset_mm.
  core::Vec3 tip_offset_mm = core::Vec3::Zero();
};

struct InstrumentPose {
  bool inserted = false;              // tip inside the globe, beyond the port
  core::Vec3 tip_mm = core::Vec3::Zero();
  core::Vec3 axis = core::Vec3::UnitZ();  // unit, from the port toward the tip
  double insertion_mm = 0.0;          // port → tip distance along the shaft (0 when outside)
  double roll_rad = 0.0;              // twist about the shaft
  double actuation = 0.0;             // handle 0..1 (forceps closed at 1)
};

struct TrackedPose {
  core::Vec3 tip_mm = core::Vec3::Zero();  // rig frame
  core::Quat orientation = core::Quat::Identity();  // rig frame; the instrument's +z is its shaft, tip-ward
  double actuation = 0.0;
};

// Maps a tracked pose through `port`, with the eye rotated by `eye_rotation` (eye frame relative to
// its rest orientation in the rig). Returns false (and leaves `out` unchanged) for non-finite input
// or an orientation that is not a unit quaternion.
bool map_through_port(const TrackedPose& tracked, const Port& port, const core::Quat& eye_rotation,
                      const TrackerCalibration& calibration, InstrumentPose& out);

}  // namespace vitreo::rig
