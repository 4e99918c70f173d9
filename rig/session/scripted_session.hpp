#pragma once
// A session played by a surgical script (surgical_script.hpp) on simulated devices: what the main
// job does by default, and what the end-to-end tests do for every case.
#include <functional>
#include <vector>

#include "rig/session/rig_file.hpp"
#include "rig/session/surgical_script.hpp"

namespace vitreo::rig {

// The embedded rig: the tool tracker, the pedals and the eyeball fixture simulated behind ptys (a
// second tracker, for the light pipe, when the script has a second hand; the microscope pedal when
// the script works the microscope).
std::vector<DeviceSpec> simulated_devices(const SurgicalScript& script);

// SessionConfig::adapt_devices for a script: resolves it against the first case as loaded and gives
// each simulated device without a script of its own its part (tracker channel k plays
// "tracker-k", the pedals "pedals", the fixture "eyeball", the microscope pedal
// "microscope-pedal"). Throws like resolve_script.
std::function<void(const PreparedCase&, std::vector<DeviceSpec>&)> play_script(SurgicalScript script, PedalMapping pedals,
                                                                                core::MicroscopeSettings microscope = {});

}  // namespace vitreo::rig
