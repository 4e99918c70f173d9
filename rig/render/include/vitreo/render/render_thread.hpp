#pragma once
// RenderThread: renders the latest FrameScene on its own thread, with its own EGL context.
//
// The physics side only calls publish(), which is wait-free (runtime::TripleBuffer): rendering can never slow
// the simulation down; if rendering is slower than physics, intermediate scenes are skipped (and
// counted). Each rendered frame carries the sim time and step index of the scene it shows and is
// handed to the sinks: the shared-memory ring (if named), PNG files on request, and a callback.
#include <atomic>
#include <cstdint>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "vitreo/render/egl_context.hpp"
#include "vitreo/render/frame_scene.hpp"
#include "vitreo/render/kms_display.hpp"
#include "rig/runtime/triple_buffer.hpp"
#include "vitreo/render/renderer.hpp"

namespace vitreo::render {

struct RenderThreadOptions {
  EglOptions egl;
  RenderSettings render;
  std::string shm_ring_name;  // empty: no shared-memory ring
  int shm_ring_slots = 3;
  /// The instructor's view (instructor_view.hpp): the left eye with the scene's InstructorOverlay,
  /// into its own one-picture ring (empty: none) and, with png_dir, beside each PNG series as
  /// <prefix>_instructor.png. Scenes without an overlay show the plain left eye there.
  std::string instructor_ring_name;
  /// Stereo frames of a run as PNGs (issue 8: "a few along the way and the last one"): when set, every
  /// png_every_frames-th rendered frame (0: none along the way) and the last frame rendered before
  /// stop() are written to <png_dir>/step_<step>_{left,right,stereo}.png. The directory must exist.
  std::string png_dir;
  std::uint64_t png_every_frames = 0;
  /// The rig's displays (KMS scan-out), opened on the render thread at start (a failure is a start
  /// failure, with the reason). A display that fails later (unplugged) is dropped with an error in
  /// the log and display_errors(); rendering and the other outputs go on.
  std::vector<KmsOptions> displays;
  /// The rig's eyepiece displays as calibrated: applied to every scene published or kept (each eye's
  /// image shift, the stereo base and convergence). Empty: the scenes' own microscope.
  std::optional<EyepieceSettings> eyepieces;
  /// Called on the render thread after each frame (keep it short; it delays the next frame only).
  std::function<void(const StereoFrame&)> on_frame;
};

class RenderThread {
 public:
  /// Starts the thread and waits until its EGL context and renderer exist; throws EglError /
  /// RenderError / std::runtime_error (with the reason) if they cannot be created.
  explicit RenderThread(RenderThreadOptions options);
  ~RenderThread();  // stops and joins
  RenderThread(const RenderThread&) = delete;
  RenderThread& operator=(const RenderThread&) = delete;

  /// Physics side: hands over the newest scene. Wait-free; never blocks.
  void publish(FrameScene scene);
  /// Asks for the next rendered frame to be written as PNGs: "<prefix>_left.png", "_right.png",
  /// "_stereo.png" (side by side). Returns immediately.
  void request_png(std::string path_prefix);
  /// A picture that must not be skipped (a frame at a key moment of the session): `scene` is
  /// rendered before the newest published one and written as "<prefix>_left.png", "_right.png",
  /// "_stereo.png" and "_instructor.png" (the instructor's view of it). One such scene waits at a
  /// time: false (and nothing taken) while the previous one has not been rendered yet. Not for the
  /// physics thread: it locks a mutex the render thread holds briefly.
  bool keep(FrameScene scene, std::string path_prefix);
  /// Prefixes of the kept scenes written so far (keep()).
  std::vector<std::string> kept_written() const;
  /// Stops rendering; returns after the thread has finished (the last published scene, and a kept
  /// one still waiting, are rendered first if they had not been).
  void stop();

  std::uint64_t frames_rendered() const { return frames_.load(std::memory_order_acquire); }
  std::uint64_t scenes_dropped() const { return mailbox_.dropped(); }
  /// Step index of the last rendered frame.
  std::uint64_t last_step_rendered() const { return last_step_.load(std::memory_order_acquire); }
  /// The first error raised on the render thread after start-up (rendering then stops), if any.
  std::optional<std::string> error() const;
  const std::string& context_description() const { return context_description_; }
  /// One line per display opened ("card0 HDMI-A-1 1920x1080@60 (page flip)").
  const std::vector<std::string>& display_descriptions() const { return display_descriptions_; }
  std::uint64_t display_errors() const { return display_errors_.load(std::memory_order_acquire); }
  /// Prefixes ("<dir>/step_<step>") of the PNG series written so far (png_dir).
  std::vector<std::string> pngs_written() const;

 private:
  void run(std::promise<void>& started);
  void present_on_displays(const StereoFrame& frame, std::vector<std::unique_ptr<KmsDisplay>>& displays);
  RenderThreadOptions options_;
  runtime::TripleBuffer<FrameScene> mailbox_;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> wake_{0};  // bumped by publish()/stop(); the render thread sleeps on it
  std::atomic<std::uint64_t> frames_{0};
  std::atomic<std::uint64_t> last_step_{0};
  mutable std::mutex mutex_;  // guards png_prefix_, the kept scene and error_ (never taken by publish())
  std::string png_prefix_;
  std::optional<FrameScene> kept_scene_;
  std::string kept_prefix_;
  std::vector<std::string> kept_written_;
  std::optional<std::string> error_;
  std::vector<std::string> pngs_written_;
  std::string context_description_;
  std::vector<std::string> display_descriptions_;
  std::atomic<std::uint64_t> display_errors_{0};
  std::thread thread_;
};

}  // namespace vitreo::render
