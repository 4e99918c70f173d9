#include "vitreo/render/render_thread.hpp"

#include <spdlog/spdlog.h>

#include <cstdio>
#include <future>

#include "vitreo/render/frame_ring.hpp"
#include "vitreo/render/instructor_view.hpp"
#include "vitreo/render/png_io.hpp"

namespace vitreo::render {

RenderThread::RenderThread(RenderThreadOptions options) : options_(std::move(options)) {
  std::promise<void> started;
  std::future<void> ready = started.get_future();
  // The promise moves into the thread: this constructor may return (and its locals die) while
  // set_value() is still finishing there.
  thread_ = std::thread([this, p = std::move(started)]() mutable { run(p); });
  try {
    ready.get();  // rethrows the start-up failure
  } catch (...) {
    thread_.join();
    throw;
  }
}

RenderThread::~RenderThread() { stop(); }

void RenderThread::publish(FrameScene scene) {
  if (options_.eyepieces) options_.eyepieces->apply(scene.microscope);
  mailbox_.write(std::move(scene));
  // Wakes the render thread if it sleeps on wake_; a notify is a syscall at most, never a wait.
  wake_.fetch_add(1, std::memory_order_release);
  wake_.notify_one();
}

void RenderThread::request_png(std::string path_prefix) {
  std::lock_guard lock(mutex_);
  png_prefix_ = std::move(path_prefix);
}

bool RenderThread::keep(FrameScene scene, std::string path_prefix) {
  if (options_.eyepieces) options_.eyepieces->apply(scene.microscope);
  {
    std::lock_guard lock(mutex_);
    if (kept_scene_) return false;
    kept_scene_ = std::move(scene);
    kept_prefix_ = std::move(path_prefix);
  }
  wake_.fetch_add(1, std::memory_order_release);
  wake_.notify_one();
  return true;
}

std::vector<std::string> RenderThread::kept_written() const {
  std::lock_guard lock(mutex_);
  return kept_written_;
}

void RenderThread::stop() {
  if (!thread_.joinable()) return;
  stop_.store(true, std::memory_order_release);
  wake_.fetch_add(1, std::memory_order_release);
  wake_.notify_one();
  thread_.join();
}

std::vector<std::string> RenderThread::pngs_written() const {
  std::lock_guard lock(mutex_);
  return pngs_written_;
}

namespace {
void write_stereo_pngs(const std::string& prefix, const StereoFrame& frame, const Image* instructor) {
  write_png(prefix + "_left.png", frame.eye(0));
  write_png(prefix + "_right.png", frame.eye(1));
  write_png(prefix + "_stereo.png", frame.side_by_side());
  if (instructor) write_png(prefix + "_instructor.png", *instructor);
}

std::string series_prefix(const std::string& dir, std::uint64_t step) {
  char name[48];
  std::snprintf(name, sizeof name, "/step_%09llu", static_cast<unsigned long long>(step));
  return dir + name;
}
}  // namespace

void RenderThread::present_on_displays(const StereoFrame& frame, std::vector<std::unique_ptr<KmsDisplay>>& displays) {
  if (displays.empty()) return;
  const RgbaView sbs{frame.rgba.data(), frame.width(), frame.eye_height, 4 * static_cast<std::size_t>(frame.width())};
  for (auto it = displays.begin(); it != displays.end();) {
    try {
      (*it)->present(sbs);
      ++it;
    } catch (const KmsError& e) {
      // A display that went away must not take the other outputs (or the simulation) with it.
      spdlog::error("render thread: display dropped: {}", e.what());
      display_errors_.fetch_add(1, std::memory_order_acq_rel);
      it = displays.erase(it);
    }
  }
}

std::optional<std::string> RenderThread::error() const {
  std::lock_guard lock(mutex_);
  return error_;
}

void RenderThread::run(std::promise<void>& started) {
  std::unique_ptr<EglContext> context;
  std::unique_ptr<StereoRenderer> renderer;
  std::unique_ptr<FrameRingWriter> ring, instructor_ring;
  std::vector<std::unique_ptr<KmsDisplay>> displays;
  try {
    context = std::make_unique<EglContext>(options_.egl);
    renderer = std::make_unique<StereoRenderer>(options_.render);
    if (!options_.shm_ring_name.empty())
      ring = std::make_unique<FrameRingWriter>(options_.shm_ring_name, options_.render.eye_width,
                                               options_.render.eye_height, options_.shm_ring_slots);
    if (!options_.instructor_ring_name.empty())
      instructor_ring = std::make_unique<FrameRingWriter>(options_.instructor_ring_name, options_.render.eye_width,
                                                          options_.render.eye_height, options_.shm_ring_slots, 1);
    for (const KmsOptions& d : options_.displays) {
      displays.push_back(std::make_unique<KmsDisplay>(d));
      display_descriptions_.push_back(displays.back()->description());
    }
    context_description_ = context->description();
    started.set_value();
  } catch (...) {
    displays.clear();
    renderer.reset();
    context.reset();
    started.set_exception(std::current_exception());
    return;
  }
  spdlog::info("render thread: {}", context_description_);

  StereoFrame frame;
  Image instructor;
  const bool instructor_wanted = !options_.instructor_ring_name.empty() || !options_.png_dir.empty();
  // A kept scene (keep()) gets a frame and an instructor view of its own: the running frame, the
  // last one of the run, stays the newest published scene's.
  auto render_kept = [&] {
    std::optional<FrameScene> kept;
    std::string prefix;
    {
      std::lock_guard lock(mutex_);
      if (!kept_scene_) return false;
      kept.swap(kept_scene_);
      prefix.swap(kept_prefix_);
    }
    StereoFrame kept_frame;
    renderer->render(*kept, kept_frame);
    const Image view = compose_instructor_view(kept_frame, kept->instructor ? *kept->instructor : InstructorOverlay{});
    write_stereo_pngs(prefix, kept_frame, &view);
    std::lock_guard lock(mutex_);
    kept_written_.push_back(prefix);
    return true;
  };
  try {
    for (;;) {
      const std::uint64_t wake = wake_.load(std::memory_order_acquire);
      const bool stopping = stop_.load(std::memory_order_acquire);
      if (render_kept()) continue;
      const FrameScene* scene = mailbox_.take();
      if (scene == nullptr) {
        if (stopping) break;
        wake_.wait(wake, std::memory_order_acquire);  // sleeps until the next publish()/stop()
        continue;
      }
      renderer->render(*scene, frame);
      if (ring) ring->write(frame);
      if (instructor_wanted) {
        instructor = compose_instructor_view(frame, scene->instructor ? *scene->instructor : InstructorOverlay{});
        if (instructor_ring) instructor_ring->write(instructor, frame.sim_time_s, frame.step_index, frame.frame_index);
      }
      const Image* instructor_png = instructor_wanted && !options_.png_dir.empty() ? &instructor : nullptr;
      present_on_displays(frame, displays);
      std::string prefix;
      {
        std::lock_guard lock(mutex_);
        prefix.swap(png_prefix_);
      }
      if (!prefix.empty()) write_stereo_pngs(prefix, frame, instructor_wanted ? &instructor : nullptr);
      const std::uint64_t n = frames_.load(std::memory_order_relaxed) + 1;
      if (!options_.png_dir.empty() && options_.png_every_frames > 0 && n % options_.png_every_frames == 0) {
        const std::string p = series_prefix(options_.png_dir, frame.step_index);
        write_stereo_pngs(p, frame, instructor_png);
        std::lock_guard lock(mutex_);
        pngs_written_.push_back(p);
      }
      if (options_.on_frame) options_.on_frame(frame);
      last_step_.store(frame.step_index, std::memory_order_release);
      frames_.fetch_add(1, std::memory_order_acq_rel);
      frames_.notify_all();
    }
    // The last frame of the run, unless it was just written as one of the series.
    if (!options_.png_dir.empty() && frames_.load(std::memory_order_relaxed) > 0) {
      const std::string p = series_prefix(options_.png_dir, frame.step_index);
      std::lock_guard lock(mutex_);
      if (pngs_written_.empty() || pngs_written_.back() != p) {
        write_stereo_pngs(p, frame, instructor_wanted ? &instructor : nullptr);
        pngs_written_.push_back(p);
      }
      spdlog::info("render thread: {} stereo frame(s) written to {} (last: {}_stereo.png)", pngs_written_.size(),
                   options_.png_dir, pngs_written_.back());
    }
  } catch (const std::exception& e) {
    spdlog::error("render thread stopped: {}", e.what());
    std::lock_guard lock(mutex_);
    error_ = e.what();
  }
  ring.reset();
  instructor_ring.reset();
  displays.clear();
  renderer.reset();
  context.reset();
}

}  // namespace vitreo::render
