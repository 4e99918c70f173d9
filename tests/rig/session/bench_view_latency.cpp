// Device sample → frame containing it, per case (issue 19 item 7; target: one display period + 2 ms
// on the rig). Each iteration moves the tool tracker to a new pose — a RecordedInput exactly as the
// tracker driver delivers it — and times, on this machine, the work between its arrival and the
// stereo frame (1280×1024 per eye, read back) that shows it:
//   apply (port pivot, calibration) → one physics step → capture_view (physics' copy for the
//   picture, including the criteria re-measured every kProgressEvery_s) → FrameBuilder::build
//   (render service) → StereoRenderer::render (render thread)
// and checks the frame is the one with the sample (its step, and the tool tip where the sample put
// it). What it does not include is waiting: in a live session a sample waits for the next physics
// step (≤ 1 ms), for the next view capture (every display period) and for the render service's
// next poll (every display period); the README adds those to the measured work.
//
//   build/test/tests/rig/session/bench_view_latency [--benchmark_filter=u_tear]
//
// Counters (ms, over the iterations): p50_ms, p99_ms of the whole chain; apply_step_capture_ms,
// build_ms, render_ms (medians) of its parts; score_ms, what measuring the criteria and score (done
// by capture_view every kProgressEvery_s of case time) costs the physics thread when it happens.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

#include "fixed_poses.hpp"
#include "rig/session/frame_source.hpp"
#include "vitreo/render/egl_context.hpp"
#include "vitreo/render/renderer.hpp"

using namespace vitreo;
namespace vr = vitreo::render;
using Clock = std::chrono::steady_clock;

namespace {

constexpr int kEyeW = 1280, kEyeH = 1024;
const std::string kScenes = std::string(VITREO_SOURCE_DIR) + "/scenes";

vr::EglContext& context() {
  static vr::EglContext ctx;
  return ctx;
}

double ms(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); }

double pct(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[std::min(v.size() - 1, static_cast<std::size_t>(p * static_cast<double>(v.size())))];
}

void BM_SampleToFrame(benchmark::State& state, const std::string& name) {
  context();
  // The main job's resolution (5000-vertex retina, the case's own textures).
  rig::testing::CaseUnderTest c(kScenes + "/" + name + ".toml", 5000,
                                (std::filesystem::temp_directory_path() / "vitreo-bench-case-cache").string());
  rig::SimulationModel& model = c.model;
  if (!rig::testing::place_at_fixed_poses(model)) {
    state.SkipWithError("poses refused");
    return;
  }
  vr::StereoRenderer renderer(vr::RenderSettings{kEyeW, kEyeH, 1024, 1024});
  rig::FrameBuilder builder;
  rig::ViewSnapshot view;
  vr::StereoFrame frame;
  const rig::PreparedCase& pc = model.current_case();
  const core::Vec3 port = pc.tracker_ports[rig::kToolTracker].position_mm;
  const core::Vec3 base = pc.focus_mm - 3.0 * (pc.focus_mm - port).normalized();
  // Warm-up: textures, buffers and shader variants.
  (void)rig::capture_view(model, model.steps(), 0.0, view);
  renderer.render(builder.build(view), frame);
  // What capture_view adds every kProgressEvery_s on the physics thread: the criteria and score.
  std::vector<double> scoring;
  for (int i = 0; i < 5; ++i) {
    const auto a = Clock::now();
    benchmark::DoNotOptimize(model.metrics().score().total);
    scoring.push_back(ms(a, Clock::now()));
  }
  std::vector<double> total, capture, build, render;
  int k = 0;
  for (auto _ : state) {
    // A new pose each time (the tip 0.3 mm to one side or the other).
    const core::Vec3 tip = base + (k++ % 2 ? 0.3 : -0.3) * (pc.focus_mm - port).normalized().unitOrthogonal();
    const telemetry::RecordedInput sample = rig::testing::tracker_sample(rig::kToolTracker, tip, 0.3);
    const auto t0 = Clock::now();
    model.apply(sample);
    model.step();
    const std::uint64_t step = model.steps();
    const auto t1 = Clock::now();
    rig::capture_view(model, step, static_cast<double>(step) * 1e-3, view);
    const auto t2 = Clock::now();
    const vr::FrameScene scene = builder.build(view);
    const auto t3 = Clock::now();
    renderer.render(scene, frame);
    const auto t4 = Clock::now();
    benchmark::DoNotOptimize(frame.rgba.data());
    // The frame is the sample's: its step, and the tool's tip where the sample put it.
    const auto& ins = view.instruments[0];
    if (frame.step_index != step || !ins.present || (core::Vec3(ins.tip[0], ins.tip[1], ins.tip[2]) - tip).norm() > 0.3) {
      state.SkipWithError("the frame does not show the sample");
      return;
    }
    total.push_back(ms(t0, t4));
    capture.push_back(ms(t1, t2) + ms(t0, t1));
    build.push_back(ms(t2, t3));
    render.push_back(ms(t3, t4));
  }
  state.counters["p50_ms"] = pct(total, 0.5);
  state.counters["p99_ms"] = pct(total, 0.99);
  state.counters["apply_step_capture_ms"] = pct(capture, 0.5);
  state.counters["build_ms"] = pct(build, 0.5);
  state.counters["render_ms"] = pct(render, 0.5);
  state.counters["score_ms"] = pct(scoring, 0.5);
}

}  // namespace

int main(int argc, char** argv) {
  for (const auto& n : rig::testing::shipped_case_names()) {
    benchmark::RegisterBenchmark(("BM_SampleToFrame/" + n + "/1280x1024").c_str(), BM_SampleToFrame, n)
        ->Unit(benchmark::kMillisecond)
        ->Iterations(12);
  }
  // Which GL the figures are from (llvmpipe here, a GPU's driver on a rig).
  benchmark::AddCustomContext("egl", context().description());
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
