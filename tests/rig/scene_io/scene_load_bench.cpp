// Loading a case: parse → build (eye, retina, gel, pathology, textures) → settle, at a given retina
// resolution; and the same case started from a stored equilibrium snapshot instead of settling.
//   build/test/bench/bench_scene_load --benchmark_filter=20000
#include <benchmark/benchmark.h>

#include <string>

#include "core/scene/scene_builder.hpp"
#include "core/scene/snapshot.hpp"
#include "rig/scene_io/case_loader.hpp"
#include "rig/scene_io/scene_file.hpp"

namespace {

using namespace vitreo;

const std::string kCase = std::string(VITREO_SOURCE_DIR) + "/scenes/rhegmatogenous_u_tear.toml";

void BM_LoadCaseAndSettle(benchmark::State& state) {
  int steps = 0;
  for (auto _ : state) {
    core::SceneDescription d = scene_io::load_scene_file(kCase);
    d.anatomy.retina_vertices = static_cast<int>(state.range(0));
    core::Scene s = core::build_scene(d);
    steps = s.settle.steps;
    benchmark::DoNotOptimize(s.world.state_hash());
  }
  state.counters["settle_steps"] = steps;
}
BENCHMARK(BM_LoadCaseAndSettle)->Arg(5000)->Arg(20000)->Unit(benchmark::kMillisecond)->Iterations(2);

void BM_LoadCaseFromSnapshot(benchmark::State& state) {
  core::SceneDescription d = scene_io::load_scene_file(kCase);
  d.anatomy.retina_vertices = static_cast<int>(state.range(0));
  const auto bytes = core::encode_snapshot(core::build_scene(d).world, d.name);
  for (auto _ : state) {
    core::SceneDescription d2 = scene_io::load_scene_file(kCase);
    d2.anatomy.retina_vertices = static_cast<int>(state.range(0));
    core::BuildOptions o;
    o.settle = false;
    core::Scene s = core::build_scene(d2, o);
    if (!core::decode_snapshot(s.world, bytes).is_ok()) state.SkipWithError("snapshot refused");
    benchmark::DoNotOptimize(s.world.state_hash());
  }
}
BENCHMARK(BM_LoadCaseFromSnapshot)->Arg(20000)->Unit(benchmark::kMillisecond)->Iterations(3);

// What the rig does on the second load of a case: the equilibrium comes from the cache.
void BM_LoadCaseCached(benchmark::State& state) {
  const std::string dir = "/tmp/vitreo-bench-scene-cache";
  (void)scene_io::load_case(kCase, {dir, true});  // fills the cache
  bool hit = false;
  for (auto _ : state) {
    auto c = scene_io::load_case(kCase, {dir, true});
    hit = c.from_cache;
    benchmark::DoNotOptimize(c.scene.world.state_hash());
  }
  state.counters["cache_hit"] = hit ? 1 : 0;
}
BENCHMARK(BM_LoadCaseCached)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace

BENCHMARK_MAIN();
