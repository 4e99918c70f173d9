#pragma once
// The one codec of recorded inputs: RecordedInput <-> device_input_t (VITREO_REC_INPUT), shared by
// the recorder, the reader and physics' own check of live inputs. Each kind's fields travel as
// device_input_t.values in the order RECORDING.md lists them; the reading direction range-checks
// every number it takes, so a record it returns is one physics can be handed.
#include <cstddef>
#include <cstdint>

#include "rig/telemetry/input_record.hpp"
#include "vitreo_lcm/device_input_t.hpp"

namespace vitreo::telemetry {

// Steps beyond this are not a session (2^40 steps of 1 ms: 35 years).
inline constexpr std::int64_t kMaxRecordedStep = std::int64_t{1} << 40;
// device_input_t.values of the largest kind (the eye fixture: 13).
inline constexpr std::size_t kMaxInputValues = 16;

// The payload's fields in wire order into `out`; returns how many. Allocates nothing (physics calls it).
std::size_t input_values(const InputPayload& p, double (&out)[kMaxInputValues]) noexcept;

vitreo_lcm::device_input_t to_lcm(const RecordedInput& in);
// nullptr and `out` filled, or why the message is not a recorded input of format 3 (a static string).
const char* from_lcm(const vitreo_lcm::device_input_t& m, RecordedInput& out) noexcept;

}  // namespace vitreo::telemetry
