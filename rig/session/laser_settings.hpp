#pragma once
// The endolaser console's settings. Each shot (a rising edge of the laser switch) is one pulse of
// this power for this long, and the core sizes its burn by the pulse's energy (core/instruments,
// stage_act.cpp). The rig file's [laser] table sets them at the start, the laser_power and
// laser_duration operator commands during a session; both are held to the commands' ranges
// (telemetry::CommandLimits). A recording carries the start values (encode_case_list) and the
// commands as inputs, so a replay fires the same shots.
#include <cmath>

#include "rig/telemetry/commands.hpp"

namespace vitreo::rig {

struct LaserSettings {
  double power_mw = 200.0;     // the core's default shot: 200 mW for 100 ms, its 20 mJ reference
  double duration_ms = 100.0;  // a pulse per shot: the core has no continuous mode
};

inline bool laser_power_in_range(double mw, const telemetry::CommandLimits& l = {}) {
  return std::isfinite(mw) && mw >= l.laser_power_min_mw && mw <= l.laser_power_max_mw;
}
inline bool laser_duration_in_range(double ms, const telemetry::CommandLimits& l = {}) {
  return std::isfinite(ms) && ms >= l.laser_duration_min_ms && ms <= l.laser_duration_max_ms;
}

}  // namespace vitreo::rig
