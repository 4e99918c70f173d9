#pragma once
// A whole session: devices → physics (fixed step) → telemetry and recording, on separate threads
// (rig/runtime/README.md has the diagram). Physics only ever touches wait-free mailboxes.
#include <atomic>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "rig/runtime/fixed_step_loop.hpp"
#include "rig/session/device_hub.hpp"
#include "rig/session/simulation_model.hpp"
#include "rig/telemetry/recording.hpp"
#include "vitreo/render/frame_scene.hpp"
#include "vitreo/render/kms_display.hpp"

namespace vitreo::rig {

struct SessionConfig {
  ModelConfig model;  // the case list (the first case is model.cases[model.first_case])
  std::vector<DeviceSpec> devices;
  std::uint64_t steps = 5000;
  // Set (to the signal's number) by whoever wants the session to end early — vitreo's SIGINT/SIGTERM
  // handler: physics finishes the step it is in, records the end and stops; the recording is
  // complete and the summary says why it ended. nullptr: run all `steps`.
  const std::atomic<int>* stop = nullptr;
  std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0";
  std::string record_path;  // empty: no recording
  // Operator "save snapshot NAME" writes NAME.snapshot here (core/scene/snapshot format); empty:
  // the folder of record_path, else the current folder.
  std::string snapshot_dir;
  // Operator commands typed on a terminal: lines read from this descriptor on their own thread
  // (telemetry::TerminalCommands), acks printed to command_echo. -1: none.
  int command_fd = -1;
  std::FILE* command_echo = stdout;
  bool realtime = false;    // SCHED_FIFO/mlockall/affinity for physics where permitted
  // Lockstep (DeviceHub, HubMode::lockstep): every device simulated, the emulators on the
  // simulation's clock, each step's inputs waited for, so a scripted session receives the same
  // samples at the same steps however loaded the machine is. Real time: the rig's way.
  HubMode device_mode = HubMode::realtime;
  // Lockstep only: run physics as fast as it goes (no wall-clock pacing), for tests and batch
  // scoring; false paces it to real time where the machine keeps up (a demonstration).
  bool unpaced = false;
  // Batch scoring (the scripted acceptance): the step after the case is over is the session's last —
  // its score is frozen then, and stepping on would only play the rest of the script. The live rig
  // and the main job keep running and offer the next case instead.
  bool end_at_case_over = false;
  // Scripted actions at given steps, run on the physics thread (hardware-in-the-loop tests pull a
  // simulated cable with it). Must be quick and wait-free, like everything on that thread.
  std::function<void(std::uint64_t step, DeviceHub& hub)> on_step;
  // Called once the first case is loaded, before the devices start: lets simulated devices follow
  // the case's anatomy (the main job's scripted hand aims at where this case's tissue lies).
  std::function<void(const PreparedCase& first, std::vector<DeviceSpec>& devices)> adapt_devices;

  // Stereo microscope frames (EGL, headless here): rendered on their own thread from snapshots
  // physics takes at display rate; PNGs of every png_every_frames-th frame and of the last one.
  bool render = false;
  int eye_width = 640, eye_height = 512;
  double display_hz = 30.0;
  std::string png_dir;
  std::uint64_t png_every_frames = 0;
  // Shared-memory rings (rig/render/frame_ring.hpp) for a viewer or recorder: the stereo frames, and
  // the instructor's view (the left eye with score, retina force and events over it); empty: none.
  std::string frame_ring_name, instructor_ring_name;
  // The rig's displays (KMS scan-out, rig/render/kms_display.hpp); empty: headless.
  std::vector<vitreo::render::KmsOptions> displays;
  // The eyepiece displays' calibration (calibration_in_force.hpp); empty: the scenes' own microscope.
  std::optional<vitreo::render::EyepieceSettings> eyepieces;
  // Running scores on VITREO_SCORE every this many steps (and a final one at the end).
  std::uint64_t score_every_steps = 1000;
};

struct SessionSummary {
  std::string case_name, case_file, case_title;  // the first case
  std::string instruments;                       // its instruments and their trackers
  bool case_from_cache = false;
  std::vector<std::string> cases_loaded;         // every switch and reset, "step N: name"
  std::vector<std::string> snapshots;            // files written by "save snapshot"
  std::uint64_t grasps = 0, burns = 0;           // instrument events of note
  LaserSettings laser_at_start, laser_at_end;    // the endolaser's settings (rig file, then commands)
  std::uint64_t steps = 0;
  double simulated_s = 0.0;
  runtime::LoopStats loop;
  std::uint64_t inputs_applied = 0, inputs_refused = 0, inputs_recorded = 0, recorder_dropped = 0;
  std::uint64_t tears = 0, attachments_broken = 0, rolled_back = 0;
  std::string stop_reason = "duration reached";  // or "SIGTERM", "SIGINT" (SessionConfig::stop), "case over" (end_at_case_over)
  std::string recording_problem;                 // empty when the recording is complete
  std::uint64_t telemetry_published = 0, telemetry_dropped = 0;
  std::vector<std::string> receive_lines;  // per subscribed LCM channel: received, refused, handler errors
  std::uint64_t state_hash = 0;
  std::vector<std::string> device_lines;  // per device: name, link statistics
  // Sensor faults (stuck, out of range, timestamp jumps, framing errors, gaps) per device that had
  // any, and the driver thread's starvation; empty when all was well.
  std::vector<std::string> fault_lines;
  std::uint64_t instrument_events = 0;     // grasps, contacts, collisions, burns… (telemetry VITREO_EVENT)
  std::uint64_t frozen_steps = 0;          // steps during which an instrument was frozen (its tracker lost)
  std::uint64_t frames_rendered = 0, scenes_dropped = 0;
  std::vector<std::string> pngs;           // frames written
  std::vector<std::string> key_moment_frames;  // frames of the key moments written (key_moments.hpp), in order
  std::string renderer;                    // EGL/GL context in use
  std::vector<std::string> displays;       // rig displays frames were scanned out to
  // The final score of the case the session ended in (core/metrics), as published on VITREO_SCORE,
  // and its criteria ("membrane_removed epiretinal: 0.42 of 0.9"), one line each.
  std::vector<std::string> score_lines;
  // Lockstep sessions: grants, handshake rounds, stalls and physics' wait for its inputs.
  std::string lockstep_line;
  // The end of the case the session ended in (core/metrics: every criterion met, or its time limit
  // passed): from then on its score stood. The structured final score, for tests and tools.
  bool case_finished = false, case_completed = false;
  double case_finished_at_s = 0.0;
  std::vector<core::CriterionProgress> criteria;
  core::ScoreCard score;
  core::SessionTotals totals;
};

// Runs a live session to completion (config.steps) and returns its summary. Throws on setup errors
// (bad LCM URL, unopenable recording, bad device script, a first case that does not load).
//
// Operator commands (LCM VITREO_COMMAND): next/previous case and reset ask the loader thread for a
// case; it is built there (from the cache folder when it has the settled start) and installed by
// physics at the next step boundary with one pointer move — recorded as a CaseSwitch input, so a
// replay switches at the same step. Save snapshot copies the world into a preallocated buffer at
// the step boundary; a writer thread stores it atomically as <snapshot_dir>/NAME.snapshot.
SessionSummary run_session(const SessionConfig& config);

struct ReplaySummary {
  // What the recording turned out to be (telemetry::read_recording) and, for a complete one, the
  // final state it recorded: a replay that is not complete, or reaches another state, is no proof.
  telemetry::RecordingVerdict verdict = telemetry::RecordingVerdict::Complete;
  std::string verdict_text;                  // "complete (...)", "truncated at step N — replayed up to there"
  std::optional<std::uint64_t> recorded_state_hash;
  std::string stop_reason;                   // how the recorded session ended
  bool matches_recording() const { return recorded_state_hash && *recorded_state_hash == state_hash; }
  std::uint64_t steps = 0;
  std::uint64_t inputs = 0;
  std::uint64_t state_hash = 0;
  double wall_s = 0.0;
  std::string case_id;
  std::vector<std::string> cases;  // names of the recording's case list
  std::vector<std::string> score_lines;  // the final score, as the live session published it
};

struct ReplayOptions {
  bool real_time = false;  // paced by the wall clock; otherwise as fast as it goes (simulated clock)
  // What physics published live, published again from the replay to this LCM URL (a log file:
  // "file://PATH?mode=w"): instrument states, controls, events, score cards, criteria and totals —
  // step for step the live session's, since the replay is. Not the device statuses, the timing or
  // the command acknowledgements: a recording holds the inputs, not what the drivers and threads
  // saw. Empty: nothing is published.
  std::string lcm_url;
  std::uint64_t score_every_steps = 1000;  // as SessionConfig::score_every_steps
};

// Replays a recording through the same model as fast as possible (simulated clock), or at real
// time (ReplayOptions). The cases (their file and library texts, resolution overrides) come
// from the recording, not from scenes/; `model` supplies the rest (pedal mapping, calibration, the
// cache folder). Only what the recording can vouch for is replayed: a truncated or corrupted one
// up to its last verified step (the verdict says so). Throws telemetry::RecordingError when it
// cannot be replayed at all (no header, another format, a case list that does not decode, a start
// state the case no longer rebuilds to).
ReplaySummary replay_session(const std::string& recording_path, const ModelConfig& model, const ReplayOptions& options = {});

}  // namespace vitreo::rig
