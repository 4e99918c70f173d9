#pragma once
// A technician's calibration script: the surgical-script format (surgical_script.hpp, kind =
// "calibration") with the calibration fixture's landmarks instead of a case's, resolved into the
// calibration procedure's steps with their windows and the simulated devices' motion.
//
// Landmarks: `rest` (where an instrument is parked), `divot`, `fiducial.N` (1 … the fixture's
// count, as machined and as the technician is told), `port.N` (0 the tool hand's, 1 the light
// pipe's). A hand starts at rest; each waypoint moves its tip in a straight line to the landmark
// (plus `offset_mm`), tilting the shaft to `tilt_deg` from the fixture's vertical, then holds. A
// waypoint's `records` names the procedure step its hold makes (its first and last 0.15 s cut off,
// the settling): "pivot" (at the divot; `swing_deg = [from, to]` swings the handle about the resting
// tip in widening circles meanwhile), "fiducial" and "port" (the landmark's index), "eye_zero",
// "pedal_rest", "pedal_travel.AXIS" (the pedal pressed to `travel` and let back during the hold; the
// whole hold counts). Open loop and seeded, like a surgeon's script, so a calibration run against
// simulated devices is reproducible.
#include <string>
#include <vector>

#include "rig/calibration/procedure.hpp"
#include "rig/session/surgical_script.hpp"

namespace vitreo::rig {

// Which of the rig's devices the script's hands and feet move.
struct TechnicianDevices {
  std::vector<calibration::TrackerRole> trackers;  // hand.tracker is the instrument number
  std::string pedals, eyeball;                     // empty: none
};

// The script's steps (instructions from `planned`, calibration::plan_steps) with their windows, in
// the order they happen, the devices' clocks measured throughout, and each device's emulator
// keyframes. Throws std::runtime_error "FILE:LINE: KEY: why" for a landmark the fixture lacks, a
// step recorded at the wrong landmark or twice, a hand or pedal the rig lacks, overlapping presses.
calibration::Procedure resolve_technician_script(const SurgicalScript& script, const calibration::Fixture& fixture,
                                                 const TechnicianDevices& devices, const std::vector<calibration::ProcedureStep>& planned);

}  // namespace vitreo::rig
