#pragma once
// A whole session: devices → physics (fixed step) → telemetry and recording, on separate threads
// (rig/runtime/README.md has the diagram). Physics only ever touches wait-free mailboxes.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "rig/runtime/fixed_step_loop.hpp"
#include "rig/session/device_hub.hpp"
#include "rig/session/simulation_model.hpp"

namespace vitreo::rig {

struct SessionConfig {
  ModelConfig model;
  std::vector<DeviceSpec> devices;
  std::uint64_t steps = 5000;
  std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0";
  std::string record_path;  // empty: no recording
  std::string case_id = "retina-cap";
  std::string config_text;  // stored in the recording's header
  bool realtime = false;    // SCHED_FIFO/mlockall/affinity for physics where permitted
  // Scripted actions at given steps, run on the physics thread (hardware-in-the-loop tests pull a
  // simulated cable with it). Must be quick and wait-free, like everything on that thread.
  std::function<void(std::uint64_t step, DeviceHub& hub)> on_step;

  // Stereo microscope frames (EGL, headless here): rendered on their own thread from snapshots
  // physics takes at display rate; PNGs of every png_every_frames-th frame and of the last one.
  bool render = false;
  int eye_width = 640, eye_height = 512;
  double display_hz = 30.0;
  std::string png_dir;
  std::uint64_t png_every_frames = 0;
};

struct SessionSummary {
  std::uint64_t steps = 0;
  double simulated_s = 0.0;
  runtime::LoopStats loop;
  std::uint64_t inputs_applied = 0, inputs_refused = 0, inputs_recorded = 0, recorder_dropped = 0;
  std::uint64_t tears = 0, attachments_broken = 0, rolled_back = 0;
  std::uint64_t telemetry_published = 0, telemetry_dropped = 0;
  std::uint64_t state_hash = 0;
  std::vector<std::string> device_lines;  // per device: name, link statistics
  std::uint64_t instrument_events = 0;     // grasps, contacts, collisions, burns… (telemetry VITREO_EVENT)
  std::uint64_t frozen_steps = 0;          // steps during which an instrument was frozen (its tracker lost)
  std::uint64_t frames_rendered = 0, scenes_dropped = 0;
  std::vector<std::string> pngs;           // frames written
  std::string renderer;                    // EGL/GL context in use
};

// Runs a live session to completion (config.steps) and returns its summary. Throws on setup errors
// (bad LCM URL, unopenable recording, bad device script).
SessionSummary run_session(const SessionConfig& config);

struct ReplaySummary {
  std::uint64_t steps = 0;
  std::uint64_t inputs = 0;
  std::uint64_t state_hash = 0;
  double wall_s = 0.0;
  std::string case_id;
};

// Replays a recording through the same model as fast as possible (simulated clock), or at real
// time when `real_time` is set. The model must be configured as the live session was.
ReplaySummary replay_session(const std::string& recording_path, const ModelConfig& model, bool real_time = false);

}  // namespace vitreo::rig
