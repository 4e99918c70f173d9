#pragma once
// Instrument tip pivot calibration: the technician rests the instrument's tip in a divot and swings
// the handle about it. Every tracked pose (R_i, p_i) then maps the same unknown tip offset t
// (instrument frame) to the same unknown pivot point b (tracker frame): R_i t + p_i = b. Stacking
// [R_i  -I] [t; b] = -p_i over all poses gives a linear least-squares problem in six unknowns —
// the standard "algebraic" pivot calibration (e.g. Yaniv, "Which pivot calibration?", SPIE Medical
// Imaging 2015, which compares it with the sphere-fitting formulations and finds it as accurate).
#include <string>
#include <vector>

#include "core/common/types.hpp"

namespace vitreo::rig::calibration {

struct PivotPose {
  core::Vec3 position_mm = core::Vec3::Zero();  // where the tracker says the instrument is (tracker frame)
  core::Quat orientation = core::Quat::Identity();
};

struct PivotLimits {
  std::size_t min_poses = 30;
  double min_spread_deg = 15.0;   // widest angle between two poses' shaft axes
  double max_rms_mm = 0.15;       // pass/fail: 0.05 mm of tracker noise per axis alone gives 0.087
};

struct PivotResult {
  bool ok = false;
  std::string error;                          // why not, in a technician's words; empty when ok
  core::Vec3 tip_offset_mm = core::Vec3::Zero();  // tracked point → real tip, instrument frame
  core::Vec3 pivot_mm = core::Vec3::Zero();       // the divot, tracker frame
  double rms_mm = 0.0;                        // RMS of |R_i t + p_i - b|
  double max_residual_mm = 0.0;
  double spread_deg = 0.0;
  std::size_t poses = 0;
  std::vector<double> residuals_mm;           // per pose, for the report's plot
};

// The widest angle (degrees) between the shaft axes (+z) of any two poses.
double pivot_spread_deg(const std::vector<PivotPose>& poses);

// Fails (ok = false, error set) on too few poses, too little spread, rotations about one axis only
// (the offset along it is then unobservable) or an RMS above the limit — the result's numbers are
// still filled in where they could be computed, so the technician sees how far off it was.
PivotResult calibrate_pivot(const std::vector<PivotPose>& poses, const PivotLimits& limits = {});

}  // namespace vitreo::rig::calibration
