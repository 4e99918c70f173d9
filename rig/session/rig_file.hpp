#pragma once
// A rig file (rig/config/*.toml): which devices this rig has, where each one is (a URI,
// drivers/device_uri.hpp), what it is (its role and, optionally, its serial number) and what it
// does (the instrument a tracker carries), plus the rig's pedal mapping and laser settings. `vitreo --rig FILE`.
//
//   [rig]
//   version = 1                      # this format's version; another one is refused
//   name = "bench 2: tracker on USB, pedals on a UART, eyeball on CAN"
//
//   [[device]]
//   name = "tracker"                 # the rig's name for it: logs, telemetry, /dev/vitreo/NAME
//   role = "tracker"                 # tracker | pedals | eyeball: the device type it must announce
//   uri = "usb:1209:7a11/1001"
//   id = 1                           # device id in telemetry and recordings (unique)
//   serial = 1001                    # optional: the serial number it must announce (0: any)
//   instrument = 0                   # trackers: the instrument it carries (0 the tool hand, 1 the light pipe)
//   rate_hz = 1000                   # optional: the sample rate the host configures (default: the
//                                    # protocol's rate for the device's type, PROTOCOL.md §7)
//   script = "sim/tracker.sim"       # sim: URIs only, optional: the emulator's script, relative to
//                                    # the rig file (default: the main job's scripted session)
//
//   [pedals]                         # optional: the pedal mapping (rig/input/controls.hpp)
//
//   [laser]                          # optional: the endolaser's settings at the start (rig/session/laser_settings.hpp)
//   power_mw = 200                   # 50..2000 mW (default 200); operator command laser_power MW
//   duration_ms = 100                # pulse per shot, 10..2000 ms (default 100); laser_duration MS
//
//   [calibration]                    # optional: the sensor calibration in force (vitreo-calibrate)
//   file = "bench2.calibration.toml" # relative to the rig file; `vitreo --calibration` overrides it
//   max_age_days = 30                # optional: warn when the calibration is older (default 30)
//
// Errors name the file, line and key ("rig/config/x.toml:12: device[1].uri: ..."), like the
// scene files' (rig/scene_io).
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "rig/input/controls.hpp"
#include "rig/session/laser_settings.hpp"

namespace vitreo::rig {

inline constexpr int kRigFileVersion = 1;

enum class DeviceRole : std::uint8_t { tracker, pedals, eyeball };
const char* to_string(DeviceRole r);

struct DeviceSpec {
  std::string name;  // "tracker", "pedals", "eyeball"
  DeviceRole role = DeviceRole::tracker;
  std::string uri;   // drivers/device_uri.hpp
  std::int32_t device_id = 0;
  int channel = 0;   // trackers: the instrument slot it carries
  std::uint32_t expected_serial = 0;  // 0: any
  std::uint16_t sample_rate_hz = 0;   // 0: the protocol's rate for the type the device announces
  // sim: URIs: the emulator's script text (drivers/sim/emulator.hpp); empty: decided by the caller
  // (the main job's scripted session), else the built-in script of the device's kind.
  std::string sim_script;
  // The calibration in force for this device (calibration_in_force.hpp's calibration_id), set when
  // a calibration file that covers it is loaded; empty: uncalibrated. Published in its status.
  std::string calibration = {};
};

struct RigFile {
  std::string name;
  std::vector<DeviceSpec> devices;
  std::optional<PedalMapping> pedals;
  std::optional<LaserSettings> laser;
  std::string calibration_path;              // empty: none (resolved against the rig file's folder)
  std::optional<double> calibration_max_age_days;
};

inline constexpr double kDefaultCalibrationMaxAgeDays = 30.0;

// Throws std::runtime_error "<origin>:<line>: <key>: <reason>". Scripts named in the file are read
// relative to base_dir.
RigFile parse_rig_file(const std::string& toml_text, const std::string& origin, const std::string& base_dir);
RigFile read_rig_file(const std::string& path);

}  // namespace vitreo::rig
