#pragma once
// The calibration file: what vitreo-calibrate measured, for which devices, when and how well — a
// versioned, human-readable TOML file the rig loads (`vitreo --calibration FILE`, or the rig
// file's [calibration] file). Written atomically (rig/files/write_file_atomically.hpp); read with
// "<file>:<line>: <key>: <reason>" errors; refused for other devices' serial numbers; stale after a
// configurable age. README.md in this folder shows a file.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/common/types.hpp"
#include "rig/calibration/pedal_range.hpp"

namespace vitreo::rig::calibration {

inline constexpr int kCalibrationFileVersion = 1;

struct DeviceSerial {
  std::string name;          // the rig file's device name ("tracker")
  std::uint32_t serial = 0;  // the serial number it announced while being calibrated
};

struct RegistrationRecord {  // tracker → eye fixture
  core::Quat rig_to_eye = core::Quat::Identity();
  core::Vec3 eye_center_in_rig_mm = core::Vec3::Zero();
  std::size_t fiducials = 0;
  double fre_mm = 0.0;
  double tre_mm = 0.0;
  bool tre_measured = false;  // at touched targets; else predicted (Fitzpatrick et al. 1998)
};

struct InstrumentRecord {  // tip pivot, per tracker channel
  int instrument = 0;
  core::Vec3 tip_offset_mm = core::Vec3::Zero();  // instrument frame: tracked point → real tip
  std::size_t poses = 0;
  double spread_deg = 0.0;
  double rms_mm = 0.0;
};

struct PortRecord {
  int port = 0;  // 0 the tool hand's, 1 the light pipe's
  core::Vec3 position_mm = core::Vec3::Zero();  // eye frame
  core::Vec3 outward = core::Vec3::UnitZ();
  std::size_t samples = 0;
  double spread_mm = 0.0;
};

struct PedalRecord {
  int pedal = 0;  // pedal id
  int axis = 0;
  PedalRange range;
};

struct EyeZeroRecord {  // the eyeball fixture's reading with the eye at rest
  core::Quat zero = core::Quat::Identity();
  std::size_t samples = 0;
  double spread_deg = 0.0;
};

// The stereo eyepiece displays, adjusted while looking at the test pattern (vitreo-calibrate
// --eyepieces): each eye's image shift on its display, and the stereo geometry the renderer uses.
struct EyepieceRecord {
  double offset_px[2][2] = {{0.0, 0.0}, {0.0, 0.0}};  // [eye: left, right][x right, y up], display pixels
  double stereo_base_mm = 22.0;                        // the two views' separation at the objective
  double convergence_mm = 0.0;                         // zero-disparity distance; 0: at the working plane
};

struct ClockRecord {
  std::string device;
  double offset_ms = 0.0, drift_ppm = 0.0, latency_ms = 0.0, rms_ms = 0.0;
};

struct CalibrationFile {
  std::int64_t created_unix_s = 0;  // UTC
  std::string tool;                 // "vitreo-calibrate 0.1.0"
  std::string rig;                  // the rig file's name
  std::vector<DeviceSerial> devices;
  std::optional<RegistrationRecord> registration;
  std::vector<InstrumentRecord> instruments;
  std::vector<PortRecord> ports;
  std::vector<PedalRecord> pedals;
  std::optional<EyeZeroRecord> eye_zero;
  std::vector<ClockRecord> clocks;
  std::optional<EyepieceRecord> eyepieces;

  const InstrumentRecord* instrument(int channel) const;
  const PortRecord* port(int index) const;
  const PedalRecord* pedal(int pedal_id, int axis) const;
};

std::string format_calibration(const CalibrationFile& c);
// Throws std::runtime_error "<origin>:<line>: <key>: <reason>".
CalibrationFile parse_calibration(const std::string& toml_text, const std::string& origin);
CalibrationFile read_calibration_file(const std::string& path);
// Atomic; throws std::runtime_error when it cannot (the previous file is then untouched).
void write_calibration_file(const std::string& path, const CalibrationFile& c);

// Empty when every device the file was made for is present in `rig` with the same serial number;
// else a message naming each mismatch. A rig device absent from the file is not an error (it was
// not calibrated); a calibrated device the rig lacks is.
std::string check_devices(const CalibrationFile& c, const std::vector<DeviceSerial>& rig);
// A warning when the file is older than max_age_days at now_unix_s (or dated in the future).
std::optional<std::string> age_warning(const CalibrationFile& c, std::int64_t now_unix_s, double max_age_days);

// "2026-11-26T05:55:00Z" ↔ seconds since 1970 (UTC, proleptic Gregorian).
std::string utc_timestamp(std::int64_t unix_s);

}  // namespace vitreo::rig::calibration
