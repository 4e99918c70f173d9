#include "rig/session/rig_session.hpp"

#include <spdlog/spdlog.h>

#include <cmath>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <algorithm>
#include <array>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <optional>
#include <thread>

#include "core/scene/snapshot.hpp"
#include "rig/runtime/clock.hpp"
#include "rig/runtime/thread_harness.hpp"
#include "rig/telemetry/commands.hpp"
#include "rig/telemetry/publisher.hpp"
#include "rig/telemetry/recording.hpp"
#include "rig/telemetry/telemetry_mapping.hpp"
#include "rig/telemetry/terminal_commands.hpp"
#include "rig/session/case_switcher.hpp"
#include "rig/session/frame_source.hpp"
#include "rig/session/key_moments.hpp"
#include "rig/session/snapshot_writer.hpp"
#include "vitreo/render/render_thread.hpp"

namespace vitreo::rig {

namespace {

// A paused step's events: none (the lists keep the last step's until the world steps again).
const std::vector<core::InstrumentEvent> kNoInstrumentEvents;
const std::vector<core::TissueEvent> kNoTissueEvents;

// The simulated instrument a hand (tracker) drives now: the working hand's selected tool, the other
// hand's light pipe or second-hand tool; -1 when the case has none for it.
int driven_instrument(const SimulationModel& model, std::size_t tracker) {
  const int sim = tracker == static_cast<std::size_t>(kToolTracker)         ? model.selected_tool()
                  : tracker == static_cast<std::size_t>(kSecondHandTracker) ? model.current_case().second_hand
                                                                            : -1;
  return sim >= 0 && static_cast<std::uint32_t>(sim) < model.simulation().instrument_count() ? sim : -1;
}

// The hand (tracker) a simulated instrument belongs to: the light pipe or second-hand tool is the other
// hand's, every other tool the working hand's (only the one in the hand is inside the eye).
int hand_of(const SimulationModel& model, std::uint32_t instrument) {
  return static_cast<int>(instrument) == model.current_case().second_hand ? kSecondHandTracker : kToolTracker;
}

// The step's telemetry from the model's state (rig/telemetry/telemetry_mapping.hpp says what each
// field is): events as they happen, instrument states and controls at 250 Hz.
// `stepped`: the world stepped (not paused), so its events are this step's.
void push_step_telemetry(const SimulationModel& model, bool stepped, std::uint64_t k, std::int64_t step, double t_s,
                         telemetry::TelemetrySource& out) {
  telemetry::step_event_items(stepped ? model.world().events() : kNoTissueEvents,
                              stepped ? model.simulation().events() : kNoInstrumentEvents, step, t_s,
                              [&](std::uint32_t instrument) { return hand_of(model, instrument); },
                              [&](const telemetry::Event& e) { out.push(e); });
  if (k % 4 != 0) return;  // instrument states and controls at 250 Hz (CHANNELS.md)
  const auto& slots = model.instruments();
  for (std::size_t i = 0; i < slots.size(); ++i) {
    const int sim = driven_instrument(model, i);
    if (!slots[i].present || sim < 0) continue;
    const core::InstrumentState& st = model.simulation().instrument(static_cast<std::uint32_t>(sim));
    const telemetry::Hand hand{static_cast<int>(i), model.current_case().tracker_port_ids[i], core::to_string(st.description.kind),
                               slots[i].frozen};
    out.push(telemetry::instrument_state_item(hand, st, step, t_s));
  }
  const SurgicalControls& c = model.controls();
  out.push(telemetry::controls_item({c.vacuum_mmhg, c.cut_rate_cpm, c.reflux, c.laser_fire, c.pick_out, c.light_level, c.zoom,
                                     model.laser().power_mw, model.laser().duration_ms, c.vitrectomy_travel, c.microscope_travel,
                                     model.simulation().light().macula_dose_j_cm2,
                                     model.simulation().options().light_dose_limit_j_cm2},
                                    step, t_s));
}

// The current case's score card, criteria and totals (score() scans the world: call at a low rate).
void push_scores(SimulationModel& model, std::int64_t step, bool final_score, telemetry::TelemetrySource& out) {
  const std::string_view case_id = model.scene().description.name;
  out.push(telemetry::score_item(model.metrics().score(), case_id, step, final_score, model.scene().description.pass_score));
  out.push(telemetry::criteria_item(model.metrics().criteria(), case_id, step, final_score));  // what score() just measured
  out.push(telemetry::totals_item(model.metrics(), case_id, step, final_score));
}

// Recorded at the last step so a replay knows how long the session ran.
telemetry::RecordedInput session_end_marker(std::uint64_t steps) {
  telemetry::RecordedInput in;
  in.what = telemetry::SessionEnd{static_cast<std::int64_t>(steps)};
  return in;
}

telemetry::RecordedInput case_input(int index) {
  telemetry::RecordedInput in;
  in.what = telemetry::CaseSwitch{index};
  return in;
}

std::string hex(std::uint64_t v) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
  return buf;
}

telemetry::RecordedInput command_input(const telemetry::AcceptedCommand& cmd) {
  telemetry::RecordedInput in;
  in.sequence = cmd.seq;
  telemetry::OperatorCommand c;
  c.code = static_cast<std::int8_t>(cmd.code);
  c.value = cmd.value;
  if (cmd.code == telemetry::CommandCode::Pan) c.pan_y_mm = std::strtod(cmd.arg, nullptr);  // y travels as text (validated by the server)
  in.what = c;
  return in;
}

// The final score and the case's criteria, for the summaries (live and replay print the same lines).
std::vector<std::string> score_lines(SimulationModel& model) {
  std::vector<std::string> lines;
  const core::ScoreCard& card = model.metrics().score();
  char buf[160];
  std::string cats;
  for (const core::ScoreEntry& e : card.categories) {
    std::snprintf(buf, sizeof buf, "%s%s %.0f", cats.empty() ? "" : ", ", e.name, e.value);
    cats += buf;
  }
  std::snprintf(buf, sizeof buf, "%.0f / 100 (", card.total);
  lines.push_back(buf + cats + ")");
  const double pass = model.scene().description.pass_score;
  // Passing takes the case completed (every criterion met) as well as the score: a high score on a
  // case left unfinished does not pass.
  const bool completed = model.metrics().completed();
  std::snprintf(buf, sizeof buf, "pass score %.0f: %s (%.1f%s)", pass, completed && card.total >= pass ? "passed" : "not passed", card.total,
                completed ? "" : ", the case not completed");
  lines.push_back(buf);
  for (const core::CriterionProgress& c : model.metrics().criteria()) {
    std::snprintf(buf, sizeof buf, "%s%s%s: %.3g (goal %.3g) %s", core::to_string(c.kind), c.target.empty() ? "" : " ",
                  c.target.c_str(), c.value, c.threshold, c.met ? "met" : "not met");
    lines.push_back(buf);
  }
  const core::SessionTotals& t = model.metrics().totals();
  std::snprintf(buf, sizeof buf, "iatrogenic events %u", static_cast<unsigned>(t.iatrogenic_events()));
  std::string kinds;
  using K = core::InstrumentEventKind;
  for (K k : {K::kExcessiveRetinaForce, K::kUnintendedTear, K::kLaserOnDetachedRetina, K::kLightTooClose, K::kLightToxicity,
              K::kInstrumentCollision, K::kLensTouch, K::kWallContact}) {
    if (t.count(k) == 0) continue;
    kinds += (kinds.empty() ? " (" : ", ") + std::string(core::to_string(k)) + " " + std::to_string(t.count(k));
  }
  lines.push_back(buf + kinds + (kinds.empty() ? "" : ")"));
  std::snprintf(buf, sizeof buf, "handling: path %.1f mm, %u retina contacts (%.2f s), peak retina force %.0f uN, %u grasps, %u retina tears",
                t.path_length_mm, static_cast<unsigned>(t.retina_contacts), t.retina_contact_time_s, t.peak_retina_force_un,
                static_cast<unsigned>(t.count(K::kGrasp)), static_cast<unsigned>(t.retina_tears));
  lines.push_back(buf);
  return lines;
}

}  // namespace

SessionSummary run_session(const SessionConfig& config) {
  if (config.model.cases.empty()) throw std::invalid_argument("run_session: no case to run");
  // spdlog's registry (the default logger) is a function-local static inside Debian's libspdlog,
  // which is not built for ThreadSanitizer: when a session thread logged first, the other threads'
  // reads of the logger looked unordered to TSan (its fast path is an atomic it cannot see). It is
  // no race — C++ makes the static's initialisation thread-safe — but creating it here, before any
  // session thread starts, gives it an order TSan can see (thread creation) and keeps the report
  // of a real race readable.
  (void)spdlog::default_logger_raw();
  CaseSwitcher switcher(config.model.cases, config.model.load, config.render);
  // The first case is loaded here, before any thread starts (a bad case stops the session now).
  std::unique_ptr<PreparedCase> first = switcher.load_now(config.model.first_case);
  const std::uint64_t start_hash = first->start_hash;
  SessionSummary summary;
  summary.case_name = first->scene->description.name;
  summary.case_title = first->scene->description.title;
  summary.case_file = config.model.cases[static_cast<std::size_t>(config.model.first_case)].file_name;
  summary.case_from_cache = first->from_cache;
  summary.instruments = describe_instruments(*first);
  summary.laser_at_start = config.model.laser;
  SimulationModel model(config.model, std::move(first));

  telemetry::TelemetryPublisher publisher(telemetry::PublisherConfig{config.lcm_url, 4096});
  telemetry::TelemetrySource& physics_out = publisher.add_source("physics");
  telemetry::TelemetrySource& devices_out = publisher.add_source("devices");
  // Malformed packets on the command channel are counted in the publisher's receive statistics
  // (VITREO_RECEIVE_STATUS) and never reach the server.
  telemetry::CommandServer commands(publisher.lcm(), 64, &publisher.receive_stats().channel(telemetry::kChanCommand));

  std::string snapshot_dir = config.snapshot_dir;
  if (snapshot_dir.empty()) {
    snapshot_dir = config.record_path.empty() ? std::string(".")
                                              : std::filesystem::path(config.record_path).parent_path().string();
    if (snapshot_dir.empty()) snapshot_dir = ".";
  }
  // Twice the first case's state: room for cuts and a larger case without allocating.
  SnapshotWriter snapshots(snapshot_dir, 2 * core::encode_snapshot(model.world(), summary.case_name).size() + (1u << 20));
  commands.set_snapshot_folder(snapshots.folder());

  std::unique_ptr<telemetry::Recorder> recorder;
  if (!config.record_path.empty()) {
    telemetry::RecordingHeader header;
    header.case_id = summary.case_name;
    header.config_name = "vitreo-cases";
    header.config_text = encode_case_list(config.model);
    header.snapshot_ref = summary.case_file;
    header.snapshot_hash = hex(start_hash);
    header.step_period_us = static_cast<std::int32_t>(config.model.dt_s * 1e6);
    recorder = std::make_unique<telemetry::Recorder>(config.record_path, header);
  }

  // Rendering: created first so an EGL failure stops the session before any device starts.
  std::unique_ptr<render::RenderThread> renderer;
  runtime::TripleBuffer<ViewSnapshot> views;
  FrameBuilder frames;
  if (config.render) {
    render::RenderThreadOptions ro;
    ro.render.eye_width = config.eye_width;
    ro.render.eye_height = config.eye_height;
    ro.png_dir = config.png_dir;
    ro.png_every_frames = config.png_every_frames;
    ro.displays = config.displays;
    ro.shm_ring_name = config.frame_ring_name;
    ro.instructor_ring_name = config.instructor_ring_name;
    ro.eyepieces = config.eyepieces;
    renderer = std::make_unique<render::RenderThread>(ro);
  }
  const std::uint64_t view_every = std::max<std::uint64_t>(1, static_cast<std::uint64_t>(1.0 / (config.display_hz * config.model.dt_s)));
  // Frames at the session's key moments (key_moments.hpp), when frames are written: physics takes
  // the picture of the very step into key_view while it is free; the render service hands it to the
  // render thread, which writes it beside the running frames.
  const bool picture_moments = renderer && !config.png_dir.empty();
  KeyMoments moments;
  ViewSnapshot key_view;
  KeyMoment key_moment;               // what key_view shows (written by physics before key_view_ready)
  std::atomic<bool> key_view_ready{false};
  FrameBuilder key_frames;

  std::vector<DeviceSpec> devices = config.devices;
  if (config.adapt_devices) config.adapt_devices(model.current_case(), devices);
  DeviceHub hub(devices, &devices_out, config.device_mode);
  const bool lockstep = config.device_mode == HubMode::lockstep;
  const auto period_us = static_cast<std::uint64_t>(std::llround(config.model.dt_s * 1e6));
  runtime::SteadyClock wall;
  runtime::SimulatedClock unpaced_clock;  // lockstep without pacing: the loop never sleeps
  runtime::HarnessConfig harness_config;
  harness_config.loop.period_ns = static_cast<std::int64_t>(config.model.dt_s * 1e9);
  harness_config.max_steps = config.steps;
  harness_config.physics_realtime = config.realtime;
  runtime::FixedStepLoop* loop = nullptr;        // the harness's loop; set before start()
  std::optional<telemetry::TimingReporter> timing;  // physics timing on the harness's loop; set before start()
  std::unique_ptr<PreparedCase> retiring;        // a replaced case waiting for room in the ring
  // Case switches for the summary: fixed slots written by physics, read after it stopped.
  constexpr std::size_t kMaxSwitchLog = 64;
  std::array<std::pair<std::uint64_t, int>, kMaxSwitchLog> switch_log{};
  std::size_t switches = 0;

  int stopped_by = 0;                              // the signal that ended the session early (physics thread)
  bool ended_at_case_over = false;                 // or the case's end (SessionConfig::end_at_case_over)
  // The step the current case ended at, -1 while it runs (physics writes, the telemetry service
  // announces it once); whether it ended complete or out of time.
  std::atomic<std::int64_t> case_over_step{-1};
  std::atomic<bool> case_over_complete{false};
  std::int64_t case_over_announced = -1;  // telemetry service
  runtime::Clock& physics_clock = lockstep && config.unpaced ? static_cast<runtime::Clock&>(unpaced_clock) : static_cast<runtime::Clock&>(wall);
  runtime::ThreadHarness harness(physics_clock, harness_config, [&](std::uint64_t k, double t_s) {
    const auto step = static_cast<std::int64_t>(k);
    // A stop request (SIGINT/SIGTERM) makes this step the session's last: it is finished, the end
    // marker recorded, and nothing is cut off in the middle.
    const int stop = config.stop ? config.stop->load(std::memory_order_relaxed) : 0;
    const bool case_done = config.end_at_case_over && case_over_step.load(std::memory_order_relaxed) >= 0;
    const bool last = k + 1 == config.steps || stop != 0 || case_done;
    if (k == 0) hub.mark_session_start();
    if (config.on_step) config.on_step(k, hub);
    auto consume = [&](const telemetry::RecordedInput& in) {
      telemetry::RecordedInput stamped = in;
      stamped.step = step;
      // What no device sent (a command, a case switch, the end) is stamped when physics takes it, on
      // the clock the devices' samples are stamped with (RECORDING.md).
      if (stamped.host_time_us == 0) stamped.host_time_us = static_cast<std::int64_t>(hub.now_us());
      if (recorder) recorder->push(stamped);
      model.apply(stamped);
    };
    // A case the loader finished: installed now, at the step boundary (a pointer move), recorded.
    if (std::unique_ptr<PreparedCase> ready = switcher.take()) {
      const int index = ready->index;
      model.stage(std::move(ready));
      case_over_step.store(-1, std::memory_order_release);  // a new (or reset) case runs
      moments.reset();
      consume(case_input(index));
      if (switches < kMaxSwitchLog) switch_log[switches] = {k, index};
      ++switches;
      if (!retiring) retiring = model.take_retired();
    }
    if (retiring && !switcher.retire(retiring)) { /* ring full: try again next step */ }
    // Operator commands, decided here in order against the state the previous one left (its ack
    // says so): a pending case switch counts as the current case, so "next, next" walks two cases.
    telemetry::AcceptedCommand cmd;
    while (commands.poll(cmd)) {
      const int target = switcher.pending() >= 0 ? switcher.pending() : model.case_index();
      const telemetry::CommandContext ctx{target, model.case_count(), model.paused()};
      telemetry::CommandRefusal why = telemetry::decide_command(cmd.code, ctx);
      if (why == telemetry::CommandRefusal::None && cmd.code == telemetry::CommandCode::SaveSnapshot &&
          !snapshots.capture(model.world(), model.scene().description.name, cmd.arg, k))
        why = telemetry::CommandRefusal::SnapshotBusy;
      if (why == telemetry::CommandRefusal::None) {
        consume(command_input(cmd));
        switch (cmd.code) {
          case telemetry::CommandCode::NextCase: switcher.request(target + 1); break;
          case telemetry::CommandCode::PreviousCase: switcher.request(target - 1); break;
          // Reset: the case the operator is in — or on the way to, when a switch is still loading.
          case telemetry::CommandCode::Reset: switcher.request(target); break;
          default: break;
        }
      }
      commands.report(cmd, why, ctx);
    }
    hub.lockstep_deliver(k, period_us);  // lockstep: step k's inputs, all of them, before taking them
    hub.take_new(consume);
    if (last) consume(session_end_marker(k + 1));
    const bool stepped = !model.paused();  // paused: the world does not step, and has no new events
    const core::StepReport report = model.step();
    // The end of the case: announced once (console and telemetry), with the score that now stands.
    bool case_ended = false;
    if (model.metrics().finished() && case_over_step.load(std::memory_order_relaxed) < 0) {
      case_ended = true;
      case_over_complete.store(model.metrics().completed(), std::memory_order_relaxed);
      case_over_step.store(step, std::memory_order_release);
      push_scores(model, step, true, physics_out);
    }
    // The model's metrics observed the step; running scores go out at a low rate (score() scans
    // the world), the final one with the last step.
    if (last || (config.score_every_steps > 0 && (k + 1) % config.score_every_steps == 0)) push_scores(model, step, last, physics_out);
    for (const auto& slot : model.instruments()) {
      if (slot.frozen) {
        ++summary.frozen_steps;
        break;
      }
    }
    summary.tears += report.tears;
    summary.attachments_broken += report.attachments_broken;
    if (!report.ok) ++summary.rolled_back;
    for (const auto& e : stepped ? model.simulation().events() : kNoInstrumentEvents) {
      ++summary.instrument_events;
      if (e.kind == core::InstrumentEventKind::kGrasp) ++summary.grasps;
      if (e.kind == core::InstrumentEventKind::kLaserBurn) ++summary.burns;
    }
    push_step_telemetry(model, stepped, k, step, t_s, physics_out);
    if (picture_moments && !key_view_ready.load(std::memory_order_acquire)) {
      const std::optional<KeyMoment> m = moments.pending(stepped ? model.simulation().events() : kNoInstrumentEvents, case_ended);
      if (m && capture_view(model, k, t_s, key_view)) {
        key_moment = *m;
        moments.pictured(*m);
        key_view_ready.store(true, std::memory_order_release);
      }
    }
    if (renderer && (k % view_every == 0 || last)) {
      if (capture_view(model, k, t_s, views.write_slot())) views.publish();
    }
    if (timing) timing->on_step(k, model.paused());  // 10 Hz, each message its own window (CHANNELS.md)
    if (last && (stop != 0 || case_done)) {
      stopped_by = stop;
      ended_at_case_over = stop == 0;
      loop->request_stop();
    }
  });
  loop = &harness.loop();
  timing.emplace(harness.loop(), physics_out, telemetry::TimingReporter::steps_for_rate(harness_config.loop.period_ns, 10.0));
  std::int64_t next_receive_status_ns = 0;
  harness.add_service("telemetry", std::chrono::milliseconds(2), [&] {
    if (const std::int64_t over = case_over_step.load(std::memory_order_acquire); over >= 0 && over != case_over_announced) {
      case_over_announced = over;
      if (config.command_echo) {
        std::fprintf(config.command_echo, "case over at step %lld: %s — the score stands; 'n' for the next case, 'r' to try it again\n",
                     static_cast<long long>(over),
                     case_over_complete.load(std::memory_order_relaxed) ? "every criterion met" : "its time limit passed");
        std::fflush(config.command_echo);
      }
    }
    publisher.pump();
    publisher.handle_incoming();
    commands.pump_local();  // terminal commands in, physics' decisions back, acks out
    if (const std::int64_t now = wall.now_ns(); now >= next_receive_status_ns) {  // 1 Hz (CHANNELS.md)
      publisher.publish_receive_status("vitreo");
      next_receive_status_ns = now + 1'000'000'000;
    }
  });
  if (recorder) harness.add_service("recorder", std::chrono::milliseconds(20), [&] { recorder->pump(wall.now_ns()); });
  harness.add_service("case-loader", std::chrono::milliseconds(5), [&] { switcher.service(!harness.physics_done()); });
  harness.add_service("snapshots", std::chrono::milliseconds(20), [&] { snapshots.service(); });
  std::uint64_t last_view = ~std::uint64_t{0};
  // A key moment's picture goes first; it stays with physics' snapshot until the render thread took
  // the previous one.
  auto hand_over_moment = [&] {
    if (!key_view_ready.load(std::memory_order_acquire)) return true;
    if (!renderer->keep(key_frames.build(key_view), KeyMoments::file_prefix(config.png_dir, key_view.step, key_moment))) return false;
    key_view_ready.store(false, std::memory_order_release);
    return true;
  };
  auto render_latest = [&] {
    if (picture_moments) hand_over_moment();
    if (!views.update()) return;
    const ViewSnapshot& v = views.read_slot();
    if (v.step == last_view || !v.visuals) return;
    last_view = v.step;
    renderer->publish(frames.build(v));
  };
  if (renderer) {
    harness.add_service("render", std::chrono::milliseconds(static_cast<int>(1000.0 / config.display_hz)), render_latest);
  }

  std::unique_ptr<telemetry::TerminalCommands> terminal;
  if (config.command_fd >= 0) terminal = std::make_unique<telemetry::TerminalCommands>(config.command_fd, commands, config.command_echo);

  hub.start();
  if (lockstep) hub.lockstep_connect();
  harness.start();
  if (terminal) terminal->start();
  harness.wait_physics();
  if (terminal) terminal->stop();
  harness.stop();
  hub.stop();
  commands.abandon_pending("the session ended before physics carried it out");
  publisher.pump();
  publisher.publish_receive_status("vitreo");  // the session's last word on what it received
  if (renderer) {
    render_latest();  // the final state, so the last frame shows where the session ended
    // The last key moment (often the case's end) waits for the one before it to be written.
    while (picture_moments && !hand_over_moment() && !renderer->error()) std::this_thread::sleep_for(std::chrono::milliseconds(2));
    renderer->stop();
    summary.key_moment_frames = renderer->kept_written();
    summary.frames_rendered = renderer->frames_rendered();
    summary.scenes_dropped = renderer->scenes_dropped();
    summary.pngs = renderer->pngs_written();
    summary.renderer = renderer->context_description();
    summary.displays = renderer->display_descriptions();
    if (renderer->display_errors() > 0) summary.displays.push_back(std::to_string(renderer->display_errors()) + " display(s) dropped (see the log)");
    if (auto err = renderer->error()) throw std::runtime_error("rendering failed: " + *err);
  }
  for (std::size_t i = 0; i < std::min(switches, kMaxSwitchLog); ++i) {
    const int index = switch_log[i].second;
    summary.cases_loaded.push_back("step " + std::to_string(switch_log[i].first) + ": " +
                                   config.model.cases[static_cast<std::size_t>(index)].file_name);
  }
  if (switcher.failures() > 0) summary.cases_loaded.push_back("load failures: " + std::to_string(switcher.failures()) + " (last: " + switcher.last_error() + ")");
  snapshots.service();
  summary.snapshots = snapshots.written();

  summary.steps = harness.loop().stats().steps;
  if (ended_at_case_over) summary.stop_reason = "case over";
  if (stopped_by != 0) {
    summary.stop_reason = stopped_by == SIGINT ? "SIGINT" : stopped_by == SIGTERM ? "SIGTERM" : "signal " + std::to_string(stopped_by);
  }
  summary.simulated_s = static_cast<double>(summary.steps) * config.model.dt_s;
  summary.loop = harness.loop().stats();
  summary.inputs_applied = model.inputs_applied();
  summary.inputs_refused = model.inputs_refused();
  if (recorder) {
    summary.inputs_recorded = recorder->written();
    summary.recorder_dropped = recorder->dropped();
  }
  for (const auto& row : publisher.receive_stats().snapshot()) {
    char line[256];
    std::snprintf(line, sizeof line, "%-16s %llu received, %llu refused as malformed, %llu handler errors%s%s", row.channel.c_str(),
                  static_cast<unsigned long long>(row.received), static_cast<unsigned long long>(row.rejected),
                  static_cast<unsigned long long>(row.handler_errors), row.last_error.empty() ? "" : " (last: ",
                  row.last_error.empty() ? "" : (row.last_error + ")").c_str());
    summary.receive_lines.emplace_back(line);
  }
  summary.telemetry_published = publisher.published();
  summary.telemetry_dropped = publisher.dropped();
  summary.state_hash = model.state_hash();
  summary.laser_at_end = model.laser();
  if (lockstep) {
    const LockstepStats ls = hub.lockstep_stats();
    char line[256];
    std::snprintf(line, sizeof line,
                  "%llu steps granted after %llu handshake rounds; physics waited %.1f us a step on average (max %.1f ms); %llu stalls",
                  static_cast<unsigned long long>(ls.grants), static_cast<unsigned long long>(ls.handshake_rounds),
                  ls.grants ? static_cast<double>(ls.wait_ns_total) * 1e-3 / static_cast<double>(ls.grants) : 0.0,
                  static_cast<double>(ls.wait_ns_max) * 1e-6, static_cast<unsigned long long>(ls.stalls));
    summary.lockstep_line = line;
  }
  if (recorder) {
    // The end event: the recording is complete, and says which state a replay must reach.
    if (!recorder->finish(telemetry::RecordingEnd{static_cast<std::int64_t>(summary.steps), summary.state_hash, summary.stop_reason}))
      summary.recording_problem = "the recording failed during the session (see the log): it is incomplete";
    summary.inputs_recorded = recorder->written();
    summary.recorder_dropped = recorder->dropped();
  }
  summary.score_lines = score_lines(model);
  summary.case_finished = model.metrics().finished();
  summary.case_completed = model.metrics().completed();
  summary.case_finished_at_s = model.metrics().finished_at_s();
  summary.criteria = model.metrics().criteria();
  summary.score = model.metrics().score();
  summary.totals = model.metrics().totals();
  for (std::size_t i = 0; i < hub.device_count(); ++i) {
    const auto& st = hub.stats(i);
    char line[512];
    std::snprintf(line, sizeof line, "%-10s frames %llu, valid %llu, CRC errors %llu, samples %llu, reconnects %llu",
                  hub.name(i).c_str(), static_cast<unsigned long long>(st.frames),
                  static_cast<unsigned long long>(st.valid), static_cast<unsigned long long>(st.crc_errors),
                  static_cast<unsigned long long>(st.samples_delivered), static_cast<unsigned long long>(st.reconnects));
    summary.device_lines.emplace_back(line);
    // Sensor faults, each only when it happened: what a technician has to look at.
    std::string faults;
    auto add = [&](std::uint64_t n, const char* what) {
      if (n == 0) return;
      faults += (faults.empty() ? "" : ", ") + std::to_string(n) + " " + what;
    };
    add(st.stuck_episodes, st.stuck_episodes == 1 ? "time stuck (instrument frozen)" : "times stuck (instrument frozen)");
    add(st.stuck_samples, "samples while stuck");
    add(st.range_rejected, "samples out of range");
    add(st.timestamp_jumps, "timestamp jumps");
    add(st.framing_errors, "framing errors");
    add(st.drops, "frames missing (sequence gaps)");
    add(st.version_errors + st.unknown_type + st.length_errors, "frames of another version, type or length");
    add(st.identity_rejected + st.protocol_rejected, "announcements refused (another device, serial or protocol)");
    if (!faults.empty()) summary.fault_lines.push_back(hub.name(i) + ": " + faults);
  }
  if (hub.reader_stalls() > 0) {
    summary.fault_lines.push_back("driver thread starved " + std::to_string(hub.reader_stalls()) + " times (longest " +
                                  std::to_string(hub.reader_stall_max_us() / 1000) +
                                  " ms): framing errors and gaps may be this machine's load, not a device");
  }
  return summary;
}

ReplaySummary replay_session(const std::string& path, const ModelConfig& base, const ReplayOptions& options) {
  const telemetry::Recording rec = telemetry::read_recording(path);
  // The cases as they were recorded: their texts are in the header, not read from scenes/.
  ModelConfig model_config = base;
  if (rec.header.config_name != "vitreo-cases") {
    throw telemetry::RecordingError(path + ": recording has no case list (config '" + rec.header.config_name.substr(0, 64) +
                                    "'); it was made by an older vitreo");
  }
  decode_case_list(rec.header.config_text, model_config);
  model_config.load.textures = false;  // physics only
  SimulationModel model(model_config);
  const std::string start = hex(model.current_case().start_hash);
  if (rec.header.snapshot_hash != start) {
    throw telemetry::RecordingError(path + ": the recorded case '" + rec.header.case_id.substr(0, 64) +
                                    "' rebuilds to start state " + start + ", the recording started from " +
                                    rec.header.snapshot_hash + " (a different build of the simulation?)");
  }
  for (const auto& in : rec.inputs) {
    const auto* to = std::get_if<telemetry::CaseSwitch>(&in.what);
    if (to && to->index >= model.case_count()) {
      throw telemetry::RecordingError(path + ": an input at step " + std::to_string(in.step) + " switches to case " +
                                      std::to_string(to->index) + " of a list of " + std::to_string(model.case_count()));
    }
  }
  telemetry::InputCursor cursor(rec);
  std::uint64_t steps = 0;
  std::uint64_t inputs = 0;
  // A complete recording says how many steps the session ran; one that is not is replayed through
  // the last step it can vouch for (read_recording decided which).
  const std::int64_t through = rec.end ? rec.end->steps - 1 : rec.trusted_through_step;
  const std::uint64_t total = through < 0 ? 0 : static_cast<std::uint64_t>(through) + 1;
  runtime::SimulatedClock sim;
  runtime::SteadyClock wall;
  runtime::Clock& clock = options.real_time ? static_cast<runtime::Clock&>(wall) : static_cast<runtime::Clock&>(sim);
  runtime::LoopConfig loop_config;
  loop_config.period_ns = rec.header.step_period_us * 1000LL;
  // The physics telemetry again, when asked for: pumped from this thread (nothing here is real
  // time), often enough that the source's ring never fills.
  std::optional<telemetry::TelemetryPublisher> publisher;
  telemetry::TelemetrySource* physics_out = nullptr;
  if (!options.lcm_url.empty()) {
    publisher.emplace(telemetry::PublisherConfig{options.lcm_url, 4096});
    physics_out = &publisher->add_source("physics");
  }
  bool case_over_published = false;
  runtime::FixedStepLoop loop(clock, loop_config, [&](std::uint64_t k, double t_s) {
    const auto step = static_cast<std::int64_t>(k);
    cursor.feed_through_step(step, [&](const telemetry::RecordedInput& in) {
      if (std::holds_alternative<telemetry::CaseSwitch>(in.what)) case_over_published = false;  // a new (or reset) case runs
      model.apply(in);
      ++inputs;
    });
    const bool stepped = !model.paused();
    model.step();
    ++steps;
    if (!physics_out) return;
    // What run_session's physics step publishes, in the same order. The session's final score only
    // where the recording says the session ended there (a truncated one ends early: a running score).
    const bool last = k + 1 == total;
    const bool session_end = last && rec.end.has_value();
    if (model.metrics().finished() && !case_over_published) {
      case_over_published = true;
      push_scores(model, step, true, *physics_out);
    }
    if (last || (options.score_every_steps > 0 && (k + 1) % options.score_every_steps == 0)) push_scores(model, step, session_end, *physics_out);
    push_step_telemetry(model, stepped, k, step, t_s, *physics_out);
    if (k % 64 == 0) publisher->pump();
  });
  const auto t0 = std::chrono::steady_clock::now();
  loop.run(total);
  if (publisher) publisher->pump();
  ReplaySummary out;
  out.steps = steps;
  out.inputs = inputs;
  out.state_hash = model.state_hash();
  out.score_lines = score_lines(model);
  out.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  out.case_id = rec.header.case_id;
  for (const auto& c : model_config.cases) out.cases.push_back(c.file_name);
  out.verdict = rec.verdict;
  out.verdict_text = rec.describe();
  if (rec.end) {
    out.recorded_state_hash = rec.end->state_hash;
    out.stop_reason = rec.end->stop_reason;
  }
  return out;
}

}  // namespace vitreo::rig
