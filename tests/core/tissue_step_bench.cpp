// Solver step on retina-like shells of 5k, 20k and 80k vertices with an attached epiretinal
// membrane and a detachment force, at dt = 1 ms. Reports per-step latency quantiles (p50, p99 in µs)
// and constraint projections per second. Target (design guide): 20k vertices, median ≤ 0.5 ms,
// p99 ≤ 0.8 ms on one core.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <vector>

#include "core/anatomy/retina_cap.hpp"

using namespace vitreo::core;

namespace {

void report_quantiles(benchmark::State& state, std::vector<double>& samples_us, double projections_per_step) {
  if (samples_us.empty()) return;
  std::sort(samples_us.begin(), samples_us.end());
  auto q = [&](double p) { return samples_us[static_cast<std::size_t>(p * static_cast<double>(samples_us.size() - 1))]; };
  state.counters["p50_us"] = q(0.50);
  state.counters["p99_us"] = q(0.99);
  state.counters["max_us"] = samples_us.back();
  state.counters["projections_per_s"] =
      benchmark::Counter(projections_per_step * static_cast<double>(samples_us.size()), benchmark::Counter::kIsRate);
}

// state.range(1): 1 = sleeping on (the default), 0 = every vertex simulated every step.
void BM_TissueStep(benchmark::State& state) {
  RetinaCapOptions o;
  o.retina_vertices = static_cast<int>(state.range(0));
  o.membrane = true;
  o.solver.sleeping = state.range(1) != 0;
  // Two substeps resolve the retina's stiffness up to ~20k vertices; at 80k the triangles are so
  // light that two substeps under-resolve it and the detachment tears, so that size runs four.
  o.solver.substeps = o.retina_vertices > 40000 ? 4 : 2;
  auto scene = build_retina_cap(o);
  TissueWorld& world = scene.world;
  // Warm-up: the detachment lifts and settles; the attached retina goes to sleep.
  for (int i = 0; i < 1000; ++i) world.step(1e-3);

  std::size_t edges = 0, vertices = 0, bends = 0;
  for (std::uint32_t s = 0; s < world.surface_count(); ++s) {
    const Surface& surface = world.surface(s);
    edges += surface.edge_count();
    vertices += surface.vertex_count();
    for (std::uint32_t e = 0; e < surface.edge_slots(); ++e) bends += surface.edge_alive(e) && surface.edge_bend(e).stiffness > 0.0;
  }
  const double per_sweep = static_cast<double>(edges + bends) + world.attachment_count() + static_cast<double>(vertices);
  const double projections_per_step = per_sweep * world.settings().substeps * world.settings().iterations;

  std::vector<double> samples;
  samples.reserve(1 << 16);
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    const auto r = world.step(1e-3);
    const auto t1 = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(r);
    samples.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
  }
  state.counters["vertices"] = static_cast<double>(vertices);
  state.counters["springs"] = static_cast<double>(edges);
  state.counters["attachments"] = world.attachment_count();
  state.counters["substeps"] = world.settings().substeps;
  state.counters["awake_fraction"] = static_cast<double>(world.awake_blocks()) / world.total_blocks();
  report_quantiles(state, samples, projections_per_step);
}

}  // namespace

BENCHMARK(BM_TissueStep)
    ->ArgNames({"vertices", "sleeping"})
    ->ArgsProduct({{5000, 20000, 80000}, {1, 0}})
    ->Unit(benchmark::kMicrosecond)
    ->MinTime(2.0);
