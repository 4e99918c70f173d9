// Stereo 1280×1024 frame time for every case in scenes/ (issue 8 bar: "frame time per case here,
// with triangle counts"), through the path the rig uses: the case loaded as the main job loads it
// (5000-vertex retina, the case's own 1024 px fundus textures), the light pipe and the case's first
// tool at the fixed poses of the case golden test, captured at a step boundary (capture_view),
// turned into a FrameScene (FrameBuilder) and rendered by the StereoRenderer on this machine's EGL
// (llvmpipe here). Each iteration stands for one displayed frame: the tissue meshes count as moved
// (re-uploaded), as they are every frame in a session, and both eyes are read back.
//
//   build/test/bench/bench_case_frames [--benchmark_filter=u_tear]
//
// Counters: triangles per eye, p50 and p99 of the frame time (ms) over the iterations.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "rig/scene_io/case_loader.hpp"
#include "rig/session/case_switcher.hpp"
#include "rig/session/frame_source.hpp"
#include "rig/session/simulation_model.hpp"
#include "fixed_poses.hpp"
#include "vitreo/render/egl_context.hpp"
#include "vitreo/render/renderer.hpp"

using namespace vitreo;
namespace vr = vitreo::render;

namespace {

constexpr int kEyeW = 1280, kEyeH = 1024;
const std::string kScenes = std::string(VITREO_SOURCE_DIR) + "/scenes";

vr::EglContext& context() {
  static vr::EglContext ctx;  // one per process; benchmarks run on the main thread
  return ctx;
}

// The FrameScene of a case at the golden test's poses.
vr::FrameScene case_scene(const std::string& name) {
  // The main job's default resolution.
  rig::testing::CaseUnderTest under_test(kScenes + "/" + name + ".toml", 5000,
                                         (std::filesystem::temp_directory_path() / "vitreo-bench-case-cache").string());
  rig::SimulationModel& model = under_test.model;
  if (!rig::testing::place_at_fixed_poses(model)) throw std::runtime_error(name + ": poses refused");
  rig::ViewSnapshot view;
  if (!rig::capture_view(model, 3, 0.003, view)) throw std::runtime_error(name + ": no view captured");
  rig::FrameBuilder builder;
  vr::FrameScene scene = builder.build(view);
  // The scene holds its geometry and textures through shared pointers: it outlives the loader.
  return scene;
}

void BM_CaseStereoFrame(benchmark::State& state, const std::string& name) {
  context();
  vr::FrameScene scene;
  try {
    scene = case_scene(name);
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  vr::StereoRenderer renderer(vr::RenderSettings{kEyeW, kEyeH, 1024, 1024});
  vr::StereoFrame frame;
  renderer.render(scene, frame);  // first frame: textures and buffers uploaded once
  std::vector<double> ms;
  for (auto _ : state) {
    // Every tissue mesh moved since the last frame (as in a session): its vertices are re-uploaded.
    for (auto& m : scene.meshes) {
      if (m.material != vr::MaterialKind::Static && m.material != vr::MaterialKind::Instrument) ++m.geometry_version;
    }
    const auto t0 = std::chrono::steady_clock::now();
    renderer.render(scene, frame);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    benchmark::DoNotOptimize(frame.rgba.data());
  }
  std::sort(ms.begin(), ms.end());
  state.counters["tris_per_eye"] = static_cast<double>(renderer.stats().triangles_last_frame);
  state.counters["p50_ms"] = ms[ms.size() / 2];
  state.counters["p99_ms"] = ms[std::min(ms.size() - 1, ms.size() * 99 / 100)];
}

}  // namespace

int main(int argc, char** argv) {
  for (const auto& n : rig::testing::shipped_case_names()) {
    benchmark::RegisterBenchmark(("BM_CaseStereoFrame/" + n + "/1280x1024").c_str(), BM_CaseStereoFrame, n)
        ->Unit(benchmark::kMillisecond)
        ->Iterations(20);
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
