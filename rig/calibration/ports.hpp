#pragma once
// Sclerotomy port positions measured on the fixture: the technician holds the calibrated tip in each
// port's trocar for a moment; the tip positions (already in the eye frame, through the registration)
// average to the port, and their spread says whether the tip was held still. The port's outward
// normal is the globe's radial direction there (the eye frame's origin is the globe centre).
#include <string>
#include <vector>

#include "core/common/types.hpp"

namespace vitreo::rig::calibration {

struct PortLimits {
  std::size_t min_samples = 20;
  double max_spread_mm = 0.2;  // RMS distance of the samples from their mean
};

struct PortResult {
  bool ok = false;
  std::string error;
  core::Vec3 position_mm = core::Vec3::Zero();  // eye frame
  core::Vec3 outward = core::Vec3::UnitZ();
  double spread_mm = 0.0;
  std::size_t samples = 0;
};

// Where a held tip was and how still: the samples' mean and their RMS distance from it (at least
// one sample). A port, a touched fiducial and the guided procedure's "held still" all judge by it.
struct HeldPoint {
  core::Vec3 mean_mm = core::Vec3::Zero();
  double spread_mm = 0.0;
};
HeldPoint held_point(const std::vector<core::Vec3>& tips);

PortResult measure_port(const std::vector<core::Vec3>& tip_in_eye_mm, const PortLimits& limits = {});

}  // namespace vitreo::rig::calibration
