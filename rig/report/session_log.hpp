#pragma once
// A session's telemetry log (the LCM log the main job writes to OUT/telemetry.lcmlog), read into
// plain records for the debrief. Only what the report uses is kept; everything is taken from the
// messages as the rig published them (no recomputation of scores or criteria here).
//
// A log that stops inside an event or holds bytes that are not an event is read up to there: the
// records before it are kept and `notice` says where and why it stopped. A message that does not
// decode is skipped and counted. Only a file that cannot be opened, or that holds no readable event
// at all, is an error (read_session_log throws std::runtime_error with the reason).
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace vitreo::report {

struct TipSample {
  std::int64_t step = 0;
  double t_s = 0;
  int instrument = 0;  // tracker slot (instrument_state_t.instrument_id)
  int port = -1;       // -1: outside the eye
  std::string kind;
  std::array<double, 3> tip_mm{};
  double insertion_mm = 0;
  double actuation = 0;
  double retina_force_un = 0;
  bool frozen = false;
};

struct EventRecord {
  std::int64_t step = 0;
  double t_s = 0;
  int kind = 0;  // event_t::KIND_*
  int instrument = -1;
  int tissue = -1;
  std::array<double, 3> position_mm{};
  double magnitude = 0;
  std::string what;
};

struct ScoreRecord {
  std::int64_t step = 0;
  std::string case_id;
  bool final_score = false;
  double total = 0;
  double pass_score = 0;  // the case's ([proficiency] pass_score)
  std::vector<std::pair<std::string, double>> categories;
};

struct CriterionRecord {
  std::string kind, target;
  double value = 0, threshold = 0, progress = 0;
  bool met = false;
};

struct CriteriaRecord {
  std::int64_t step = 0;
  std::string case_id;
  bool final_score = false;
  std::vector<CriterionRecord> criteria;
};

struct InstrumentTotals {
  std::string kind;
  double path_mm = 0, peak_force_un = 0, contact_time_s = 0;
  std::int32_t contacts = 0;
};

struct TotalsRecord {
  std::int64_t step = 0;
  std::string case_id;
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
  std::vector<std::pair<std::string, std::int32_t>> events_by_kind;
  std::vector<InstrumentTotals> instruments;
};

struct ControlsRecord {
  std::int64_t step = 0;
  double t_s = 0;
  double vacuum_mmhg = 0, cut_rate_cpm = 0, light_level = 0, zoom = 1;
  bool reflux = false, laser_fire = false;
  double vitrectomy_travel[4] = {}, microscope_travel[4] = {};  // the pedals' axes, 0..1
  double macula_dose_j_cm2 = 0, dose_limit_j_cm2 = 0;
};

// A spell in which a device was not simply working: "lost" (link gone), "stuck" (bit-identical
// samples for 50 ms or more of device time; a tracker's instrument frozen), "stale" (no sample for a
// while), "refused" (ERROR: another device, serial or protocol version than the rig file's). Times are
// the session's, as the statuses carry them (device_status_t.t_s): a link change and a stuck verdict
// are published at once, staleness to the statuses' 10 Hz.
struct DeviceSpell {
  std::string what;
  double from_s = 0;
  double to_s = -1;  // < 0: it lasted to the end of the log
  std::string detail;  // the rig's words when it began
};

// One device's link and sensor record (VITREO_DEVICE_STATUS): the counters of its last status (they
// are cumulative over the session) and its spells.
struct DeviceRecord {
  std::int32_t device_id = 0;
  std::string name, transport;
  std::string calibration;  // the calibration in force for it (its last status), "" uncalibrated
  int state = 0;  // device_status_t::STATE_* of the last status
  std::string detail;
  std::uint64_t status_messages = 0;
  std::int64_t frames_rx = 0, crc_errors = 0, framing_errors = 0, version_rejected = 0, unknown_type_rejected = 0, length_rejected = 0,
               range_rejected = 0, identity_rejected = 0, protocol_rejected = 0, sequence_gaps = 0, heartbeat_misses = 0, reconnects = 0,
               stuck_episodes = 0, stuck_samples = 0, timestamp_jumps = 0, reader_stalls = 0;
  double reader_stall_max_ms = 0;
  std::vector<DeviceSpell> spells;
};

struct SessionLog {
  std::string path;
  std::uint64_t file_bytes = 0;
  std::uint64_t events_read = 0;      // LCM log events read
  std::int64_t first_utime_us = 0;    // the first event's log timestamp: when the session started
  std::uint64_t messages_skipped = 0; // events that did not decode as their channel's type
  bool complete = true;               // the log ended exactly after an event
  std::string notice;                 // why it is not complete (empty when it is)
  std::vector<TipSample> tips;
  std::vector<EventRecord> events;
  std::vector<ScoreRecord> scores;
  std::vector<CriteriaRecord> criteria;
  std::vector<TotalsRecord> totals;
  std::vector<ControlsRecord> controls;
  std::vector<DeviceRecord> devices;  // in order of their first status
};

// Reads the whole log (see above for what is an error and what a notice).
SessionLog read_session_log(const std::string& path);

}  // namespace vitreo::report
