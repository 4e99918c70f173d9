#pragma once
// Device samples in the one form the physics step consumes and the recorder stores.
//
// Live and replayed sessions must feed the simulation the same bits, so everything a device sends
// becomes a telemetry::DeviceInput (the recording's record) before physics sees it, and physics
// decodes only that. Layout of `values` per kind is fixed here and versioned with the recording.
#include <cstdint>

#include "drivers/session.hpp"
#include "rig/input/controls.hpp"
#include "rig/input/port_pivot.hpp"
#include "rig/telemetry/recording.hpp"

namespace vitreo::rig {

enum class InputKind : std::int8_t { Tracker = 1, Pedals = 2, Eyeball = 3 };

// Tracker: tip xyz (mm), q wxyz, actuation, quality, instrument id, tool type.
// Pedals:  pedal id, axis count, axes[4], switches.
// Eyeball: q wxyz, port count, inserted[3], depth[3] (mm).
telemetry::DeviceInput encode_sample(const drivers::Sample& sample, std::int32_t device_id, std::int64_t sequence);

struct DecodedTracker {
  int instrument_id = 0;
  int tool_type = 0;
  TrackedPose pose;
  double quality = 0.0;
};
struct DecodedEyeball {
  core::Quat orientation = core::Quat::Identity();
  int port_count = 0;
  bool inserted[3] = {};
  double depth_mm[3] = {};
};
// Each returns false for a record of another kind or with too few values (a tracker's also for an
// instrument id or tool type that is no byte).
bool decode_tracker(const telemetry::DeviceInput& in, DecodedTracker& out);
bool decode_pedals(const telemetry::DeviceInput& in, PedalReading& out);
bool decode_eyeball(const telemetry::DeviceInput& in, DecodedEyeball& out);

}  // namespace vitreo::rig
