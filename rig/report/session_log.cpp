#include "rig/report/session_log.hpp"

#include <algorithm>
#include <iterator>
#include <stdexcept>

#include "rig/telemetry/channels.hpp"
#include "rig/telemetry/lcm_decode.hpp"
#include "rig/telemetry/lcm_log_reader.hpp"
#include "rig/telemetry/lcm_subscribe.hpp"
#include "vitreo_lcm/controls_t.hpp"
#include "vitreo_lcm/criteria_t.hpp"
#include "vitreo_lcm/device_status_t.hpp"
#include "vitreo_lcm/event_t.hpp"
#include "vitreo_lcm/instrument_state_t.hpp"
#include "vitreo_lcm/score_t.hpp"
#include "vitreo_lcm/session_totals_t.hpp"

namespace vitreo::report {

namespace {

using telemetry::DecodeError;
using telemetry::decode_message;

template <class Msg>
bool decode(const telemetry::LcmLogEvent& ev, Msg& m) {
  return decode_message(ev.data.data(), ev.data.size(), m, telemetry::kDefaultMaxMessageBytes) == DecodeError::None;
}

// What a status says is wrong with its device now ("" when nothing): the spell it belongs to.
std::string spell_of(const vitreo_lcm::device_status_t& m) {
  using S = vitreo_lcm::device_status_t;
  if (m.state == S::STATE_LOST) return "lost";
  if (m.state == S::STATE_ERROR) return "refused";
  if (m.stuck) return "stuck";
  if (m.state == S::STATE_ACTIVE && m.detail.rfind("stale", 0) == 0) return "stale";
  return "";
}

void take_device_status(const vitreo_lcm::device_status_t& m, SessionLog& log) {
  auto it = std::find_if(log.devices.begin(), log.devices.end(), [&](const DeviceRecord& d) { return d.device_id == m.device_id; });
  if (it == log.devices.end()) {
    log.devices.emplace_back();
    it = std::prev(log.devices.end());
    it->device_id = m.device_id;
  }
  DeviceRecord& d = *it;
  ++d.status_messages;
  d.name = m.name;
  d.transport = m.transport;
  d.calibration = m.calibration;
  d.state = m.state;
  d.detail = m.detail;
  d.frames_rx = m.frames_rx;
  d.crc_errors = m.crc_errors;
  d.framing_errors = m.framing_errors;
  d.version_rejected = m.version_rejected;
  d.unknown_type_rejected = m.unknown_type_rejected;
  d.length_rejected = m.length_rejected;
  d.range_rejected = m.range_rejected;
  d.identity_rejected = m.identity_rejected;
  d.protocol_rejected = m.protocol_rejected;
  d.sequence_gaps = m.sequence_gaps;
  d.heartbeat_misses = m.heartbeat_misses;
  d.reconnects = m.reconnects;
  d.stuck_episodes = m.stuck_episodes;
  d.stuck_samples = m.stuck_samples;
  d.timestamp_jumps = m.timestamp_jumps;
  d.reader_stalls = m.reader_stalls;
  d.reader_stall_max_ms = m.reader_stall_max_ms;
  // A spell ends when a status no longer says it, and begins when one first does, at the session
  // time the status was taken (not where the telemetry thread happened to publish it among the
  // physics' messages: a loaded machine drains those late and in bulk).
  const std::string now = spell_of(m);
  DeviceSpell* open = !d.spells.empty() && d.spells.back().to_s < 0 ? &d.spells.back() : nullptr;
  if (open && open->what != now) {
    open->to_s = m.t_s;
    open = nullptr;
  }
  if (!open && !now.empty()) d.spells.push_back({now, m.t_s, -1, m.detail});
}

// Records one decoded event; false when its bytes did not decode as its channel's type.
bool take(const telemetry::LcmLogEvent& ev, SessionLog& log) {
  namespace t = telemetry;
  if (ev.channel == t::kChanInstrumentState) {
    vitreo_lcm::instrument_state_t m{};
    if (!decode(ev, m)) return false;
    TipSample s;
    s.step = m.step;
    s.t_s = m.t_s;
    s.instrument = m.instrument_id;
    s.port = m.port_id;
    s.kind = m.kind;
    for (int i = 0; i < 3; ++i) s.tip_mm[static_cast<std::size_t>(i)] = m.tip_mm[i];
    s.insertion_mm = m.insertion_mm;
    s.actuation = m.actuation;
    s.retina_force_un = m.retina_force_un;
    s.frozen = m.frozen;
    log.tips.push_back(std::move(s));
  } else if (ev.channel == t::kChanEvent) {
    vitreo_lcm::event_t m{};
    if (!decode(ev, m)) return false;
    EventRecord e;
    e.step = m.step;
    e.t_s = m.t_s;
    e.kind = m.kind;
    e.instrument = m.instrument_id;
    e.tissue = m.tissue_id;
    for (int i = 0; i < 3; ++i) e.position_mm[static_cast<std::size_t>(i)] = m.position_mm[i];
    e.magnitude = m.magnitude;
    e.what = m.what;
    log.events.push_back(std::move(e));
  } else if (ev.channel == t::kChanScore) {
    vitreo_lcm::score_t m{};
    if (!decode(ev, m)) return false;
    ScoreRecord s;
    s.step = m.step;
    s.case_id = m.case_id;
    s.final_score = m.final_score;
    s.total = m.total;
    s.pass_score = m.pass_score;
    for (std::size_t i = 0; i < m.name.size() && i < m.value.size(); ++i) s.categories.emplace_back(m.name[i], m.value[i]);
    log.scores.push_back(std::move(s));
  } else if (ev.channel == t::kChanCriteria) {
    vitreo_lcm::criteria_t m{};
    if (!decode(ev, m)) return false;
    CriteriaRecord c;
    c.step = m.step;
    c.case_id = m.case_id;
    c.final_score = m.final_score;
    for (std::size_t i = 0; i < static_cast<std::size_t>(m.n); ++i)
      c.criteria.push_back({m.kind[i], m.target[i], m.value[i], m.threshold[i], m.progress[i], m.met[i] != 0});
    log.criteria.push_back(std::move(c));
  } else if (ev.channel == t::kChanTotals) {
    vitreo_lcm::session_totals_t m{};
    if (!decode(ev, m)) return false;
    TotalsRecord r;
    r.step = m.step;
    r.case_id = m.case_id;
    r.final_score = m.final_score;
    r.formula_version = m.formula_version;
    r.elapsed_s = m.elapsed_s;
    r.path_length_mm = m.path_length_mm;
    r.retina_contacts = m.retina_contacts;
    r.retina_contact_time_s = m.retina_contact_time_s;
    r.peak_retina_force_un = m.peak_retina_force_un;
    r.retina_force_impulse_un_s = m.retina_force_impulse_un_s;
    r.time_over_force_limit_s = m.time_over_force_limit_s;
    r.force_limit_un = m.force_limit_un;
    r.burns_on_target = m.burns_on_target;
    r.burns_elsewhere = m.burns_elsewhere;
    r.retina_tears = m.retina_tears;
    r.other_tears = m.other_tears;
    r.iatrogenic_events = m.iatrogenic_events;
    r.illumination_measured = m.illumination_measured;
    r.working_time_s = m.working_time_s;
    r.lit_working_time_s = m.lit_working_time_s;
    r.microscope_measured = m.microscope_measured;
    r.microscope_working_time_s = m.microscope_working_time_s;
    r.out_of_field_s = m.out_of_field_s;
    r.off_centre_s = m.off_centre_s;
    r.out_of_focus_s = m.out_of_focus_s;
    r.extreme_zoom_s = m.extreme_zoom_s;
    for (std::size_t i = 0; i < static_cast<std::size_t>(m.n_kinds); ++i) r.events_by_kind.emplace_back(m.event_kind[i], m.event_count[i]);
    for (std::size_t i = 0; i < static_cast<std::size_t>(m.n_instruments); ++i)
      r.instruments.push_back({m.instrument_kind[i], m.instrument_path_mm[i], m.instrument_peak_force_un[i],
                               m.instrument_contact_time_s[i], m.instrument_contacts[i]});
    log.totals.push_back(std::move(r));
  } else if (ev.channel == t::kChanControls) {
    vitreo_lcm::controls_t m{};
    if (!decode(ev, m)) return false;
    ControlsRecord c;
    c.step = m.step;
    c.t_s = m.t_s;
    c.vacuum_mmhg = m.vacuum_mmhg;
    c.cut_rate_cpm = m.cut_rate_cpm;
    c.light_level = m.light_level;
    c.zoom = m.zoom;
    c.reflux = m.reflux;
    c.laser_fire = m.laser_fire;
    for (int a = 0; a < 4; ++a) {
      c.vitrectomy_travel[a] = m.vitrectomy_pedal_travel[a];
      c.microscope_travel[a] = m.microscope_pedal_travel[a];
    }
    c.macula_dose_j_cm2 = m.macula_light_dose_j_cm2;
    c.dose_limit_j_cm2 = m.light_dose_limit_j_cm2;
    log.controls.push_back(c);
  } else if (ev.channel == t::kChanDeviceStatus) {
    vitreo_lcm::device_status_t m{};
    if (!decode(ev, m)) return false;
    take_device_status(m, log);
  }
  return true;  // other channels (timing, acks, frames) are not part of the debrief
}

}  // namespace

SessionLog read_session_log(const std::string& path) {
  SessionLog log;
  log.path = path;
  telemetry::LcmLogReader reader;
  if (!reader.open(path)) throw std::runtime_error(reader.problem());
  log.file_bytes = reader.file_size();
  telemetry::LcmLogEvent ev;
  for (;;) {
    const auto st = reader.next(ev, static_cast<std::uint32_t>(telemetry::kDefaultMaxMessageBytes));
    if (st == telemetry::LcmLogReader::Status::End) break;
    if (st == telemetry::LcmLogReader::Status::Event) {
      if (log.events_read++ == 0) log.first_utime_us = ev.timestamp;
      if (!take(ev, log)) ++log.messages_skipped;
      continue;
    }
    log.complete = false;
    const std::string where = "byte " + std::to_string(reader.offset()) + " of " + std::to_string(log.file_bytes);
    log.notice = st == telemetry::LcmLogReader::Status::Truncated
                     ? "the telemetry log ends inside an event at " + where + " (truncated: the session was cut off or the file is incomplete)"
                     : "the telemetry log is corrupted at " + where + " (" + reader.problem() + ")";
    log.notice += "; the report shows the " + std::to_string(log.events_read) + " events before it";
    break;
  }
  if (log.events_read == 0)
    throw std::runtime_error("'" + path + "' holds no readable LCM event" + (log.notice.empty() ? "" : ": " + log.notice));
  return log;
}

}  // namespace vitreo::report
