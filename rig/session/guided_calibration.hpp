#pragma once
// The guided calibration: a technician at the rig's devices, real or simulated, in real time, told
// each step in the terminal and shown what the devices report while doing it ("pivot the instrument
// about its tip… 412 samples, spread 38°, RMS 0.04 mm"), one step after another.
//
// Each step starts when the technician presses Enter and ends by itself once its samples are good
// enough — the pivot when the fit is sound over ≥ 3 s of poses spread ≥ 40°, a touch once the tip has
// been held still (RMS ≤ 0.10 mm over 0.4 s, at least 2 mm from the last point taken), the pedals and
// the eye after 1.2 s at rest, a pedal press once the pedal went down ≥ 0.3 and came back — or when
// the technician presses Enter again. Each step's outcome is shown at once; a failed one can be
// repeated (Enter), skipped (s), or the procedure given up (q: nothing is written). The technician's
// answers are lines on `input` (a terminal or a pipe).
#include <cstdio>
#include <vector>

#include "rig/calibration/calibration_recording.hpp"
#include "rig/session/rig_file.hpp"

namespace vitreo::rig {

struct GuidedOutcome {
  bool completed = false;  // false: the technician gave up (q, or the input ended)
  calibration::CalibrationSession session;
};

// Throws std::runtime_error when a device cannot be opened.
GuidedOutcome run_guided_calibration(const RigFile& rig, const std::vector<calibration::ProcedureStep>& planned, int input_fd,
                                     std::FILE* out);

}  // namespace vitreo::rig
