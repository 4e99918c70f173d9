#pragma once
// Taking a calibration's samples from the rig's devices over their transports (vitreo-calibrate).
//
// run_scripted_calibration(): a scripted technician (technician_script.hpp) against simulated
// devices: each device's own emulator script keeps its imperfections, noise and faults, with its
// motion replaced by the technician's; the run goes in lockstep on the simulation's clock, 1 ms a
// step, so it is reproducible and as fast as the machine. It prints each step as the technician
// starts it, and every link fault.
#include <cstdio>
#include <mutex>
#include <string>
#include <vector>

#include "rig/calibration/calibration_recording.hpp"
#include "rig/session/rig_file.hpp"
#include "rig/telemetry/input_record.hpp"

namespace vitreo::rig {

// The rig's devices in the roles the procedure gives them: trackers in instrument order.
struct CalibrationRoles {
  std::vector<calibration::TrackerRole> trackers;
  std::string pedals, eyeball;
};
CalibrationRoles calibration_roles(const RigFile& rig);

// One input from the hub into the calibration's recording at session time t_s (samples by device
// name; a link lost or stuck is a fault of the run, printed and kept in session.events).
void record_calibration_input(calibration::CalibrationSession& session, const std::string& device, double t_s,
                              const telemetry::RecordedInput& in, std::FILE* progress);

class DeviceHub;
// Before hub.start(): every device's completed time-sync exchanges go into rec.clocks (on the
// hub's driver thread, under `m`: read them after hub.stop() or under the same lock).
void collect_time_syncs(DeviceHub& hub, calibration::Recording& rec, std::mutex& m);

// The device's own emulator script with its motion ("key" and "loop" lines) replaced by `motion`.
std::string with_technician_motion(const DeviceSpec& d, const std::string& motion);

// Throws std::runtime_error when a device cannot be opened or a device is not simulated.
calibration::CalibrationSession run_scripted_calibration(const RigFile& rig, const calibration::Procedure& procedure, std::FILE* progress);

}  // namespace vitreo::rig
