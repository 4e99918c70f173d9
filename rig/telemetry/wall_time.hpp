#pragma once
// The host's wall clock as LCM's messages carry it (utime_us).
#include <cstdint>

namespace vitreo::telemetry {

// Wall clock (CLOCK_REALTIME) in µs since the epoch: LCM's utime convention.
std::int64_t wall_time_us() noexcept;

}  // namespace vitreo::telemetry
