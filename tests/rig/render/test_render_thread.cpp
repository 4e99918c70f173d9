// The render thread: fed from a simulated physics thread, it never makes the publisher wait, and
// every frame it emits shows the sim time and step of the scene it rendered.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <future>
#include <mutex>
#include <thread>
#include <vector>

#include "synthetic_scene.hpp"
#include "vitreo/render/frame_ring.hpp"
#include "vitreo/render/png_io.hpp"
#include "vitreo/render/render_thread.hpp"

namespace vr = vitreo::render;
namespace vt = vitreo::render::testing;
using Clock = std::chrono::steady_clock;

namespace {
vr::RenderThreadOptions small_options() {
  vr::RenderThreadOptions o;
  o.egl.honour_environment = false;
  o.render = {96, 64, 256, 256};
  return o;
}
}  // namespace

TEST(RenderThread, PublishNeverWaitsForASlowRenderer) {
  std::promise<void> first_frame_started;
  std::promise<void> release_renderer;
  std::shared_future<void> released = release_renderer.get_future().share();
  std::mutex m;
  std::vector<std::pair<double, std::uint64_t>> shown;  // (sim time, step) of each rendered frame
  vr::RenderThreadOptions o = small_options();
  bool first = true;
  o.on_frame = [&](const vr::StereoFrame& f) {
    {
      std::lock_guard lock(m);
      shown.emplace_back(f.sim_time_s, f.step_index);
    }
    if (first) {
      first = false;
      first_frame_started.set_value();
      released.wait();  // the renderer is stuck on its first frame until the test lets it go
    }
  };
  vr::RenderThread thread(o);

  vt::SyntheticOptions so;
  so.retina_triangles = 500;
  const vr::FrameScene base = vt::make_scene(so);
  vr::FrameScene scene = base;
  scene.step_index = 1;
  scene.sim_time_s = 0.001;
  thread.publish(scene);
  first_frame_started.get_future().wait();
  // While the renderer is blocked, the "physics thread" publishes 2000 steps at full speed.
  double worst_publish_s = 0;
  constexpr std::uint64_t kLast = 2001;
  for (std::uint64_t step = 2; step <= kLast; ++step) {
    scene.step_index = step;
    scene.sim_time_s = static_cast<double>(step) * 0.001;
    const auto t0 = Clock::now();
    thread.publish(scene);
    worst_publish_s = std::max(worst_publish_s, std::chrono::duration<double>(Clock::now() - t0).count());
  }
  release_renderer.set_value();
  thread.stop();  // renders the newest scene before stopping
  EXPECT_FALSE(thread.error().has_value()) << *thread.error();
  // The renderer was blocked for the whole loop, so any waiting would have shown as a long publish.
  EXPECT_LT(worst_publish_s, 0.05);
  EXPECT_GE(thread.scenes_dropped(), 1u);
  EXPECT_EQ(thread.last_step_rendered(), kLast);
  std::lock_guard lock(m);
  ASSERT_GE(shown.size(), 2u);
  EXPECT_EQ(shown.front().second, 1u);
  EXPECT_EQ(shown.back().second, kLast);
  for (const auto& [t, step] : shown) EXPECT_DOUBLE_EQ(t, static_cast<double>(step) * 0.001);
}

TEST(RenderThread, WritesTheRingAndPngsOnRequest) {
  vr::RenderThreadOptions o = small_options();
  o.shm_ring_name = "/vitreo-test-thread-" + std::to_string(getpid());
  std::promise<vr::StereoFrame> rendered;
  bool done = false;
  o.on_frame = [&](const vr::StereoFrame& f) {
    if (!done) {
      done = true;
      rendered.set_value(f);
    }
  };
  vr::RenderThread thread(o);
  vr::FrameRingReader reader(o.shm_ring_name);
  const std::string prefix = ::testing::TempDir() + "vitreo_thread_png";
  thread.request_png(prefix);
  vt::SyntheticOptions so;
  so.retina_triangles = 500;
  vr::FrameScene scene = vt::make_scene(so);
  scene.step_index = 77;
  scene.sim_time_s = 0.077;
  thread.publish(scene);
  const vr::StereoFrame f = rendered.get_future().get();  // the ring is written before on_frame
  vr::RingFrame r;
  ASSERT_TRUE(reader.read_latest(r));
  EXPECT_EQ(r.step_index, 77u);
  EXPECT_DOUBLE_EQ(r.sim_time_s, 0.077);
  EXPECT_EQ(r.width, 192);
  EXPECT_EQ(r.height, 64);
  EXPECT_EQ(r.rgba, f.rgba);
  thread.stop();
  const vr::Image left = vr::read_png(prefix + "_left.png");
  const vr::Image stereo = vr::read_png(prefix + "_stereo.png");
  EXPECT_EQ(left.width, 96);
  EXPECT_EQ(stereo.width, 192);
  EXPECT_EQ(stereo.rgba, f.rgba);
  EXPECT_EQ(left.rgba, f.eye(0).rgba);
}

TEST(RenderThread, StartFailureThrowsTheEglReason) {
  vr::RenderThreadOptions o = small_options();
  o.egl.platform = vr::EglPlatform::Gbm;
  o.egl.gbm_node = "/nonexistent/card9";
  const auto t0 = Clock::now();
  try {
    vr::RenderThread thread(o);
    ADD_FAILURE() << "started without a display";
  } catch (const vr::EglError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/card9"), std::string::npos) << e.what();
  }
  EXPECT_LT(std::chrono::duration<double>(Clock::now() - t0).count(), 10.0);
}

TEST(RenderThread, WritesAFewStereoFramesAlongTheWayAndTheLast) {
  const std::string dir = ::testing::TempDir() + "vitreo_series_" + std::to_string(getpid());
  ASSERT_EQ(mkdir(dir.c_str(), 0755), 0);
  vr::RenderThreadOptions o = small_options();
  o.png_dir = dir;
  o.png_every_frames = 2;
  std::atomic<std::uint64_t> rendered{0};
  o.on_frame = [&](const vr::StereoFrame&) {
    rendered.fetch_add(1);
    rendered.notify_all();
  };
  vr::RenderThread thread(o);
  vt::SyntheticOptions so;
  so.retina_triangles = 500;
  vr::FrameScene scene = vt::make_scene(so);
  for (std::uint64_t i = 1; i <= 3; ++i) {  // one frame per scene: wait for each before the next
    scene.step_index = 10 * i;
    thread.publish(scene);
    for (std::uint64_t seen = rendered.load(); seen < i; seen = rendered.load()) rendered.wait(seen);
  }
  thread.stop();
  const std::vector<std::string> written = thread.pngs_written();
  ASSERT_EQ(written.size(), 2u);
  EXPECT_EQ(written[0], dir + "/step_000000020");  // frame 2 of 3, along the way
  EXPECT_EQ(written[1], dir + "/step_000000030");  // the last
  for (const std::string& p : written) {
    EXPECT_EQ(vr::read_png(p + "_stereo.png").width, 192);
    EXPECT_EQ(vr::read_png(p + "_left.png").width, 96);
    std::remove((p + "_stereo.png").c_str());
    std::remove((p + "_left.png").c_str());
    std::remove((p + "_right.png").c_str());
  }
  EXPECT_THROW(vr::read_png(dir + "/step_000000010_stereo.png"), std::runtime_error);
  rmdir(dir.c_str());
}
