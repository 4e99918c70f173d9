// What the recorder and the reader share: the input codec with its range checks, bitwise input
// equality, verdict texts, and paced replay of a read recording.
#include "rig/telemetry/recording.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "rig/telemetry/input_codec.hpp"

namespace vitreo::telemetry {

vitreo_lcm::device_input_t to_lcm(const DeviceInput& in) {
  vitreo_lcm::device_input_t m;
  m.host_time_us = in.host_time_us;
  m.device_time_us = in.device_time_us;
  m.step = in.step;
  m.device_id = in.device_id;
  m.device_kind = in.device_kind;
  m.channel = in.channel;
  m.sequence = in.sequence;
  const std::size_t nv = std::min<std::size_t>(in.n_values, DeviceInput::kMaxValues);
  const std::size_t nr = std::min<std::size_t>(in.n_raw, DeviceInput::kMaxRaw);
  m.n_values = static_cast<std::int16_t>(nv);
  m.values.assign(in.values, in.values + nv);
  m.n_raw = static_cast<std::int16_t>(nr);
  m.raw.assign(in.raw, in.raw + nr);
  return m;
}

const char* from_lcm(const vitreo_lcm::device_input_t& m, DeviceInput& in) noexcept {
  if (m.n_values < 0 || static_cast<std::size_t>(m.n_values) > DeviceInput::kMaxValues) return "more than 16 values";
  if (m.n_raw < 0 || static_cast<std::size_t>(m.n_raw) > DeviceInput::kMaxRaw) return "more than 64 raw bytes";
  if (m.values.size() != static_cast<std::size_t>(m.n_values) || m.raw.size() != static_cast<std::size_t>(m.n_raw))
    return "counts and arrays disagree";
  if (m.step < 0 || m.step > kMaxRecordedStep) return "step out of range";
  if (m.device_kind <= 0) return "device kind out of range";
  in = DeviceInput{};
  in.host_time_us = m.host_time_us;
  in.device_time_us = m.device_time_us;
  in.step = m.step;
  in.device_id = m.device_id;
  in.device_kind = m.device_kind;
  in.channel = m.channel;
  in.sequence = m.sequence;
  in.n_values = static_cast<std::uint8_t>(m.n_values);
  std::copy(m.values.begin(), m.values.end(), in.values);
  in.n_raw = static_cast<std::uint8_t>(m.n_raw);
  std::copy(m.raw.begin(), m.raw.end(), in.raw);
  return nullptr;
}

bool operator==(const DeviceInput& a, const DeviceInput& b) noexcept {
  if (a.host_time_us != b.host_time_us || a.device_time_us != b.device_time_us || a.step != b.step ||
      a.device_id != b.device_id || a.device_kind != b.device_kind || a.channel != b.channel ||
      a.sequence != b.sequence || a.n_values != b.n_values || a.n_raw != b.n_raw)
    return false;
  // Bit patterns, not values: replay must be bit-identical (NaN == NaN, -0 != +0 here).
  return std::memcmp(a.values, b.values, sizeof(double) * std::min<std::size_t>(a.n_values, DeviceInput::kMaxValues)) == 0 &&
         std::memcmp(a.raw, b.raw, std::min<std::size_t>(a.n_raw, DeviceInput::kMaxRaw)) == 0;
}

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
                   const std::function<void(const DeviceInput&)>& fn) {
  if (rec.inputs.empty()) return 0;
  const std::int64_t t0_ns = clock.now_ns();
  const std::int64_t first_us = rec.inputs.front().host_time_us;
  std::size_t n = 0;
  for (const DeviceInput& in : rec.inputs) {
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
