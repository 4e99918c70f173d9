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
// Counters: triangles per eye, meshes, vertices re-uploaded per frame, p50 and p99 of the frame time
// (ms) over the iterations, and p50_still_ms: the same frame with nothing moved (no re-upload).
// Each case also at 640×512 per eye, to tell shading-bound frames from geometry-bound ones.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
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

void BM_CaseStereoFrame(benchmark::State& state, const std::string& name, int eye_w, int eye_h) {
  context();
  vr::FrameScene scene;
  try {
    scene = case_scene(name);
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  vr::StereoRenderer renderer(vr::RenderSettings{eye_w, eye_h, 1024, 1024});
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
  // The same frames with nothing moved: what the re-upload of the tissue costs is the difference.
  std::vector<double> still_ms;
  for (int i = 0; i < 10; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    renderer.render(scene, frame);
    still_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(still_ms.begin(), still_ms.end());
  std::size_t moved_vertices = 0;
  for (const auto& m : scene.meshes) {
    if (m.material != vr::MaterialKind::Static && m.material != vr::MaterialKind::Instrument)
      moved_vertices += m.geometry ? m.geometry->vertices.size() : 0;
  }
  state.counters["meshes"] = static_cast<double>(scene.meshes.size());
  state.counters["moved_vertices"] = static_cast<double>(moved_vertices);
  state.counters["p50_still_ms"] = still_ms[still_ms.size() / 2];
  state.counters["tris_per_eye"] = static_cast<double>(renderer.stats().triangles_last_frame);
  state.counters["p50_ms"] = ms[ms.size() / 2];
  state.counters["p99_ms"] = ms[std::min(ms.size() - 1, ms.size() * 99 / 100)];
}

}  // namespace

int main(int argc, char** argv) {
  for (const auto& n : rig::testing::shipped_case_names()) {
    // The rig's 1280×1024 per eye, and a quarter of its pixels: a frame whose time falls with the
    // pixels is bound by shading and blending, not by geometry or the driver.
    for (const auto& [w, h] : {std::pair{1280, 1024}, std::pair{640, 512}}) {
      benchmark::RegisterBenchmark(("BM_CaseStereoFrame/" + n + "/" + std::to_string(w) + "x" + std::to_string(h)).c_str(),
                                   BM_CaseStereoFrame, n, w, h)
          ->Unit(benchmark::kMillisecond)
          ->Iterations(20);
    }
  }
  // Which GL the figures are from (llvmpipe here, a GPU's driver on a rig).
  benchmark::AddCustomContext("egl", context().description());
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
