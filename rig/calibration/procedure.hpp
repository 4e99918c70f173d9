#pragma once
// The calibration procedure: what the technician does, in which order, and how the samples recorded
// meanwhile become a calibration.
//
// plan_steps() lists the steps a rig needs — pivot each instrument in the fixture's divot, touch
// the fiducials with instrument 0, hold its tip in each port, leave the pedals and the eye at rest,
// press each pedal axis fully down — each with the instruction the technician reads. Who does them
// gives each step its window of time: a technician's script (rig/session/technician_script.hpp,
// which also writes the simulated devices' motion), or the technician at the devices confirming each
// step (vitreo-calibrate's guided mode), or a recorded calibration session
// (calibration_recording.hpp). analyse() then cuts the recorded samples by those windows and runs
// the math of this folder on them, step by step, with a line of feedback per step.
#include <map>
#include <string>
#include <vector>

#include "core/common/types.hpp"
#include "rig/calibration/calibration_file.hpp"
#include "rig/calibration/clock_sync.hpp"
#include "rig/calibration/pedal_range.hpp"
#include "rig/calibration/pivot.hpp"
#include "rig/calibration/ports.hpp"
#include "rig/calibration/registration.hpp"

namespace vitreo::rig::calibration {

// The mock eye's calibration features in the eye frame (origin the globe centre, +z anterior).
struct Fixture {
  core::Vec3 divot_mm = core::Vec3(22.0, 0.0, -4.0);  // the pivot divot on the fixture's base
  std::vector<core::Vec3> fiducials_mm;               // machined touch points on the eye's shell and base
  std::vector<core::Vec3> ports_mm;                   // where the technician finds each port's trocar
  core::Vec3 tre_target_mm = core::Vec3(0.0, 0.0, -12.0);  // where TRE is predicted: the posterior pole
  core::Vec3 rest_mm = core::Vec3(30.0, 0.0, 25.0);         // where an instrument is parked, well clear of the eye
};
// Eight fiducials (six on a ring about the cornea, the apex, one at the equator) and the two working
// ports 3.5 mm behind the limbus at 10 and 2 o'clock of a 12 mm globe.
Fixture default_fixture();

enum class StepKind { pivot, fiducial, port, pedal_rest, pedal_travel, eye_zero, clock };

struct ProcedureStep {
  StepKind kind = StepKind::pivot;
  std::string device;      // the rig file's device name that does it
  int index = 0;           // instrument (pivot), fiducial, port, pedal axis (travel)
  double start_s = 0.0, end_s = 0.0;  // when its samples count (the hold, without the moves)
  std::string instruction;  // what the technician is asked to do
};
// The same step (kind, device, index), whatever its window.
bool same_step(const ProcedureStep& a, const ProcedureStep& b);
// "pivot tracker-0 0", "fiducial tracker-0 3", … : how a recording names a step.
std::string step_kind_name(StepKind k);
bool step_kind_from_name(const std::string& name, StepKind& k);

struct TrackerRole {
  std::string device;  // "tracker-0"
  int instrument = 0;
};

// The steps with their windows, as someone did them.
struct Procedure {
  std::vector<ProcedureStep> steps;
  double duration_s = 0.0;
  // Emulator keyframe lines ("key T ...") per device: a scripted technician's motion (empty otherwise).
  std::map<std::string, std::string> motion;
};

// The steps a rig's devices need, in the order a technician does them (windows 0): trackers: every
// tracker pivots; the first one (instrument 0 where present) also touches the fiducials and measures
// the ports. pedals, eyeball: the devices' names, empty for none. The devices' clocks are measured
// throughout (a clock step per device, its window the whole run).
std::vector<ProcedureStep> plan_steps(const Fixture& fixture, const std::vector<TrackerRole>& trackers, const std::string& pedals,
                                      const std::string& eyeball = {});
// The planned steps `done` lacks, as "DEVICE: instruction" lines (empty: nothing is missing).
std::vector<std::string> missing_steps(const std::vector<ProcedureStep>& planned, const std::vector<ProcedureStep>& done);

// What a run recorded, by device name, with session times in seconds.
struct TimedPose {
  double t_s = 0.0;
  core::Vec3 position_mm = core::Vec3::Zero();
  core::Quat orientation = core::Quat::Identity();
};
struct TimedPedal {
  double t_s = 0.0;
  int pedal_id = 0;
  double axes[2] = {0.0, 0.0};
};
struct TimedOrientation {
  double t_s = 0.0;
  core::Quat orientation = core::Quat::Identity();
};
struct Recording {
  std::map<std::string, std::vector<TimedPose>> poses;
  std::map<std::string, std::vector<TimedOrientation>> eyeball;
  std::map<std::string, std::vector<TimedPedal>> pedals;
  std::map<std::string, std::vector<TimeSyncExchange>> clocks;
  std::map<std::string, std::uint32_t> serials;
};

struct StepOutcome {
  const ProcedureStep* step = nullptr;
  bool ok = false;
  std::string feedback;  // "412 samples, spread 38.0°, RMS 0.041 mm"
};

struct EyeZeroLimits {
  std::size_t min_samples = 20;
  double max_spread_deg = 0.5;  // the eye was left alone: its readings stay within this of their mean
};

struct Limits {
  EyeZeroLimits eye_zero;
  PivotLimits pivot;
  RegistrationLimits registration;
  PortLimits port;
  PedalRangeLimits pedal;
  ClockLimits clock;
};

// What the calibration report plots of one pivot calibration (rig/report/calibration_report.hpp):
// each pose's residual, and where its shaft pointed — degrees off the mean axis, in two
// perpendicular directions — which shows the spread the technician swung the handle through.
struct PivotPlot {
  std::string device;
  int instrument = 0;
  bool ok = false;
  std::vector<double> residuals_mm;
  std::vector<double> tilt_x_deg, tilt_y_deg;
  double rms_mm = 0.0, spread_deg = 0.0;
};

struct Analysis {
  bool ok = false;          // every step passed: the calibration may be written
  std::vector<StepOutcome> steps;
  std::vector<std::string> errors;  // the failures, each naming its step
  CalibrationFile file;     // filled as far as the steps passed (created/tool/rig: the caller's)
  std::vector<double> fiducial_residuals_mm;
  std::vector<PivotPlot> pivots;  // every pivot step, passed or not
  Limits limits;                  // the tolerances it was judged by
};

Analysis analyse(const Procedure& procedure, const Fixture& fixture, const Recording& recording, const Limits& limits = {});

// The summary a technician files: every result with its residual and tolerance.
std::string summary_text(const Analysis& a);

}  // namespace vitreo::rig::calibration
