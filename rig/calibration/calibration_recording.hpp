#pragma once
// A recorded calibration session: every sample a calibration run took from the devices, the time
// syncs, the units' serial numbers, and each procedure step with the window its samples were taken
// in — so the run can be analysed again later (vitreo-calibrate --from-recording), with other
// limits or a newer tool, without the technician or the devices.
//
// A line-oriented text file, written atomically, numbers printed so that they read back bit for bit
// (the analysis of a recording gives the very numbers of the run that wrote it):
//
//   vitreo-calibration-recording 1
//   rig simulated rig to calibrate
//   fixture default
//   duration 27.500000000000000
//   serial tracker-0 1001
//   step pivot tracker-0 0 8.65 14.35 rest the tip of instrument 0 in the divot and …
//   pose tracker-0 T X Y Z QW QX QY QZ        (s; tracker frame, mm)
//   eye eyeball T QW QX QY QZ
//   pedal pedals T PEDAL_ID AXIS0 AXIS1        (raw readings)
//   sync tracker-0 T1 T2 T3 T4                 (µs: host tx, device rx, device tx, host rx)
//   event tracker-0: link lost at 3.000 s      (a link lost or stuck during the run: the run failed)
//
// Reading is strict: an unknown line, a missing or malformed field, a step or device name the
// file does not declare, times that go backwards are "FILE:LINE: why"; a recording of another
// version is refused naming both versions.
#include <string>
#include <vector>

#include "rig/calibration/procedure.hpp"

namespace vitreo::rig::calibration {

inline constexpr int kCalibrationRecordingVersion = 1;

struct CalibrationSession {
  std::string rig;                  // the rig file's name
  Procedure procedure;              // its steps and duration (no motion)
  Recording recording;
  std::vector<std::string> events;  // link faults during the run
};

// Throws std::runtime_error with the reason when the file cannot be written (a file already there is then untouched).
void write_calibration_recording(const std::string& path, const CalibrationSession& session);
CalibrationSession read_calibration_recording(const std::string& path);
CalibrationSession parse_calibration_recording(const std::string& text, const std::string& origin);

}  // namespace vitreo::rig::calibration
