#pragma once
// What producers (physics, driver threads) push towards the telemetry thread: fixed-size, trivially
// copyable records, so a push is a memcpy into a preallocated ring slot — no allocation, no
// encoding, no system call on the producer's thread. The telemetry thread turns them into LCM
// messages (strings, variable arrays) and publishes.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <type_traits>
#include <variant>

namespace vitreo::telemetry {

template <std::size_t N>
void copy_text(char (&dst)[N], std::string_view src) noexcept {
  const std::size_t n = std::min(N - 1, src.size());
  std::copy_n(src.data(), n, dst);
  dst[n] = '\0';
}

// The text of a fixed field, stopping at its first NUL or its end (never reads past it).
template <std::size_t N>
std::string_view text(const char (&src)[N]) noexcept {
  std::size_t n = 0;
  while (n < N && src[n] != '\0') ++n;
  return {src, n};
}

struct InstrumentState {
  std::int64_t step = 0;
  double t_s = 0;
  std::int8_t instrument_id = 0;
  std::int8_t port_id = -1;
  char kind[16] = {};
  double tip_mm[3] = {};
  double shaft_axis[3] = {};
  double roll_rad = 0;
  double insertion_mm = 0;
  double actuation = 0;
  bool frozen = false;
  double retina_force_un = 0;
};

enum class EventKind : std::int8_t { Contact = 1, Cut = 2, Tear = 3, Burn = 4, Drain = 5, AttachmentBroken = 6 };

struct Event {
  std::int64_t step = 0;
  double t_s = 0;
  EventKind kind = EventKind::Contact;
  std::int8_t instrument_id = -1;
  std::int32_t tissue_id = -1;
  double position_mm[3] = {};
  double magnitude = 0;  // unit per kind: see event_t.lcm
  char what[32] = {};    // the simulation's name of the event (the longest key is 24 characters)
};

struct PhysicsTiming {
  std::int64_t step = 0;
  std::int32_t period_us = 1000;
  std::int32_t window_steps = 0;
  float step_p50_us = 0, step_p99_us = 0, step_max_us = 0;
  float jitter_p99_us = 0, jitter_max_us = 0;
  std::int64_t overruns = 0, late_steps = 0, dropped_steps = 0;
  bool paused = false;
};

struct DeviceStatus {
  double t_s = 0;  // session time of the hub's clock (device_status_t.lcm)
  std::int32_t device_id = 0;
  char name[24] = {};
  char transport[96] = {};
  std::int8_t state = 0;  // device_status_t::STATE_*
  char detail[96] = {};
  std::int64_t frames_rx = 0, frames_tx = 0, bytes_rx = 0, crc_errors = 0, framing_errors = 0;
  std::int64_t version_rejected = 0, unknown_type_rejected = 0, length_rejected = 0, identity_rejected = 0, protocol_rejected = 0;
  std::int64_t sequence_gaps = 0, heartbeat_misses = 0, reconnects = 0, last_sample_age_us = -1;
  float sample_rate_hz = 0, latency_p50_us = 0, latency_p99_us = 0, clock_offset_us = 0;
  std::int32_t configured_rate_hz = 0;
  bool stuck = false;
  std::int64_t stuck_episodes = 0, stuck_samples = 0, range_rejected = 0, timestamp_jumps = 0, reader_stalls = 0;
  float reader_stall_max_ms = 0;
  char calibration[64] = {};
};

struct Score {
  static constexpr std::size_t kMaxMetrics = 12;
  std::int64_t step = 0;
  char case_id[32] = {};
  bool final_score = false;
  double total = 0;
  std::uint8_t n = 0;
  char name[kMaxMetrics][24] = {};
  double value[kMaxMetrics] = {};
  double pass_score = 0;  // the case's ([proficiency] pass_score)
};

// The case's criteria with a score card (criteria_t).
struct Criteria {
  static constexpr std::size_t kMax = 8;
  std::int64_t step = 0;
  char case_id[32] = {};
  bool final_score = false;
  std::uint8_t n = 0;
  char kind[kMax][20] = {};
  char target[kMax][24] = {};
  double value[kMax] = {}, threshold[kMax] = {}, progress[kMax] = {};
  bool met[kMax] = {};
};

// The scoring's accumulated inputs with a score card (session_totals_t).
struct Totals {
  static constexpr std::size_t kMaxKinds = 16;
  static constexpr std::size_t kMaxInstruments = 6;
  std::int64_t step = 0;
  char case_id[32] = {};
  bool final_score = false;
  std::int32_t formula_version = 0;
  double elapsed_s = 0, path_length_mm = 0;
  std::int32_t retina_contacts = 0;
  double retina_contact_time_s = 0, peak_retina_force_un = 0, retina_force_impulse_un_s = 0;
  double time_over_force_limit_s = 0, force_limit_un = 0;
  std::int32_t burns_on_target = 0, burns_elsewhere = 0, retina_tears = 0, other_tears = 0, iatrogenic_events = 0;
  bool illumination_measured = false;
  double working_time_s = 0, lit_working_time_s = 0;
  bool microscope_measured = false;
  double microscope_working_time_s = 0, out_of_field_s = 0, off_centre_s = 0, out_of_focus_s = 0, extreme_zoom_s = 0;
  std::uint8_t n_kinds = 0;
  char event_kind[kMaxKinds][32] = {};  // event_key(): the longest is 24 characters
  std::int32_t event_count[kMaxKinds] = {};
  std::uint8_t n_instruments = 0;
  char instrument_kind[kMaxInstruments][16] = {};
  double instrument_path_mm[kMaxInstruments] = {};
  std::int32_t instrument_contacts[kMaxInstruments] = {};
  double instrument_peak_force_un[kMaxInstruments] = {};
  double instrument_contact_time_s[kMaxInstruments] = {};
};

// The pedals' surgical controls and the laser console's settings (controls_t).
struct Controls {
  std::int64_t step = 0;
  double t_s = 0;
  double vacuum_mmhg = 0, cut_rate_cpm = 0;
  bool reflux = false, laser_fire = false, pick_out = false;
  double light_level = 0, zoom = 1;
  double laser_power_mw = 0, laser_duration_ms = 0;
  double vitrectomy_pedal_travel[4] = {}, microscope_pedal_travel[4] = {};
  double macula_light_dose_j_cm2 = 0, light_dose_limit_j_cm2 = 0;
};

using TelemetryItem = std::variant<InstrumentState, Event, PhysicsTiming, DeviceStatus, Score, Criteria, Totals, Controls>;
static_assert(std::is_trivially_copyable_v<TelemetryItem>, "ring items must be memcpy-able");

}  // namespace vitreo::telemetry
