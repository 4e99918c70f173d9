#pragma once
// The rig's sensor calibration in force: a calibration file (rig/calibration/calibration_file.hpp,
// written by vitreo-calibrate) applied to the input mapping — the tracker-to-eye registration and
// each instrument's tip offset (TrackerCalibration), the ports measured on the fixture, the pedals'
// ranges and dead zones (PedalMapping::axis_ranges), the eyeball fixture's rest reading
// (ModelConfig::eye_zero), and the stereo eyepiece displays' alignment for the renderer. `vitreo --calibration FILE` or the rig file's [calibration] file.
#include <cstdint>
#include <string>
#include <vector>

#include "rig/calibration/calibration_file.hpp"
#include "rig/session/rig_file.hpp"
#include "vitreo/render/frame_scene.hpp"
#include "rig/session/simulation_model.hpp"

namespace vitreo::rig {

// Applies the calibration text to `model` (also how a replay restores it from the recording).
// Throws std::runtime_error "<origin>:<line>: <key>: <reason>" for a malformed file; `model` is then
// unchanged.
calibration::CalibrationFile apply_calibration(const std::string& text, const std::string& origin, ModelConfig& model);

struct CalibrationLoad {
  calibration::CalibrationFile file;
  std::vector<std::string> notes;     // what was applied, for the log
  std::vector<std::string> warnings;  // a stale calibration
};

// For the rig at start: reads `path`, refuses it (std::runtime_error, model and devices unchanged)
// when it was made for other devices — a device whose rig-file serial differs, or one the rig lacks —
// and pins each calibrated device's expected serial where the rig file leaves it open (0), so that
// another unit plugged in later is refused by its driver rather than driven with this calibration.
// Warns when the file is older than max_age_days at now_unix_s.
CalibrationLoad load_calibration(const std::string& path, std::vector<DeviceSpec>& devices, ModelConfig& model,
                                 double max_age_days, std::int64_t now_unix_s);

// The eyepiece displays' calibration as the renderer applies it (RenderThreadOptions::eyepieces).
render::EyepieceSettings eyepiece_settings(const calibration::EyepieceRecord& e);

// "2026-11-26T06:09:37Z vitreo-calibrate 0.1.0": which calibration is in force, for logs and telemetry.
std::string calibration_id(const calibration::CalibrationFile& c);

}  // namespace vitreo::rig
