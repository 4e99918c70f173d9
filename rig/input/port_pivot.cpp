#include "rig/input/port_pivot.hpp"

#include <algorithm>
#include <cmath>

#include "core/common/validate.hpp"

namespace vitreo::rig {

namespace {
bool unit_quaternion(const core::Quat& q) {
  const double n = q.coeffs().norm();
  return std::isfinite(n) && std::abs(n - 1.0) < 1e-3;
}
}  // namespace

bool map_through_port(const TrackedPose& tracked, const Port& port, const core::Quat& eye_rotation,
                      const TrackerCalibration& calibration, InstrumentPose& out) {
  if (!core::is_finite(tracked.tip_mm) || !std::isfinite(tracked.actuation) || !unit_quaternion(tracked.orientation) ||
      !unit_quaternion(eye_rotation)) {
    return false;
  }
  // Rig frame → eye frame at rest → eye frame as the fixture has turned it.
  const core::Quat to_eye = eye_rotation.conjugate() * calibration.rig_to_eye;
  // Only with an offset: adding a zero vector turns a -0.0 into +0.0, and uncalibrated sessions must
  // keep their bits (golden state hashes).
  const core::Vec3 tip_in_rig = calibration.tip_offset_mm == core::Vec3::Zero()
                                    ? tracked.tip_mm
                                    : core::Vec3(tracked.tip_mm + tracked.orientation * calibration.tip_offset_mm);
  const core::Vec3 tip = to_eye * (tip_in_rig - calibration.eye_center_in_rig_mm);
  const core::Quat orientation = to_eye * tracked.orientation;

  InstrumentPose pose;
  pose.actuation = std::clamp(tracked.actuation, 0.0, 1.0);
  const core::Vec3 from_port = tip - port.position_mm;
  const double depth = -from_port.dot(port.outward);  // > 0 once the tip is past the port, inward
  const double length = from_port.norm();
  if (depth > 0.0 && length > 1e-9) {
    pose.inserted = true;
    pose.axis = from_port / length;
    pose.insertion_mm = length;
    pose.tip_mm = tip;
  } else {
    // Outside the eye the shaft keeps the tracker's own direction; nothing touches tissue.
    pose.inserted = false;
    pose.axis = orientation * core::Vec3::UnitZ();
    pose.insertion_mm = 0.0;
    pose.tip_mm = tip;
  }
  // Twist: the angle of the instrument's x axis about the shaft, measured from the projection of
  // the eye's +z (anterior) onto the plane across the shaft, so roll is 0 with the handle "up".
  const core::Vec3 x = orientation * core::Vec3::UnitX();
  core::Vec3 ref = core::Vec3::UnitZ() - core::Vec3::UnitZ().dot(pose.axis) * pose.axis;
  if (ref.norm() < 1e-6) ref = core::Vec3::UnitX() - core::Vec3::UnitX().dot(pose.axis) * pose.axis;
  ref.normalize();
  const core::Vec3 x_perp = x - x.dot(pose.axis) * pose.axis;
  pose.roll_rad = x_perp.norm() > 1e-9 ? std::atan2(ref.cross(x_perp).dot(pose.axis), ref.dot(x_perp)) : 0.0;
  out = pose;
  return true;
}

}  // namespace vitreo::rig
