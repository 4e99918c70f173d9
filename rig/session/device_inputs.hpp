#pragma once
// Device samples in the one form the physics step consumes and the recorder stores.
//
// Live and replayed sessions must feed the simulation the same bits, so everything a device sends
// becomes a telemetry::RecordedInput (the recording's typed record, input_record.hpp) before physics
// sees it, and physics reads only that. These are the two crossings: a driver's sample into a
// record, and a record's fields into the rig's input types.
#include <cstdint>

#include "drivers/session.hpp"
#include "rig/input/controls.hpp"
#include "rig/input/port_pivot.hpp"
#include "rig/telemetry/input_record.hpp"

namespace vitreo::rig {

telemetry::RecordedInput encode_sample(const drivers::Sample& sample, std::int32_t device_id, std::int64_t sequence);

// A tracker sample as the pose the port pivot maps (tip, orientation, actuation).
TrackedPose tracked_pose(const telemetry::TrackerSample& s);
PedalReading pedal_reading(const telemetry::PedalSample& s);
core::Quat fixture_orientation(const telemetry::EyeFixtureSample& s);

}  // namespace vitreo::rig
