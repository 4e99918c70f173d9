#include "rig/telemetry/telemetry_mapping.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "rig/telemetry/event_keys.hpp"

namespace vitreo::telemetry {

// ---- State → items --------------------------------------------------------------------------------

InstrumentState instrument_state_item(const Hand& hand, const core::InstrumentState& sim, std::int64_t step, double t_s) {
  InstrumentState st;
  st.step = step;
  st.t_s = t_s;
  st.instrument_id = static_cast<std::int8_t>(hand.tracker);
  st.port_id = sim.inside ? static_cast<std::int8_t>(hand.eye_port) : std::int8_t{-1};
  copy_text(st.kind, hand.holds);
  // The core's frame is the one the picture draws: tip and axis already turned into the eye frame.
  // Its axis u points from the port toward the tip; instrument_state_t's from the tip to the handle.
  for (int i = 0; i < 3; ++i) {
    st.tip_mm[i] = sim.frame.tip[i];
    st.shaft_axis[i] = -sim.frame.u[i];
  }
  st.roll_rad = sim.input.twist_rad;
  st.insertion_mm = sim.inside ? sim.frame.inserted_mm : 0.0;
  st.actuation = sim.input.actuation;
  st.frozen = hand.frozen;
  st.retina_force_un = sim.retina_force_un;
  return st;
}

Event instrument_event_item(const core::InstrumentEvent& e, int hand, std::int64_t step, double t_s) {
  Event ev;
  ev.step = step;
  ev.t_s = t_s;
  using K = core::InstrumentEventKind;
  switch (e.kind) {
    case K::kLaserBurn: ev.kind = EventKind::Burn; break;
    case K::kUnintendedTear: ev.kind = EventKind::Tear; break;
    case K::kAttachmentBroken: ev.kind = EventKind::AttachmentBroken; break;
    default: ev.kind = EventKind::Contact; break;  // forces, collisions, grasps, light dose
  }
  ev.instrument_id = static_cast<std::int8_t>(hand);
  // A tear's, a grasp's, a lost grasp's and a broken attachment's `other` is the tissue surface.
  const bool on_tissue = e.kind == K::kUnintendedTear || e.kind == K::kGrasp || e.kind == K::kGraspLost ||
                         e.kind == K::kAttachmentBroken;
  if (on_tissue && e.other != core::kNone) ev.tissue_id = static_cast<std::int32_t>(e.other);
  for (int i = 0; i < 3; ++i) ev.position_mm[i] = e.position_mm[i];
  ev.magnitude = e.magnitude;
  copy_text(ev.what, event_key(e.kind));
  return ev;
}

Event tissue_event_item(const core::TissueEvent& e, std::int64_t step, double t_s) {
  Event ev;
  ev.step = step;
  ev.t_s = t_s;
  const char* what = "tissue_attachment_broken";
  switch (e.kind) {
    case core::TissueEventKind::kTear: ev.kind = EventKind::Tear, what = "tissue_tear"; break;
    case core::TissueEventKind::kGripBroken: ev.kind = EventKind::Contact, what = "tissue_grip_broken"; break;  // slipped out of the jaws
    default: ev.kind = EventKind::AttachmentBroken; break;
  }
  ev.tissue_id = static_cast<std::int32_t>(e.surface);
  for (int i = 0; i < 3; ++i) ev.position_mm[i] = e.position_mm[i];
  ev.magnitude = e.magnitude;
  copy_text(ev.what, what);
  return ev;
}

bool tissue_event_passed_on(const core::TissueEvent& e, const std::vector<core::InstrumentEvent>& instrument_events) {
  return std::any_of(instrument_events.begin(), instrument_events.end(), [&](const core::InstrumentEvent& x) {
    return x.other == e.surface && x.magnitude == e.magnitude && x.position_mm == e.position_mm;
  });
}

Score score_item(const core::ScoreCard& card, std::string_view case_id, std::int64_t step, bool final_score, double pass_score) {
  Score s;
  s.pass_score = pass_score;
  s.step = step;
  copy_text(s.case_id, case_id);
  s.final_score = final_score;
  s.total = card.total;
  for (const core::ScoreEntry& e : card.categories) {
    if (s.n == Score::kMaxMetrics) break;
    copy_text(s.name[s.n], e.name);
    s.value[s.n++] = e.value;
  }
  return s;
}

Criteria criteria_item(const std::vector<core::CriterionProgress>& criteria, std::string_view case_id, std::int64_t step, bool final_score) {
  Criteria c;
  c.step = step;
  copy_text(c.case_id, case_id);
  c.final_score = final_score;
  for (const core::CriterionProgress& p : criteria) {
    if (c.n == Criteria::kMax) break;
    copy_text(c.kind[c.n], core::to_string(p.kind));
    copy_text(c.target[c.n], p.target);
    c.value[c.n] = p.value;
    c.threshold[c.n] = p.threshold;
    c.progress[c.n] = p.progress;
    c.met[c.n++] = p.met;
  }
  return c;
}

Totals totals_item(const core::SessionMetrics& m, std::string_view case_id, std::int64_t step, bool final_score) {
  const core::SessionTotals& t = m.totals();
  Totals o;
  o.step = step;
  copy_text(o.case_id, case_id);
  o.final_score = final_score;
  o.formula_version = core::kScoreFormulaVersion;
  o.elapsed_s = t.elapsed_s;
  o.path_length_mm = t.path_length_mm;
  o.retina_contacts = static_cast<std::int32_t>(t.retina_contacts);
  o.retina_contact_time_s = t.retina_contact_time_s;
  o.peak_retina_force_un = t.peak_retina_force_un;
  o.retina_force_impulse_un_s = t.retina_force_impulse_un_s;
  o.time_over_force_limit_s = t.time_over_force_limit_s;
  o.force_limit_un = t.force_limit_un;
  o.burns_on_target = static_cast<std::int32_t>(t.burns_on_target);
  o.burns_elsewhere = static_cast<std::int32_t>(t.burns_elsewhere);
  o.retina_tears = static_cast<std::int32_t>(t.retina_tears);
  o.other_tears = static_cast<std::int32_t>(t.other_tears);
  o.iatrogenic_events = static_cast<std::int32_t>(t.iatrogenic_events());
  o.illumination_measured = t.illumination_measured;
  o.working_time_s = t.working_time_s;
  o.lit_working_time_s = t.lit_working_time_s;
  o.microscope_measured = t.microscope_measured;
  o.microscope_working_time_s = t.microscope_working_time_s;
  o.out_of_field_s = t.out_of_field_s;
  o.off_centre_s = t.off_centre_s;
  o.out_of_focus_s = t.out_of_focus_s;
  o.extreme_zoom_s = t.extreme_zoom_s;
  for (std::size_t k = 0; k < core::kInstrumentEventKinds && o.n_kinds < Totals::kMaxKinds; ++k) {
    copy_text(o.event_kind[o.n_kinds], event_key(static_cast<core::InstrumentEventKind>(k)));
    o.event_count[o.n_kinds++] = static_cast<std::int32_t>(t.events[k]);
  }
  for (std::uint32_t i = 0; i < m.instrument_count() && o.n_instruments < Totals::kMaxInstruments; ++i) {
    const core::InstrumentMetrics& im = m.instrument(i);
    copy_text(o.instrument_kind[o.n_instruments], core::to_string(im.kind));
    o.instrument_path_mm[o.n_instruments] = im.path_length_mm;
    o.instrument_contacts[o.n_instruments] = static_cast<std::int32_t>(im.retina_contacts);
    o.instrument_peak_force_un[o.n_instruments] = im.peak_retina_force_un;
    o.instrument_contact_time_s[o.n_instruments++] = im.retina_contact_time_s;
  }
  return o;
}

Controls controls_item(const ControlsState& c, std::int64_t step, double t_s) {
  Controls o;
  o.step = step;
  o.t_s = t_s;
  o.vacuum_mmhg = c.vacuum_mmhg;
  o.cut_rate_cpm = c.cut_rate_cpm;
  o.reflux = c.reflux;
  o.laser_fire = c.laser_fire;
  o.pick_out = c.pick_out;
  o.light_level = c.light_level;
  o.zoom = c.zoom;
  o.laser_power_mw = c.laser_power_mw;
  o.laser_duration_ms = c.laser_duration_ms;
  for (int i = 0; i < 4; ++i) {
    o.vitrectomy_pedal_travel[i] = c.vitrectomy_pedal_travel ? c.vitrectomy_pedal_travel[i] : 0.0;
    o.microscope_pedal_travel[i] = c.microscope_pedal_travel ? c.microscope_pedal_travel[i] : 0.0;
  }
  o.macula_light_dose_j_cm2 = c.macula_light_dose_j_cm2;
  o.light_dose_limit_j_cm2 = c.light_dose_limit_j_cm2;
  return o;
}

PhysicsTiming timing_item(const runtime::LoopStats& s, std::uint64_t last_step, std::int64_t period_ns, bool paused) {
  PhysicsTiming t;
  t.step = static_cast<std::int64_t>(last_step);
  t.period_us = static_cast<std::int32_t>(period_ns / 1000);
  t.window_steps = static_cast<std::int32_t>(s.window_steps);
  t.step_p50_us = static_cast<float>(s.step_p50_ns) * 1e-3f;
  t.step_p99_us = static_cast<float>(s.step_p99_ns) * 1e-3f;
  t.step_max_us = static_cast<float>(s.step_max_ns) * 1e-3f;
  t.jitter_p99_us = static_cast<float>(s.jitter_p99_ns) * 1e-3f;
  t.jitter_max_us = static_cast<float>(s.jitter_max_ns) * 1e-3f;
  t.overruns = static_cast<std::int64_t>(s.overruns);
  t.late_steps = static_cast<std::int64_t>(s.late_steps);
  t.dropped_steps = static_cast<std::int64_t>(s.dropped_steps);
  t.paused = paused;
  return t;
}

std::int8_t device_state_code(drivers::LinkState s, bool refused) {
  using M = vitreo_lcm::device_status_t;
  if (refused) return M::STATE_ERROR;
  switch (s) {
    case drivers::LinkState::streaming:
    case drivers::LinkState::stale: return M::STATE_ACTIVE;  // still its device; `detail` says the samples are late
    case drivers::LinkState::lost:
    case drivers::LinkState::reconnecting: return M::STATE_LOST;
    case drivers::LinkState::connecting:
    case drivers::LinkState::configuring: return M::STATE_INACTIVE;
  }
  return M::STATE_UNCONFIGURED;
}

DeviceStatus device_status_item(std::int32_t device_id, std::string_view name, std::string_view transport,
                                const drivers::DeviceSession& session, std::uint64_t now_us, const DeviceMeasured& measured,
                                std::string_view calibration) {
  const drivers::LinkStats& st = session.stats();
  const drivers::LinkState link = session.state();
  const bool refused = !session.refusal().empty();
  DeviceStatus s;
  s.device_id = device_id;
  copy_text(s.name, name);
  copy_text(s.transport, transport);
  copy_text(s.calibration, calibration);
  s.state = device_state_code(link, refused);
  const std::uint64_t last = session.last_sample_us();
  s.last_sample_age_us = last == 0 ? -1 : static_cast<std::int64_t>(now_us >= last ? now_us - last : 0);
  // `detail`: why the device is not simply working, empty when it is (device_status_t.lcm).
  char detail[sizeof s.detail] = {};
  if (refused) {
    copy_text(detail, session.refusal());
  } else if (s.state == vitreo_lcm::device_status_t::STATE_LOST) {
    copy_text(detail, session.last_error().empty() ? std::string_view("no link yet") : std::string_view(session.last_error()));
  } else if (link == drivers::LinkState::stale) {
    std::snprintf(detail, sizeof detail, "stale: no sample for %llu ms", static_cast<unsigned long long>(s.last_sample_age_us / 1000));
  } else if (session.stuck()) {
    copy_text(detail, "stuck: identical samples for >= 50 ms");
  }
  copy_text(s.detail, text(detail));
  s.frames_rx = static_cast<std::int64_t>(st.frames);
  s.frames_tx = static_cast<std::int64_t>(st.frames_tx);
  s.bytes_rx = static_cast<std::int64_t>(st.bytes);
  s.crc_errors = static_cast<std::int64_t>(st.crc_errors);
  s.framing_errors = static_cast<std::int64_t>(st.framing_errors);
  s.version_rejected = static_cast<std::int64_t>(st.version_errors);
  s.unknown_type_rejected = static_cast<std::int64_t>(st.unknown_type);
  s.length_rejected = static_cast<std::int64_t>(st.length_errors);
  s.range_rejected = static_cast<std::int64_t>(st.range_rejected);
  s.identity_rejected = static_cast<std::int64_t>(st.identity_rejected);
  s.protocol_rejected = static_cast<std::int64_t>(st.protocol_rejected);
  s.sequence_gaps = static_cast<std::int64_t>(st.drops);
  s.heartbeat_misses = static_cast<std::int64_t>(st.heartbeat_misses);
  s.reconnects = static_cast<std::int64_t>(st.reconnects);
  s.t_s = measured.session_t_s;
  s.sample_rate_hz = measured.sample_rate_hz;
  s.latency_p50_us = measured.latency_p50_us;
  s.latency_p99_us = measured.latency_p99_us;
  // ClockMapper keeps host − device; the message carries device − host.
  s.clock_offset_us = session.clock().valid() ? static_cast<float>(-session.clock().offset_us()) : 0.0f;
  s.configured_rate_hz = static_cast<std::int32_t>(session.configured_rate_hz());
  s.stuck = session.stuck();
  s.stuck_episodes = static_cast<std::int64_t>(st.stuck_episodes);
  s.stuck_samples = static_cast<std::int64_t>(st.stuck_samples);
  s.timestamp_jumps = static_cast<std::int64_t>(st.timestamp_jumps);
  s.reader_stalls = static_cast<std::int64_t>(measured.reader_stalls);
  s.reader_stall_max_ms = measured.reader_stall_max_ms;
  return s;
}

// ---- Items → messages -----------------------------------------------------------------------------

vitreo_lcm::instrument_state_t to_lcm(const InstrumentState& v, std::int64_t utime_us) {
  vitreo_lcm::instrument_state_t m;
  m.utime_us = utime_us;
  m.step = v.step;
  m.t_s = v.t_s;
  m.instrument_id = v.instrument_id;
  m.port_id = v.port_id;
  m.kind = text(v.kind);
  for (int i = 0; i < 3; ++i) {
    m.tip_mm[i] = v.tip_mm[i];
    m.shaft_axis[i] = v.shaft_axis[i];
  }
  m.roll_rad = v.roll_rad;
  m.insertion_mm = v.insertion_mm;
  m.actuation = v.actuation;
  m.frozen = v.frozen;
  m.retina_force_un = v.retina_force_un;
  return m;
}

vitreo_lcm::event_t to_lcm(const Event& v, std::int64_t utime_us) {
  vitreo_lcm::event_t m;
  m.utime_us = utime_us;
  m.step = v.step;
  m.t_s = v.t_s;
  m.kind = static_cast<std::int8_t>(v.kind);
  m.instrument_id = v.instrument_id;
  m.tissue_id = v.tissue_id;
  for (int i = 0; i < 3; ++i) m.position_mm[i] = v.position_mm[i];
  m.magnitude = v.magnitude;
  m.what = text(v.what);
  return m;
}

vitreo_lcm::physics_timing_t to_lcm(const PhysicsTiming& v, std::int64_t utime_us) {
  vitreo_lcm::physics_timing_t m;
  m.utime_us = utime_us;
  m.step = v.step;
  m.period_us = v.period_us;
  m.window_steps = v.window_steps;
  m.step_p50_us = v.step_p50_us;
  m.step_p99_us = v.step_p99_us;
  m.step_max_us = v.step_max_us;
  m.jitter_p99_us = v.jitter_p99_us;
  m.jitter_max_us = v.jitter_max_us;
  m.overruns = v.overruns;
  m.late_steps = v.late_steps;
  m.dropped_steps = v.dropped_steps;
  m.telemetry_dropped = 0;
  m.paused = v.paused;
  return m;
}

vitreo_lcm::device_status_t to_lcm(const DeviceStatus& v, std::int64_t utime_us) {
  vitreo_lcm::device_status_t m;
  m.utime_us = utime_us;
  m.t_s = v.t_s;
  m.device_id = v.device_id;
  m.name = text(v.name);
  m.transport = text(v.transport);
  m.state = v.state;
  m.detail = text(v.detail);
  m.calibration = text(v.calibration);
  m.frames_rx = v.frames_rx;
  m.frames_tx = v.frames_tx;
  m.bytes_rx = v.bytes_rx;
  m.crc_errors = v.crc_errors;
  m.framing_errors = v.framing_errors;
  m.version_rejected = v.version_rejected;
  m.unknown_type_rejected = v.unknown_type_rejected;
  m.length_rejected = v.length_rejected;
  m.identity_rejected = v.identity_rejected;
  m.protocol_rejected = v.protocol_rejected;
  m.sequence_gaps = v.sequence_gaps;
  m.heartbeat_misses = v.heartbeat_misses;
  m.reconnects = v.reconnects;
  m.last_sample_age_us = v.last_sample_age_us;
  m.sample_rate_hz = v.sample_rate_hz;
  m.configured_rate_hz = v.configured_rate_hz;
  m.latency_p50_us = v.latency_p50_us;
  m.latency_p99_us = v.latency_p99_us;
  m.clock_offset_us = v.clock_offset_us;
  m.stuck = v.stuck;
  m.stuck_episodes = v.stuck_episodes;
  m.stuck_samples = v.stuck_samples;
  m.range_rejected = v.range_rejected;
  m.timestamp_jumps = v.timestamp_jumps;
  m.reader_stalls = v.reader_stalls;
  m.reader_stall_max_ms = v.reader_stall_max_ms;
  return m;
}

vitreo_lcm::score_t to_lcm(const Score& v, std::int64_t utime_us) {
  vitreo_lcm::score_t m;
  m.utime_us = utime_us;
  m.step = v.step;
  m.case_id = text(v.case_id);
  m.final_score = v.final_score;
  m.total = v.total;
  const std::size_t n = std::min<std::size_t>(v.n, Score::kMaxMetrics);
  m.n = static_cast<std::int16_t>(n);
  for (std::size_t i = 0; i < n; ++i) {
    m.name.emplace_back(text(v.name[i]));
    m.value.push_back(v.value[i]);
  }
  m.pass_score = v.pass_score;
  return m;
}

vitreo_lcm::criteria_t to_lcm(const Criteria& v, std::int64_t utime_us) {
  vitreo_lcm::criteria_t m;
  m.utime_us = utime_us;
  m.step = v.step;
  m.case_id = text(v.case_id);
  m.final_score = v.final_score;
  const std::size_t n = std::min<std::size_t>(v.n, Criteria::kMax);
  m.n = static_cast<std::int16_t>(n);
  for (std::size_t i = 0; i < n; ++i) {
    m.kind.emplace_back(text(v.kind[i]));
    m.target.emplace_back(text(v.target[i]));
    m.value.push_back(v.value[i]);
    m.threshold.push_back(v.threshold[i]);
    m.progress.push_back(v.progress[i]);
    m.met.push_back(v.met[i]);
  }
  return m;
}

vitreo_lcm::session_totals_t to_lcm(const Totals& v, std::int64_t utime_us) {
  vitreo_lcm::session_totals_t m;
  m.utime_us = utime_us;
  m.step = v.step;
  m.case_id = text(v.case_id);
  m.final_score = v.final_score;
  m.formula_version = v.formula_version;
  m.elapsed_s = v.elapsed_s;
  m.path_length_mm = v.path_length_mm;
  m.retina_contacts = v.retina_contacts;
  m.retina_contact_time_s = v.retina_contact_time_s;
  m.peak_retina_force_un = v.peak_retina_force_un;
  m.retina_force_impulse_un_s = v.retina_force_impulse_un_s;
  m.time_over_force_limit_s = v.time_over_force_limit_s;
  m.force_limit_un = v.force_limit_un;
  m.burns_on_target = v.burns_on_target;
  m.burns_elsewhere = v.burns_elsewhere;
  m.retina_tears = v.retina_tears;
  m.other_tears = v.other_tears;
  m.iatrogenic_events = v.iatrogenic_events;
  m.illumination_measured = v.illumination_measured;
  m.working_time_s = v.working_time_s;
  m.lit_working_time_s = v.lit_working_time_s;
  m.microscope_measured = v.microscope_measured;
  m.microscope_working_time_s = v.microscope_working_time_s;
  m.out_of_field_s = v.out_of_field_s;
  m.off_centre_s = v.off_centre_s;
  m.out_of_focus_s = v.out_of_focus_s;
  m.extreme_zoom_s = v.extreme_zoom_s;
  const std::size_t nk = std::min<std::size_t>(v.n_kinds, Totals::kMaxKinds);
  m.n_kinds = static_cast<std::int16_t>(nk);
  for (std::size_t i = 0; i < nk; ++i) {
    m.event_kind.emplace_back(text(v.event_kind[i]));
    m.event_count.push_back(v.event_count[i]);
  }
  const std::size_t ni = std::min<std::size_t>(v.n_instruments, Totals::kMaxInstruments);
  m.n_instruments = static_cast<std::int8_t>(ni);
  for (std::size_t i = 0; i < ni; ++i) {
    m.instrument_kind.emplace_back(text(v.instrument_kind[i]));
    m.instrument_path_mm.push_back(v.instrument_path_mm[i]);
    m.instrument_contacts.push_back(v.instrument_contacts[i]);
    m.instrument_peak_force_un.push_back(v.instrument_peak_force_un[i]);
    m.instrument_contact_time_s.push_back(v.instrument_contact_time_s[i]);
  }
  return m;
}

vitreo_lcm::controls_t to_lcm(const Controls& v, std::int64_t utime_us) {
  vitreo_lcm::controls_t m;
  m.utime_us = utime_us;
  m.step = v.step;
  m.t_s = v.t_s;
  m.vacuum_mmhg = v.vacuum_mmhg;
  m.cut_rate_cpm = v.cut_rate_cpm;
  m.reflux = v.reflux;
  m.laser_fire = v.laser_fire;
  m.pick_out = v.pick_out;
  m.light_level = v.light_level;
  m.zoom = v.zoom;
  m.laser_power_mw = v.laser_power_mw;
  m.laser_duration_ms = v.laser_duration_ms;
  for (int i = 0; i < 4; ++i) {
    m.vitrectomy_pedal_travel[i] = v.vitrectomy_pedal_travel[i];
    m.microscope_pedal_travel[i] = v.microscope_pedal_travel[i];
  }
  m.macula_light_dose_j_cm2 = v.macula_light_dose_j_cm2;
  m.light_dose_limit_j_cm2 = v.light_dose_limit_j_cm2;
  return m;
}

}  // namespace vitreo::telemetry
