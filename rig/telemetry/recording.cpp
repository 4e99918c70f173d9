// What the recorder and the reader share besides the input codec: verdict texts, and paced replay of
// a read recording.
#include "rig/telemetry/recording.hpp"

#include <cmath>
#include <cstdio>

namespace vitreo::telemetry {

const char* to_string(RecordingVerdict v) noexcept {
  switch (v) {
    case RecordingVerdict::Complete: return "complete";
    case RecordingVerdict::Truncated: return "truncated";
    case RecordingVerdict::Corrupted: return "corrupted";
  }
  return "?";
}

std::string Recording::describe() const {
  char buf[512];
  switch (verdict) {
    case RecordingVerdict::Complete:
      std::snprintf(buf, sizeof buf, "complete (%lld steps, %zu inputs, every checksum verified)",
                    static_cast<long long>(end ? end->steps : 0), inputs.size());
      break;
    case RecordingVerdict::Truncated:
      if (trusted_through_step < 0) {
        std::snprintf(buf, sizeof buf, "truncated before its first verified step — nothing to replay (%s)", problem.c_str());
      } else {
        std::snprintf(buf, sizeof buf, "truncated at step %lld — replayed up to there (%s)",
                      static_cast<long long>(trusted_through_step), problem.c_str());
      }
      break;
    case RecordingVerdict::Corrupted:
      std::snprintf(buf, sizeof buf, "corrupted at byte %llu — replayed up to there, through step %lld (%s)",
                    static_cast<unsigned long long>(bad_byte), static_cast<long long>(trusted_through_step),
                    problem.c_str());
      break;
  }
  return buf;
}

std::size_t replay(const Recording& rec, runtime::Clock& clock, ReplayOptions options,
                   const std::function<void(const RecordedInput&)>& fn) {
  if (rec.inputs.empty()) return 0;
  const std::int64_t t0_ns = clock.now_ns();
  const std::int64_t first_us = rec.inputs.front().host_time_us;
  std::size_t n = 0;
  for (const RecordedInput& in : rec.inputs) {
    if (options.speed > 0) {
      const double offset_ns = static_cast<double>(in.host_time_us - first_us) * 1000.0 / options.speed;
      clock.sleep_until_ns(t0_ns + static_cast<std::int64_t>(std::llround(offset_ns)));
    }
    fn(in);
    ++n;
  }
  return n;
}

}  // namespace vitreo::telemetry
