// Issue 16 item 5: what a whole session publishes, decoded from the telemetry log (LCM's file
// provider) with lcm-gen's types, checked field by field against what rig/telemetry/lcmtypes/*.lcm
// and CHANNELS.md document — frames, units, directions, names, rates, counters by cause. Where a
// field can be computed another way it is: the instruments' eye-frame pose from the recorded
// fixture-frame tracker samples and the recorded eye rotation (the recording is the same session's,
// read with LCM's own log reader), the device clock offset from the recorded device and host times,
// the events from the totals' counts. One session, 1.5 s of simulated time, on ptys in real time.
#include <gtest/gtest.h>
#include <unistd.h>

#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "core/metrics/score_card.hpp"
#include "rig/session/rig_session.hpp"
#include "rig/session/simulation_model.hpp"
#include "rig/telemetry/channels.hpp"
#include "rig/telemetry/event_keys.hpp"
#include "vitreo_lcm/command_ack_t.hpp"
#include "vitreo_lcm/controls_t.hpp"
#include "vitreo_lcm/criteria_t.hpp"
#include "vitreo_lcm/device_input_t.hpp"
#include "vitreo_lcm/device_status_t.hpp"
#include "vitreo_lcm/event_t.hpp"
#include "vitreo_lcm/instrument_state_t.hpp"
#include "vitreo_lcm/physics_timing_t.hpp"
#include "vitreo_lcm/receive_status_t.hpp"
#include "vitreo_lcm/recording_header_t.hpp"
#include "vitreo_lcm/score_t.hpp"
#include "vitreo_lcm/session_totals_t.hpp"

using namespace vitreo;

namespace {

std::string temp_path(const std::string& name) {
  return (std::filesystem::path(::testing::TempDir()) / ("vitreo-contract-" + std::to_string(::getpid()) + "-" + name)).string();
}

// The forceps (tool 3) in through the working port, closing and pulling, out again; frames of
// another protocol version, of an unknown type and out of range in three windows.
const char* kTracker =
    "device tracker\nrate_hz 1000\nserial 1001\ntool 3\ninstrument 0\n"
    "key 0 -12.5 3.7 6.2 0 0 0 0\nkey 500 -8 0.5 -4.5 0 0 0 0\nkey 1000 -7 -1.5 -3.5 0 0 20 1\n"
    "key 1500 -12.5 3.7 6.2 0 0 0 0\n"
    "fault 700 40 version\nfault 900 40 unknown\nfault 1100 40 range\n";
const char* kPedals = "device pedals\nrate_hz 500\nserial 2001\nkey 0 0 0 0\nkey 400 0.7 0.2 0\nkey 1200 0 0 0\n";
// The eye turns 6° and 3° in the fixture within the first second: the eye frame and the fixture's part.
const char* kEyeball = "device eyeball\nrate_hz 250\nserial 3001\nclock_offset_ms 1500\nkey 0 0 0 0 0 0\nkey 600 6 -3 4 0 2\n";

struct Log {
  std::map<std::string, std::vector<std::vector<std::uint8_t>>> by_channel;
  std::vector<std::int64_t> timestamps;
  template <class T>
  std::vector<T> decoded(const std::string& channel) const {
    std::vector<T> out;
    auto it = by_channel.find(channel);
    if (it == by_channel.end()) return out;
    for (const auto& bytes : it->second) {
      T m;
      EXPECT_EQ(m.decode(bytes.data(), 0, static_cast<int>(bytes.size())), static_cast<int>(bytes.size())) << channel;
      out.push_back(m);
    }
    return out;
  }
};

Log read_log(const std::string& path) {
  Log log;
  lcm::LogFile f(path, "r");
  EXPECT_TRUE(f.good()) << path;
  for (const lcm::LogEvent* ev = f.readNextEvent(); ev != nullptr; ev = f.readNextEvent()) {
    const auto* d = static_cast<const std::uint8_t*>(ev->data);
    log.by_channel[ev->channel].emplace_back(d, d + ev->datalen);
    log.timestamps.push_back(ev->timestamp);
  }
  return log;
}

struct Fixture {
  rig::SessionConfig config;
  rig::SessionSummary summary;
  std::string echoed;
  Log telemetry, recording;
};

// One session for every test below (it takes a few seconds; they only read what it left).
const Fixture& session() {
  static Fixture* f = [] {
    auto* x = new Fixture;
    rig::SessionConfig& c = x->config;
    c.model.cases.push_back(scene_io::read_case_text(std::string(VITREO_SOURCE_DIR) + "/scenes/exercise_pull_tissue.toml"));
    c.model.load.retina_vertices = 1500;
    c.model.load.texture_size_px = 128;
    c.model.load.cache_dir = (std::filesystem::path(::testing::TempDir()) / "vitreo-session-cache").string();
    c.steps = 1500;
    // Lockstep: the hub's clocks (sample age, stale and lost timeouts, latency) run on the simulated
    // clock, so what the devices report does not depend on how loaded the machine is (in real time
    // an ASan build on two busy cores starved the readers past the lost timeout).
    c.device_mode = rig::HubMode::lockstep;
    c.lcm_url = "file://" + temp_path("telemetry.lcmlog") + "?mode=w";
    c.record_path = temp_path("session.lcmlog");
    c.devices = {{"tracker-0", rig::DeviceRole::tracker, "sim:tracker?transport=pty&link=" + temp_path("tracker"), 1, 0, 0, 0, kTracker},
                 {"pedals", rig::DeviceRole::pedals, "sim:pedals?transport=pty&link=" + temp_path("pedals"), 2, 0, 0, 0, kPedals},
                 {"eyeball", rig::DeviceRole::eyeball, "sim:eyeball?transport=pty&link=" + temp_path("eyeball"), 3, 0, 0, 0, kEyeball}};
    // Terminal commands, each sent once the one before was acknowledged: a second PAUSE right
    // after the first one's acknowledgement must be refused.
    int fds[2];
    EXPECT_EQ(::pipe(fds), 0);
    const std::string typed = "pause\npause\nresume\nz 2.5\n";
    EXPECT_EQ(::write(fds[1], typed.data(), typed.size()), static_cast<ssize_t>(typed.size()));
    ::close(fds[1]);
    c.command_fd = fds[0];
    std::FILE* echo = std::tmpfile();
    c.command_echo = echo;
    x->summary = rig::run_session(c);
    ::close(fds[0]);
    std::rewind(echo);
    char buf[512];
    while (std::fgets(buf, sizeof buf, echo)) x->echoed += buf;
    std::fclose(echo);
    x->telemetry = read_log(temp_path("telemetry.lcmlog"));
    x->recording = read_log(c.record_path);
    return x;
  }();
  return *f;
}

double norm3(const double* v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

// The last recorded input of a kind consumed at or before `step`.
const vitreo_lcm::device_input_t* last_input(const std::vector<vitreo_lcm::device_input_t>& inputs, int kind, std::int64_t step) {
  const vitreo_lcm::device_input_t* found = nullptr;
  for (const auto& in : inputs) {
    if (in.step > step) break;
    if (in.device_kind == kind) found = &in;
  }
  return found;
}

// The last input of `kind` recorded before `before` (the rig applies them in this order).
const vitreo_lcm::device_input_t* last_input_before(const std::vector<vitreo_lcm::device_input_t>& inputs, int kind,
                                                    const vitreo_lcm::device_input_t* before) {
  const vitreo_lcm::device_input_t* found = nullptr;
  for (const auto& in : inputs) {
    if (&in == before) break;
    if (in.device_kind == kind) found = &in;
  }
  return found;
}

}  // namespace

// instrument_state_t: the eye frame (the picture's), the shaft axis from the tip to the handle, the
// kind's name, the port, the insertion, 250 Hz.
TEST(TelemetryContract, InstrumentStateIsInTheEyeFrameWithTheShaftTowardTheHandle) {
  const Fixture& f = session();
  const auto states = f.telemetry.decoded<vitreo_lcm::instrument_state_t>(telemetry::kChanInstrumentState);
  const auto inputs = f.recording.decoded<vitreo_lcm::device_input_t>(telemetry::kChanRecInput);
  ASSERT_GT(states.size(), 200u);
  // The port the tracker's shaft pivots in, in the eye frame (the case as the session built it).
  rig::SimulationModel model(f.config.model);
  const core::Vec3 port = model.current_case().tracker_ports[rig::kToolTracker].position_mm;
  const int eye_port = model.current_case().tracker_port_ids[rig::kToolTracker];
  // While paused the simulation does not step: its instruments stay where it last placed them.
  std::vector<std::pair<std::int64_t, std::int64_t>> paused;
  for (const auto& in : inputs) {
    if (in.device_kind != 6) continue;
    if (in.values[0] == 3.0) paused.emplace_back(in.step, INT64_MAX);
    if (in.values[0] == 4.0 && !paused.empty()) paused.back().second = in.step;
  }
  ASSERT_EQ(paused.size(), 1u) << "one pause, then a resume";
  std::size_t checked_turned = 0, inserted = 0;
  for (const auto& s : states) {
    SCOPED_TRACE("step " + std::to_string(s.step));
    if (s.step >= paused[0].first && s.step < paused[0].second) continue;
    EXPECT_EQ(s.step % 4, 0) << "every 4th step (250 Hz)";
    EXPECT_DOUBLE_EQ(s.t_s, static_cast<double>(s.step) * 1e-3);
    EXPECT_EQ(s.instrument_id, 0) << "the working hand; no light-pipe tracker in this rig";
    EXPECT_EQ(s.kind, "forceps") << "the handpiece's tool 3, by core's name";
    EXPECT_NEAR(norm3(s.shaft_axis), 1.0, 1e-9);
    EXPECT_FALSE(s.frozen);
    EXPECT_GE(s.retina_force_un, 0.0);
    EXPECT_TRUE(s.actuation >= 0.0 && s.actuation <= 1.0);
    EXPECT_TRUE(s.port_id == -1 || s.port_id == eye_port) << int{s.port_id};
    if (s.port_id == -1) {
      EXPECT_EQ(s.insertion_mm, 0.0);
    }
    // Independently: the recorded fixture-frame tip, turned by the recorded eye rotation.
    const auto* tracker = last_input(inputs, 1, s.step);
    const auto* eye = last_input(inputs, 2, s.step);
    ASSERT_NE(tracker, nullptr);
    const core::Vec3 tip_fixture(tracker->values[0], tracker->values[1], tracker->values[2]);
    const core::Quat q = eye ? core::Quat(eye->values[0], eye->values[1], eye->values[2], eye->values[3]).normalized()
                             : core::Quat::Identity();
    const core::Vec3 tip_eye = q.conjugate() * tip_fixture;
    const core::Vec3 tip(s.tip_mm[0], s.tip_mm[1], s.tip_mm[2]);
    EXPECT_DOUBLE_EQ(s.actuation, tracker->values[7]);
    // Before the fixture's first sample the core turns the eye a little itself (the ports' push).
    if (!eye) continue;
    EXPECT_LT((tip - tip_eye).norm(), 1e-6) << "eye frame: " << tip.transpose() << " expected " << tip_eye.transpose();
    if (s.port_id >= 0) {
      ++inserted;
      // Through the port: the rig maps the tracker's sample through the port where the eye, as the
      // fixture last read it before that sample, carries it (q_then · port in the fixture frame),
      // and the core turns the shaft into the eye frame with the step's rotation q.
      const auto* eye_then = last_input_before(inputs, 2, tracker);
      const core::Quat q_then = eye_then ? core::Quat(eye_then->values[0], eye_then->values[1], eye_then->values[2], eye_then->values[3]).normalized()
                                         : core::Quat::Identity();
      const core::Vec3 to_handle = q.conjugate() * (q_then * port - tip_fixture).normalized();
      const core::Vec3 axis(s.shaft_axis[0], s.shaft_axis[1], s.shaft_axis[2]);
      EXPECT_LT((axis - to_handle).norm(), 1e-6) << "tip to handle: " << axis.transpose() << " expected " << to_handle.transpose();
      // The insertion: from the port to the tip along the shaft, with the eye's port where it is.
      EXPECT_NEAR(s.insertion_mm, (tip - port).dot(-axis), 1e-6);
      EXPECT_GT(s.insertion_mm, 0.0);
    }
    if (std::abs(q.w()) < 0.999) {
      ++checked_turned;
      EXPECT_GT((tip - tip_fixture).norm(), 0.2) << "the eye has turned: the fixture frame is not the eye frame";
    }
  }
  EXPECT_GT(checked_turned, 50u) << "the eye turned while the instrument was tracked";
  EXPECT_GT(inserted, 50u) << "the forceps went in";
  // 250 Hz: one state per 4 steps from the tracker's first sample to the end.
  const std::int64_t first = states.front().step;
  EXPECT_EQ(static_cast<std::int64_t>(states.size()), (1500 - first + 3) / 4);
}

// device_status_t: every field against its documentation, the counters by cause against the
// faults the tracker's script injected, the clock offset against the recorded timestamps.
TEST(TelemetryContract, DeviceStatusFillsEveryFieldAndCountsRejectionsByCause) {
  const Fixture& f = session();
  const auto statuses = f.telemetry.decoded<vitreo_lcm::device_status_t>(telemetry::kChanDeviceStatus);
  const auto inputs = f.recording.decoded<vitreo_lcm::device_input_t>(telemetry::kChanRecInput);
  using M = vitreo_lcm::device_status_t;
  const std::map<std::string, std::pair<int, int>> expected = {{"tracker-0", {1, 1000}}, {"pedals", {2, 500}}, {"eyeball", {3, 250}}};
  std::map<std::string, std::vector<M>> per;
  for (const auto& s : statuses) per[s.name].push_back(s);
  ASSERT_EQ(per.size(), 3u);
  for (std::size_t i = 0; i < f.config.devices.size(); ++i) {
    const auto& spec = f.config.devices[i];
    SCOPED_TRACE(spec.name);
    const auto& all = per[spec.name];
    ASSERT_GE(all.size(), 12u) << "10 Hz over 1.5 s";
    const int id = expected.at(spec.name).first;
    for (std::size_t k = 0; k < all.size(); ++k) {
      const M& s = all[k];
      EXPECT_EQ(s.device_id, id);
      EXPECT_EQ(s.transport.rfind("sim:", 0), 0u) << "the device's URI: " << s.transport;
      EXPECT_TRUE(s.state >= M::STATE_INACTIVE && s.state <= M::STATE_LOST) << int{s.state};
      EXPECT_NE(int{s.state}, int{M::STATE_ERROR}) << "no device here is refused: " << s.detail;
      EXPECT_EQ(s.calibration, "") << "this rig runs uncalibrated (the calibration tests check a calibrated one)";
      // detail: empty exactly when the device streams without a fault.
      const bool healthy = s.state == M::STATE_ACTIVE && !s.stuck && s.detail.rfind("stale", 0) != 0;
      if (s.state == M::STATE_ACTIVE && !s.stuck && s.last_sample_age_us < 20'000) {
        EXPECT_EQ(s.detail, "") << "streaming";
      }
      if (s.state == M::STATE_LOST) {
        EXPECT_NE(s.detail, "") << "LOST says why";
      }
      if (s.state == M::STATE_INACTIVE) {
        EXPECT_EQ(s.detail, "");
      }
      if (k > 0) {  // cumulative counters never fall
        const M& p = all[k - 1];
        EXPECT_GE(s.frames_rx, p.frames_rx);
        EXPECT_GE(s.frames_tx, p.frames_tx);
        EXPECT_GE(s.bytes_rx, p.bytes_rx);
        EXPECT_GE(s.utime_us, p.utime_us);
        EXPECT_GE(s.t_s, p.t_s) << "session time runs forward";
      }
      // t_s: in lockstep the granted step's time, k · 1 ms, within the session's 1500 steps.
      EXPECT_GE(s.t_s, 0.0);
      EXPECT_LT(s.t_s, 1.5);
      EXPECT_NEAR(s.t_s * 1000.0, std::round(s.t_s * 1000.0), 1e-6) << "a whole step: " << s.t_s;
      if (healthy) {
        // Younger than the lost timeout (the stale one, 20 ms, is the session's verdict at its own
        // poll, which on a loaded machine may come a little before this publish).
        EXPECT_GE(s.last_sample_age_us, 0);
        EXPECT_LT(s.last_sample_age_us, 250'000);
        EXPECT_EQ(s.configured_rate_hz, expected.at(spec.name).second) << "PROTOCOL.md §7's rate";
        EXPECT_LE(s.latency_p50_us, s.latency_p99_us);
      }
      if (s.state == M::STATE_INACTIVE && s.frames_rx == 0) {
        EXPECT_EQ(s.last_sample_age_us, -1);
      }
    }
    const M& last = all.back();
    EXPECT_GT(last.t_s, 1.35) << "10 Hz of session time to the end";
    EXPECT_EQ(int{last.state}, int{M::STATE_ACTIVE});
    EXPECT_GE(last.frames_tx, 4) << "identify, rate, streaming, time sync at least";
    EXPECT_GT(last.frames_rx, 0);
    EXPECT_GT(last.bytes_rx, last.frames_rx);
    // In lockstep a sample is due at the step its device time names, so its latency on the
    // simulated clock is 0 to a step; the field is the measured p99, never below the p50.
    EXPECT_GE(last.latency_p50_us, 0.0f);
    EXPECT_GE(last.latency_p99_us, last.latency_p50_us);
    EXPECT_LT(last.latency_p99_us, 500'000.0f) << "a loaded machine delays samples by tens of ms, not seconds";
    // The rate over the last second, against the rate configured (a loaded machine delays samples,
    // it does not lose them: a pty buffers).
    EXPECT_NEAR(last.sample_rate_hz, static_cast<float>(expected.at(spec.name).second), 0.35f * static_cast<float>(expected.at(spec.name).second));
    // Device clock − host clock: the recorded samples of this device carry both, received times
    // being the later by the latency.
    std::vector<double> offsets;
    for (const auto& in : inputs)
      if (in.device_id == id && in.device_kind >= 1 && in.device_kind <= 3) offsets.push_back(static_cast<double>(in.device_time_us - in.host_time_us));
    ASSERT_FALSE(offsets.empty());
    std::nth_element(offsets.begin(), offsets.begin() + static_cast<std::ptrdiff_t>(offsets.size() / 2), offsets.end());
    const double median = offsets[offsets.size() / 2];
    // float32 at ~1e11 µs is good to ~16 ms; the sign is the contract.
    EXPECT_NEAR(last.clock_offset_us, median, 25'000.0 + std::abs(median) * 1e-6) << "device − host";
    EXPECT_EQ(last.identity_rejected, 0);
    EXPECT_EQ(last.protocol_rejected, 0);
    EXPECT_EQ(last.length_rejected, 0);
    // A reader starved past the link's lost timeout (20 periods: 80 ms at the eyeball's 250 Hz, seen
    // under ASan on a loaded 2-core machine) reconnects; on a healthy link nothing reconnects.
    if (last.reader_stalls == 0) {
      EXPECT_EQ(last.reconnects, 0) << "no reader stall, yet the link was lost";
    }
    EXPECT_FALSE(last.stuck);
    EXPECT_EQ(last.timestamp_jumps, 0);
    if (last.reader_stalls == 0) {  // a starved reader finds framing errors and gaps on a healthy link
      EXPECT_EQ(last.crc_errors, 0);
      EXPECT_EQ(last.framing_errors, 0);
      // The tracker's version and unknown-type windows can each swallow one heartbeat.
      EXPECT_LE(last.heartbeat_misses, spec.name == "tracker-0" ? 2 : 0);
    }
    if (spec.name == "tracker-0") {
      // 40 ms of each fault at 1 kHz: samples (and a heartbeat) refused, each under its own cause.
      EXPECT_GE(last.version_rejected, 30);
      EXPECT_GE(last.unknown_type_rejected, 30);
      EXPECT_GE(last.range_rejected, 30);
      EXPECT_LE(last.version_rejected, 50);
      EXPECT_LE(last.unknown_type_rejected, 50);
      EXPECT_LE(last.range_rejected, 50);
    } else {
      EXPECT_EQ(last.version_rejected, 0);
      EXPECT_EQ(last.unknown_type_rejected, 0);
      EXPECT_EQ(last.range_rejected, 0);
    }
  }
}

// physics_timing_t: 10 Hz, each message its own window of steps.
TEST(TelemetryContract, PhysicsTimingIsTenHertzOverItsOwnWindow) {
  const Fixture& f = session();
  const auto timing = f.telemetry.decoded<vitreo_lcm::physics_timing_t>(telemetry::kChanPhysicsTiming);
  ASSERT_EQ(timing.size(), 15u) << "1500 steps at 1 kHz: 1.5 s at 10 Hz";
  std::int64_t steps = 0;
  for (std::size_t k = 0; k < timing.size(); ++k) {
    const auto& t = timing[k];
    EXPECT_EQ(t.step, static_cast<std::int64_t>(100 * k + 99));
    EXPECT_EQ(t.period_us, 1000);
    // The window: the steps since the last report (the reporting step's own time is the next one's).
    EXPECT_EQ(t.window_steps, k == 0 ? 99 : 100);
    steps += t.window_steps;
    EXPECT_LE(t.step_p50_us, t.step_p99_us);
    EXPECT_LE(t.step_p99_us, t.step_max_us);
    EXPECT_LE(t.jitter_p99_us, t.jitter_max_us);
    EXPECT_GT(t.step_p50_us, 0.0f);
    if (k > 0) {
      EXPECT_GE(t.overruns, timing[k - 1].overruns) << "cumulative";
      EXPECT_GE(t.late_steps, timing[k - 1].late_steps);
      EXPECT_GE(t.dropped_steps, timing[k - 1].dropped_steps);
      EXPECT_GE(t.telemetry_dropped, timing[k - 1].telemetry_dropped);
      EXPECT_GT(t.utime_us, timing[k - 1].utime_us);
    }
  }
  EXPECT_EQ(steps, 1499);
  // Each window's maximum is within the session's (the summary's, over every step).
  for (const auto& t : timing) EXPECT_LE(t.step_max_us, static_cast<float>(f.summary.loop.step_max_ns) * 1e-3f + 1.0f);
}

// event_t: one per occurrence, named by the simulation's keys, counted as the totals count them.
TEST(TelemetryContract, EventsAreOnePerOccurrenceAndAgreeWithTheTotals) {
  const Fixture& f = session();
  const auto events = f.telemetry.decoded<vitreo_lcm::event_t>(telemetry::kChanEvent);
  const auto totals = f.telemetry.decoded<vitreo_lcm::session_totals_t>(telemetry::kChanTotals);
  ASSERT_FALSE(totals.empty());
  const auto& final_totals = totals.back();
  ASSERT_TRUE(final_totals.final_score);
  std::set<std::string> keys;
  for (std::size_t k = 0; k < core::kInstrumentEventKinds; ++k) keys.insert(telemetry::event_key(static_cast<core::InstrumentEventKind>(k)));
  std::map<std::string, int> count;
  std::set<std::tuple<std::int64_t, int, double, double, double, double>> seen;
  int attachment_broken = 0;
  for (const auto& e : events) {
    SCOPED_TRACE(e.what);
    EXPECT_DOUBLE_EQ(e.t_s, static_cast<double>(e.step) * 1e-3);
    EXPECT_TRUE(e.kind >= vitreo_lcm::event_t::KIND_CONTACT && e.kind <= vitreo_lcm::event_t::KIND_ATTACHMENT_BROKEN);
    EXPECT_TRUE(keys.count(e.what) || e.what == "tissue_tear" || e.what == "tissue_grip_broken" || e.what == "tissue_attachment_broken");
    EXPECT_TRUE(e.instrument_id >= -1 && e.instrument_id <= 1) << "a hand, as instrument_state_t's";
    if (e.what == "grasp" || e.what == "grasp_lost" || e.what == "release" || e.what == "wall_contact" || e.what == "excessive_retina_force") {
      EXPECT_NE(e.instrument_id, -1) << "an instrument event names its hand";
    }
    EXPECT_TRUE(seen.insert({e.step, e.kind, e.position_mm[0], e.position_mm[1], e.position_mm[2], e.magnitude}).second)
        << "published twice at step " << e.step;
    ++count[e.what];
    if (e.kind == vitreo_lcm::event_t::KIND_ATTACHMENT_BROKEN) {
      ++attachment_broken;
      EXPECT_EQ(e.what, "attachment_broken");
      EXPECT_GE(e.tissue_id, 0) << "the surface whose attachment broke";
    }
  }
  ASSERT_EQ(final_totals.n_kinds, static_cast<int>(core::kInstrumentEventKinds));
  for (int k = 0; k < final_totals.n_kinds; ++k) {
    EXPECT_TRUE(keys.count(final_totals.event_kind[static_cast<std::size_t>(k)]));
    EXPECT_EQ(count[final_totals.event_kind[static_cast<std::size_t>(k)]], final_totals.event_count[static_cast<std::size_t>(k)])
        << final_totals.event_kind[static_cast<std::size_t>(k)] << ": the events published, the totals counted";
  }
  // Every broken attachment the tissue reported goes out once.
  EXPECT_EQ(attachment_broken, static_cast<int>(f.summary.attachments_broken));
  std::printf("events: %zu published, %d attachments broken:", events.size(), attachment_broken);
  for (const auto& [what, n] : count) std::printf(" %s %d", what.c_str(), n);
  std::printf("\n");
}

// score_t, criteria_t, session_totals_t, controls_t, command_ack_t, receive_status_t.
TEST(TelemetryContract, ScoresControlsAcksAndReceiveStatusAsDocumented) {
  const Fixture& f = session();
  const auto scores = f.telemetry.decoded<vitreo_lcm::score_t>(telemetry::kChanScore);
  const auto criteria = f.telemetry.decoded<vitreo_lcm::criteria_t>(telemetry::kChanCriteria);
  const auto totals = f.telemetry.decoded<vitreo_lcm::session_totals_t>(telemetry::kChanTotals);
  ASSERT_EQ(scores.size(), criteria.size());
  ASSERT_EQ(scores.size(), totals.size());
  ASSERT_GE(scores.size(), 2u) << "at 1000 steps and with the last";
  // The case file's pass score, read here from its text (its [proficiency] table's one line).
  double pass_score = -1;
  {
    std::ifstream in(std::string(VITREO_SOURCE_DIR) + "/scenes/exercise_pull_tissue.toml");
    for (std::string l; std::getline(in, l);) {
      if (l.rfind("pass_score", 0) == 0) pass_score = std::stod(l.substr(l.find('=') + 1));
    }
  }
  ASSERT_GT(pass_score, 0) << "the case file names its pass score";
  for (std::size_t k = 0; k < scores.size(); ++k) {
    EXPECT_EQ(scores[k].case_id, "exercise_pull_tissue");
    EXPECT_EQ(scores[k].pass_score, pass_score);
    EXPECT_EQ(criteria[k].step, scores[k].step);
    EXPECT_EQ(totals[k].step, scores[k].step);
    EXPECT_EQ(criteria[k].final_score, scores[k].final_score);
    EXPECT_TRUE(scores[k].total >= 0 && scores[k].total <= 100);
    ASSERT_EQ(scores[k].n, static_cast<int>(scores[k].name.size()));
    for (double v : scores[k].value) EXPECT_TRUE(v >= 0 && v <= 100);
    for (double p : criteria[k].progress) EXPECT_TRUE(p >= 0 && p <= 1);
    EXPECT_EQ(totals[k].formula_version, core::kScoreFormulaVersion);
    for (const auto& kind : totals[k].instrument_kind) {
      bool known = false;
      for (int i = 0; i <= static_cast<int>(core::InstrumentKind::kDrainageNeedle); ++i)
        known = known || kind == core::to_string(static_cast<core::InstrumentKind>(i));
      EXPECT_TRUE(known) << "'" << kind << "' is core's name of an instrument kind";
    }
  }
  EXPECT_TRUE(scores.back().final_score);
  EXPECT_EQ(scores.back().step, 1499);

  const auto controls = f.telemetry.decoded<vitreo_lcm::controls_t>(telemetry::kChanControls);
  ASSERT_EQ(controls.size(), 375u) << "every 4th step of 1500";
  double max_travel = 0.0, last_dose = 0.0;
  for (const auto& c : controls) {
    EXPECT_EQ(c.step % 4, 0);
    EXPECT_DOUBLE_EQ(c.t_s, static_cast<double>(c.step) * 1e-3);
    EXPECT_GE(c.vacuum_mmhg, 0.0);
    EXPECT_GE(c.cut_rate_cpm, 0.0);
    EXPECT_TRUE(c.light_level >= 0 && c.light_level <= 1);
    EXPECT_GT(c.zoom, 0.0);
    EXPECT_EQ(c.laser_power_mw, f.config.model.laser.power_mw);
    EXPECT_EQ(c.laser_duration_ms, f.config.model.laser.duration_ms);
    // The travel that set the vacuum: the default mapping's vacuum axis 0 over 650 mmHg
    // (rig/input/controls.hpp), on pedals without a calibration.
    for (int a = 0; a < 4; ++a) {
      EXPECT_TRUE(c.vitrectomy_pedal_travel[a] >= 0 && c.vitrectomy_pedal_travel[a] <= 1);
      EXPECT_TRUE(c.microscope_pedal_travel[a] >= 0 && c.microscope_pedal_travel[a] <= 1);
    }
    EXPECT_NEAR(c.vacuum_mmhg, 650.0 * c.vitrectomy_pedal_travel[0], 1e-9);
    max_travel = std::max(max_travel, c.vitrectomy_pedal_travel[0]);
    EXPECT_GE(c.macula_light_dose_j_cm2, last_dose) << "a dose only accumulates";
    last_dose = c.macula_light_dose_j_cm2;
    EXPECT_EQ(c.light_dose_limit_j_cm2, 10.0) << "core InstrumentSceneOptions' default limit";
  }
  // The script's pedal rises to 0.7 of its travel at 0.4 s and back to 0 at 1.2 s (sampled at 250 Hz,
  // carried in 16 bits).
  EXPECT_GT(max_travel, 0.6);
  EXPECT_LE(max_travel, 0.7 + 1e-4);

  // The terminal's commands: pause accepted, a second pause right after its ack refused, resume, zoom.
  const auto acks = f.telemetry.decoded<vitreo_lcm::command_ack_t>(telemetry::kChanCommandAck);
  ASSERT_EQ(acks.size(), 4u) << f.echoed;
  const std::vector<int> codes = {3, 3, 4, 9};
  const std::vector<bool> accepted = {true, false, true, true};
  for (std::size_t k = 0; k < acks.size(); ++k) {
    EXPECT_EQ(acks[k].source, "terminal");
    EXPECT_EQ(acks[k].command, codes[k]);
    EXPECT_EQ(acks[k].accepted != 0, accepted[k]) << k << ": " << acks[k].reason;
    if (k > 0) {
      EXPECT_GT(acks[k].seq, acks[k - 1].seq);
    }
    if (!accepted[k]) {
      EXPECT_NE(acks[k].reason, "");
    }
  }

  const auto received = f.telemetry.decoded<vitreo_lcm::receive_status_t>(telemetry::kChanReceiveStatus);
  ASSERT_FALSE(received.empty());
  for (const auto& r : received) {
    EXPECT_EQ(r.process, "vitreo");
    ASSERT_EQ(r.n, static_cast<int>(r.channel.size()));
    EXPECT_EQ(r.channel, std::vector<std::string>{telemetry::kChanCommand});
  }
}

// The recording: log timestamps never step back and pace the session (lcm-logplayer plays it at
// the pace physics consumed the inputs); commands carry the time physics took them; the header
// names the software.
TEST(TelemetryContract, RecordingLogTimesAreMonotonicAndPaceTheSession) {
  const Fixture& f = session();
  const auto& ts = f.recording.timestamps;
  ASSERT_GT(ts.size(), 100u);
  for (std::size_t k = 1; k < ts.size(); ++k) ASSERT_GE(ts[k], ts[k - 1]) << "event " << k << " steps back";
  EXPECT_NEAR(static_cast<double>(ts.back() - ts.front()), 1.5e6, 2e3) << "1500 steps of 1 ms";
  const auto header = f.recording.decoded<vitreo_lcm::recording_header_t>(telemetry::kChanRecHeader);
  ASSERT_EQ(header.size(), 1u);
  EXPECT_EQ(header[0].software_version.rfind("vitreo ", 0), 0u) << "'" << header[0].software_version << "'";
  const auto inputs = f.recording.decoded<vitreo_lcm::device_input_t>(telemetry::kChanRecInput);
  // What no device sent is stamped when physics took it, on the devices' clock: after every sample
  // an earlier step consumed (each was received before its step), and never 0.
  int commands = 0;
  for (const auto& in : inputs) {
    if (in.device_kind < 5) continue;
    ++commands;
    EXPECT_GT(in.host_time_us, 0);
    for (const auto& sample : inputs) {
      if (sample.device_kind > 4 || sample.step >= in.step) continue;
      EXPECT_GE(in.host_time_us, sample.host_time_us) << "kind " << int{in.device_kind} << " at step " << in.step;
    }
  }
  EXPECT_EQ(commands, 4) << "pause, resume, zoom, the session's end";
}
