#pragma once
// DeviceInput <-> device_input_t (VITREO_REC_INPUT), shared by the recorder and the reader. The
// reader's direction range-checks every number it takes (RECORDING.md lists the ranges).
#include "rig/telemetry/recording.hpp"
#include "vitreo_lcm/device_input_t.hpp"

namespace vitreo::telemetry {

// Steps beyond this are not a session (2^40 steps of 1 ms: 35 years).
inline constexpr std::int64_t kMaxRecordedStep = std::int64_t{1} << 40;

vitreo_lcm::device_input_t to_lcm(const DeviceInput& in);
// nullptr and `out` filled, or why the message is not a recorded input (a static string).
const char* from_lcm(const vitreo_lcm::device_input_t& m, DeviceInput& out) noexcept;

}  // namespace vitreo::telemetry
