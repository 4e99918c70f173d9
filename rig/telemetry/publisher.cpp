#include "rig/telemetry/publisher.hpp"

#include <algorithm>
#include <ctime>
#include <stdexcept>
#include <type_traits>

#include "vitreo_lcm/controls_t.hpp"
#include "vitreo_lcm/criteria_t.hpp"
#include "vitreo_lcm/device_status_t.hpp"
#include "vitreo_lcm/event_t.hpp"
#include "vitreo_lcm/instrument_state_t.hpp"
#include "vitreo_lcm/physics_timing_t.hpp"
#include "vitreo_lcm/receive_status_t.hpp"
#include "vitreo_lcm/score_t.hpp"
#include "vitreo_lcm/session_totals_t.hpp"

namespace vitreo::telemetry {

std::int64_t wall_time_us() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000 + ts.tv_nsec / 1000;
}

PhysicsTiming timing_item(const runtime::LoopStats& s, std::uint64_t step, std::int64_t period_ns) {
  PhysicsTiming t;
  t.step = static_cast<std::int64_t>(step);
  t.period_us = static_cast<std::int32_t>(period_ns / 1000);
  t.step_p50_us = static_cast<float>(s.step_p50_ns) * 1e-3f;
  t.step_p99_us = static_cast<float>(s.step_p99_ns) * 1e-3f;
  t.step_max_us = static_cast<float>(s.step_max_ns) * 1e-3f;
  t.jitter_p99_us = static_cast<float>(s.jitter_p99_ns) * 1e-3f;
  t.jitter_max_us = static_cast<float>(s.jitter_max_ns) * 1e-3f;
  t.overruns = static_cast<std::int64_t>(s.overruns);
  t.late_steps = static_cast<std::int64_t>(s.late_steps);
  t.dropped_steps = static_cast<std::int64_t>(s.dropped_steps);
  t.window_steps = static_cast<std::int32_t>(s.window_steps);
  return t;
}

TelemetryPublisher::TelemetryPublisher(PublisherConfig config) : config_(std::move(config)), lcm_(config_.url) {
  if (!lcm_.good()) throw std::runtime_error("telemetry: cannot open LCM URL '" + config_.url + "'");
}

TelemetrySource& TelemetryPublisher::add_source(std::string name, std::size_t capacity) {
  return sources_.emplace_back(std::move(name), capacity ? capacity : config_.default_capacity);
}

std::uint64_t TelemetryPublisher::dropped() const noexcept {
  std::uint64_t n = 0;
  for (const auto& s : sources_) n += s.dropped();
  return n;
}

int TelemetryPublisher::handle_incoming(int max_messages) {
  int n = 0;
  while (n < max_messages && lcm_.handleTimeout(0) > 0) ++n;
  return n;
}

void TelemetryPublisher::publish_receive_status(const std::string& process) {
  const std::vector<ReceiveStats::Row> rows = receive_stats_.snapshot();
  if (rows.empty()) return;
  vitreo_lcm::receive_status_t m;
  m.utime_us = wall_time_us();
  m.process = process;
  m.n = static_cast<std::int16_t>(std::min<std::size_t>(rows.size(), 256));
  for (std::size_t i = 0; i < static_cast<std::size_t>(m.n); ++i) {
    m.channel.push_back(rows[i].channel);
    m.received.push_back(static_cast<std::int64_t>(rows[i].received));
    m.rejected.push_back(static_cast<std::int64_t>(rows[i].rejected));
    m.handler_errors.push_back(static_cast<std::int64_t>(rows[i].handler_errors));
    m.last_error.push_back(rows[i].last_error);
  }
  if (lcm_.publish(kChanReceiveStatus, &m) == 0) {
    ++published_;
  } else {
    ++publish_errors_;
  }
}

std::size_t TelemetryPublisher::pump() {
  std::size_t n = 0;
  TelemetryItem item;
  for (auto& s : sources_) {
    // Bounded per call so one busy source cannot starve the others or the command channel.
    std::size_t budget = s.ring_.capacity();
    while (budget-- > 0 && s.ring_.try_pop(item)) {
      publish_item(item);
      ++n;
    }
  }
  return n;
}

namespace {
template <class Msg>
int publish(lcm::LCM& lc, const char* chan, const Msg& m) {
  return lc.publish(chan, &m);
}
}  // namespace

void TelemetryPublisher::publish_item(const TelemetryItem& item) {
  const std::int64_t now = wall_time_us();
  int rc = 0;
  std::visit(
      [&](const auto& v) {
        using T = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<T, InstrumentState>) {
          vitreo_lcm::instrument_state_t m;
          m.utime_us = now;
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
          rc = publish(lcm_, kChanInstrumentState, m);
        } else if constexpr (std::is_same_v<T, Event>) {
          vitreo_lcm::event_t m;
          m.utime_us = now;
          m.step = v.step;
          m.t_s = v.t_s;
          m.kind = static_cast<std::int8_t>(v.kind);
          m.instrument_id = v.instrument_id;
          m.tissue_id = v.tissue_id;
          for (int i = 0; i < 3; ++i) m.position_mm[i] = v.position_mm[i];
          m.magnitude = v.magnitude;
          m.what = text(v.what);
          rc = publish(lcm_, kChanEvent, m);
        } else if constexpr (std::is_same_v<T, PhysicsTiming>) {
          vitreo_lcm::physics_timing_t m;
          m.utime_us = now;
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
          m.telemetry_dropped = static_cast<std::int64_t>(dropped());
          m.paused = v.paused;
          rc = publish(lcm_, kChanPhysicsTiming, m);
        } else if constexpr (std::is_same_v<T, DeviceStatus>) {
          vitreo_lcm::device_status_t m;
          m.utime_us = now;
          m.device_id = v.device_id;
          m.name = text(v.name);
          m.transport = text(v.transport);
          m.state = v.state;
          m.detail = text(v.detail);
          m.frames_rx = v.frames_rx;
          m.frames_tx = v.frames_tx;
          m.bytes_rx = v.bytes_rx;
          m.crc_errors = v.crc_errors;
          m.framing_errors = v.framing_errors;
          m.sequence_gaps = v.sequence_gaps;
          m.heartbeat_misses = v.heartbeat_misses;
          m.reconnects = v.reconnects;
          m.last_sample_age_us = v.last_sample_age_us;
          m.sample_rate_hz = v.sample_rate_hz;
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
          rc = publish(lcm_, kChanDeviceStatus, m);
        } else if constexpr (std::is_same_v<T, Score>) {
          vitreo_lcm::score_t m;
          m.utime_us = now;
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
          rc = publish(lcm_, kChanScore, m);
        } else if constexpr (std::is_same_v<T, Criteria>) {
          vitreo_lcm::criteria_t m;
          m.utime_us = now;
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
          rc = publish(lcm_, kChanCriteria, m);
        } else if constexpr (std::is_same_v<T, Totals>) {
          vitreo_lcm::session_totals_t m;
          m.utime_us = now;
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
          rc = publish(lcm_, kChanTotals, m);
        } else if constexpr (std::is_same_v<T, Controls>) {
          vitreo_lcm::controls_t m;
          m.utime_us = now;
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
          rc = publish(lcm_, kChanControls, m);
        }
      },
      item);
  if (rc == 0) {
    ++published_;
  } else {
    ++publish_errors_;
  }
}

}  // namespace vitreo::telemetry
