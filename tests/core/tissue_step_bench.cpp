// Solver step on retina-like shells of 5k, 20k and 80k vertices with an attached epiretinal
// membrane and a detachment force, at dt = 1 ms. Reports per-step latency quantiles (p50, p99 in µs),
// constraint projections per second and, beside them, the effective-stiffness error of the same
// mesh at the same solver settings (strip_stiffness.hpp), so that speed is never bought with
// softness. Target (design guide, issue 14): 20k vertices, median ≤ 0.5 ms, p99 ≤ 0.8 ms on one core,
// at ≤ 5 % stiffness error.
//
// Loads (the `load` argument):
//   0 at rest   — sleeping on, nothing moves: the whole cap sleeps (what an idle rig costs);
//   1 working   — sleeping on, the detachment's pressure breathes (±10 % at 1 Hz), so the detached
//                 region (25° around polar 60°) stays awake, as tissue under an instrument does;
//   2 all awake — sleeping off, the same breathing: every vertex simulated every step.
// BM_TissueStepKnobs sweeps substeps and iterations at 20k, working: the stiffness-error-versus-
// step-time curve of the solver's knobs. BM_TissueStepRelayout is BM_TissueStep with the vertex
// sweep's layout rebuilt every step (TissueWorld::set_relayout_every_step), as the solver did until
// it kept the layout while the topology and the awake region stand: what keeping it saves.
// BM_TissueStepThreads is BM_TissueStep with the step's independent passes split over a worker pool
// of 1 or 2 threads (TissueWorld::set_worker_threads; the vertex sweep stays on one): its time is
// wall-clock (UseRealTime), since a second thread's work does not show in the caller's CPU time.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <vector>

#include "core/anatomy/retina_cap.hpp"
#include "strip_stiffness.hpp"

using namespace vitreo::core;

namespace {

enum Load : int { kAtRest = 0, kWorking = 1, kAllAwake = 2 };

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

void run_tissue_step(benchmark::State& state, int vertices_wanted, Load load, const SolverSettings& solver, bool relayout = false,
                     unsigned threads = 1) {
  RetinaCapOptions o;
  o.retina_vertices = vertices_wanted;
  o.membrane = true;
  o.solver = solver;
  o.solver.sleeping = load != kAllAwake;
  auto scene = build_retina_cap(o);
  TissueWorld& world = scene.world;
  world.set_relayout_every_step(relayout);
  world.set_worker_threads(threads);
  // Warm-up: the detachment lifts and settles; the attached retina goes to sleep.
  for (int i = 0; i < 1000; ++i) world.step(1e-3);
  const std::uint64_t kept_before = world.layouts_kept();

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
  double awake_sum = 0.0;
  std::uint64_t step = 0;
  for (auto _ : state) {
    if (load != kAtRest) {
      const double t = 1e-3 * static_cast<double>(step);
      (void)world.set_local_force_scale(scene.detachment_force, 0.9 + 0.1 * std::sin(2.0 * std::numbers::pi * t));
    }
    const auto t0 = std::chrono::steady_clock::now();
    const auto r = world.step(1e-3);
    const auto t1 = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(r);
    samples.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
    awake_sum += static_cast<double>(world.awake_blocks()) / world.total_blocks();
    ++step;
  }
  state.counters["vertices"] = static_cast<double>(vertices);
  state.counters["springs"] = static_cast<double>(edges);
  state.counters["attachments"] = world.attachment_count();
  state.counters["substeps"] = world.settings().substeps;
  state.counters["iterations"] = world.settings().iterations;
  state.counters["threads"] = world.worker_threads();
  state.counters["awake_fraction"] = step > 0 ? awake_sum / static_cast<double>(step) : 0.0;
  // Surfaces whose sweep layout was kept (values refreshed, not laid out afresh), per step.
  state.counters["layouts_kept_per_step"] = step > 0 ? static_cast<double>(world.layouts_kept() - kept_before) / static_cast<double>(step) : 0.0;
  report_quantiles(state, samples, projections_per_step);
  // The same retina's stiffness at the same settings (not timed): % off the nominal modulus.
  state.counters["stiffness_error_pct"] = 100.0 * vitreo::test::strip_stiffness_error(vertices_wanted, world.settings());
}

void BM_TissueStep(benchmark::State& state) {
  SolverSettings solver;  // the rig's defaults
  run_tissue_step(state, static_cast<int>(state.range(0)), static_cast<Load>(state.range(1)), solver);
}

void BM_TissueStepKnobs(benchmark::State& state) {
  SolverSettings solver;
  solver.substeps = static_cast<int>(state.range(1));
  solver.iterations = static_cast<int>(state.range(2));
  run_tissue_step(state, static_cast<int>(state.range(0)), kWorking, solver);
}

void BM_TissueStepRelayout(benchmark::State& state) {
  SolverSettings solver;
  run_tissue_step(state, static_cast<int>(state.range(0)), static_cast<Load>(state.range(1)), solver, true);
}

void BM_TissueStepThreads(benchmark::State& state) {
  SolverSettings solver;
  run_tissue_step(state, static_cast<int>(state.range(0)), static_cast<Load>(state.range(1)), solver, false,
                  static_cast<unsigned>(state.range(2)));
}

}  // namespace

BENCHMARK(BM_TissueStep)
    ->ArgNames({"vertices", "load"})
    ->ArgsProduct({{5000, 20000, 80000}, {kAtRest, kWorking, kAllAwake}})
    ->Unit(benchmark::kMicrosecond)
    ->MinTime(2.0);

BENCHMARK(BM_TissueStepKnobs)
    ->ArgNames({"vertices", "substeps", "iterations"})
    ->ArgsProduct({{20000}, {1, 2, 4}, {1, 2}})
    ->Unit(benchmark::kMicrosecond)
    ->MinTime(2.0);

BENCHMARK(BM_TissueStepRelayout)
    ->ArgNames({"vertices", "load"})
    ->ArgsProduct({{20000}, {kWorking, kAllAwake}})
    ->Unit(benchmark::kMicrosecond)
    ->MinTime(2.0);

BENCHMARK(BM_TissueStepThreads)
    ->ArgNames({"vertices", "load", "threads"})
    ->ArgsProduct({{20000, 80000}, {kWorking, kAllAwake}, {1, 2}})
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime()
    ->MinTime(2.0);
