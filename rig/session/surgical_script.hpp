#pragma once
// Surgical scripts: a scripted surgeon, written by a person, in TOML (scenes/scripts/README.md
// documents the format). Two tracked hands move between waypoints named after the case's landmarks
// (its port, the fovea, the disc, a membrane's edge, a tear, a guide's points) at given speeds, close
// and open their jaws, select tools and work the pedals; device faults can be injected on top.
//
// A script is open loop, like a recorded hand: resolve_script() turns it, once, against the case as
// loaded (its anatomy and resolution) into the device emulators' keyframe scripts
// (drivers/sim/emulator.hpp), and nothing it does while playing reads the simulation. A landmark
// the case lacks, a tool it does not offer, or a waypoint no instrument through its port can reach
// is an error when the script is resolved, with the file, line and key.
//
// The script then plays through the whole stack: emulators → transports → drivers → rig → core →
// metrics, in lockstep (rig/session/device_hub.hpp) so its outcome never depends on load.
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/common/types.hpp"
#include "core/scene/microscope.hpp"
#include "rig/input/controls.hpp"
#include "rig/session/case_runtime.hpp"

namespace vitreo::rig {

inline constexpr int kSurgicalScriptVersion = 1;

// One waypoint of a hand: where the tip goes, how fast, what it does on the way and once there.
struct ScriptWaypoint {
  int line = 0;               // in the script file (diagnostics): the table's, its `to` and `tool` keys'
  int to_line = 0, tool_line = 0;
  std::string to;             // landmark (see resolve_script)
  double above_mm = 0.0;      // along the landmark's inward normal (toward the globe centre); at a port, depth inside
  double toward_port_mm = 0.0;  // along the fundus toward the hand's port (a peel's direction)
  double across_mm = 0.0;       // along the fundus at right angles to that (to the right, seen from inside)
  core::Vec3 offset_mm = core::Vec3::Zero();  // in the eye frame, on top
  // Then this far back toward the hand's port along the line from the port through that point: the
  // shaft points at it (an endolaser fires along its shaft, so its beam lands there).
  double standoff_mm = 0.0;
  std::optional<double> at_s;      // do not leave before this session time
  std::optional<double> speed_mm_s;  // default: the hand's speed
  std::optional<double> duration_s;  // instead of a speed
  double hold_s = 0.0;             // stay once there
  std::optional<double> jaws;      // 0 open .. 1 closed, reached on arrival
  std::optional<double> roll_deg;  // twist about the shaft (0: handle up, as port_pivot measures it), reached on arrival
  std::optional<std::string> tool;  // working hand: select this tool (instrument-switch presses) before leaving
  // Pedals from this waypoint's start on (unset: unchanged).
  std::optional<double> vacuum;    // 0..1 of the vitrectomy pedal's travel
  std::optional<double> cut_rate;  // 0..1 of the side travel
  std::optional<bool> laser, reflux, air;
  std::optional<bool> pick;  // the light pipe's pick out (its own pedal switch)
  // The microscope pedal from this waypoint's start on: zoom (within the pedal mapping's zoom_min ..
  // zoom_max), focus (mm about the fundus), and `look_at`, a landmark the field's centre is driven to
  // with the joystick — deflected toward it for as long as the microscope's pan speed at the zoom in
  // force needs, then let go; "target" is where this waypoint's tip goes.
  std::optional<double> zoom, focus_mm;
  std::optional<double> light;  // the light source's level 0..1, by the pedal's light switches (its steps)
  std::optional<std::string> look_at;
  int look_at_line = 0;
  // Calibration scripts only (kind = "calibration": a technician's hand, free of any port;
  // rig/calibration/README.md): the shaft's tilt from the fixture's vertical on arrival, a swing of
  // the handle about the resting tip during the hold (tilt growing from the first to the second
  // angle, one circle every swing_period_s), which procedure step the hold's samples make
  // (`records`), and how far a pedal is pressed during a pedal_travel hold.
  std::optional<double> tilt_deg;
  std::optional<std::pair<double, double>> swing_deg;
  double swing_period_s = 1.5;
  std::optional<std::string> records;
  int records_line = 0;
  double travel = 1.0;
};

struct ScriptHand {
  int line = 0;
  int tracker = 0;  // 0: the working hand (tools, the case's working port); 1: the other (light pipe, the other port)
  double speed_mm_s = 5.0;
  std::vector<ScriptWaypoint> waypoints;
};

struct ScriptFault {
  int line = 0;
  std::string device;  // "tracker-0", "tracker-1", "pedals", "eyeball"
  double at_s = 0.0, duration_s = 0.0;
  std::string kind;    // drvers/sim's fault kinds: nan, range, stuck, jump, version, unknown, drop, disconnect
  double value = 0.0;  // jump: milliseconds
};

// The surgeon turning the eye with the instruments in its ports, as the eyeball fixture reads it: from
// at_s on, over duration_s, to yaw_deg (about the eye's z axis, anterior) and pitch_deg (about its
// y axis) from the rest reading 0, 0 — the fixture's own angles (drivers/sim/emulator.hpp).
struct ScriptEyeTurn {
  int line = 0;
  double at_s = 0.0, duration_s = 0.5;
  double yaw_deg = 0.0, pitch_deg = 0.0;
};

struct SurgicalScript {
  std::string file;        // where it was read from
  std::string case_name;   // the case it is written for
  std::string kind;        // expert, clumsy, idle, test; calibration (a technician's, no case)
  std::string summary;     // what it does (and, for a clumsy one, what it does wrong)
  double duration_s = 10.0;
  std::uint64_t seed = 1;  // sensor noise and tremor
  // Degradations, for sweeps from an expert script: hand tremor (1 σ, mm, 20 Hz), speed factor,
  // extra pressing depth past every waypoint that touches tissue (mm).
  double tremor_mm = 0.0;
  double speed_scale = 1.0;
  double press_mm = 0.0;
  std::vector<ScriptHand> hands;
  std::vector<ScriptFault> faults;
  std::vector<ScriptEyeTurn> eye;  // in time order; none: the eye stays at rest
};

// Parses a script; throws std::runtime_error "FILE:LINE: KEY: why" on malformed input.
SurgicalScript parse_surgical_script(const std::string& text, const std::string& origin);
SurgicalScript read_surgical_script(const std::string& path);

// The script as the simulated devices play it: one emulator script per device name ("tracker-0",
// "tracker-1" when the second hand is scripted, "pedals", "eyeball", and "microscope-pedal" when the
// script works the microscope).
struct ResolvedScript {
  std::map<std::string, std::string> device_scripts;
  double duration_s = 0.0;
  double path_mm[2] = {0.0, 0.0};  // planned tip path per hand (tremor excluded)
};

// Resolves the landmarks against the case as loaded; throws std::runtime_error "FILE:LINE: KEY: why"
// for a landmark, a tool or a light pipe the case lacks, and for an unreachable waypoint.
// Landmarks: port (the hand's own), fovea, disc, roi (the case's region of interest),
// membrane.NAME[.centre|.edge|.mid|.far_edge|.disc_edge|.site.N] (site.N: the wall under the retina
// end of the attachment at lattice site N), tear.NAME[.flap|.hinge],
// detachment.NAME, guide.NAME[.start|.end|.N] (N: the guide's N-th point).
// `microscope`: the settings the session's microscope runs with (its pan speed times look_at's joystick).
ResolvedScript resolve_script(const SurgicalScript& script, const PreparedCase& c, const PedalMapping& pedals,
                              const core::MicroscopeSettings& microscope = {});

// For script writers (`vitreo-cases sites`): a membrane's attachment sites in the case as loaded,
// one line each — its attachment, whether it holds, weak or strong, and where its strand crosses
// height_mm above the globe wall, as toward_port_mm / across_mm for the working hand's port from the
// site's own landmark (membrane.NAME.site.N) and from the membrane's centre, with the height of the
// strand's foot and its position (eye frame). Throws std::runtime_error for a membrane the case lacks.
std::string describe_membrane_sites(const PreparedCase& c, const std::string& membrane, double height_mm);

// The simulated microscope pedal's device name, and whether a script works the microscope (then
// the scripted rig has that pedal too).
inline constexpr const char* kMicroscopePedalDevice = "microscope-pedal";
bool works_microscope(const SurgicalScript& script);

}  // namespace vitreo::rig
