// Cost of the session metrics on a built case with every criterion kind but gel_removed (retina of N
// vertices, membrane, detachment, cut path and laser ring):
//  - BM_Observe/N: SessionMetrics::observe() after each 1 ms Simulation step (the step itself is
//    not timed), two instruments moving, one pressing the retina — per-step cost, p50/p99 in µs;
//  - BM_CriteriaAndScore/N: criteria() + score() after half the cut path has been cut and 16 laser
//    spots placed (the scans a telemetry-rate score update does), p50/p99 in µs.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <vector>

#include "core/metrics/session_metrics.hpp"
#include "core/topology/cut.hpp"

using namespace vitreo::core;

namespace {

using Clock = std::chrono::steady_clock;
constexpr double kDeg = std::numbers::pi / 180.0;

double percentile(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(std::min<double>(static_cast<double>(v.size() - 1), std::floor(p * static_cast<double>(v.size()))))];
}

SceneDescription bench_case(int vertices) {
  SceneDescription d;
  d.name = "metrics_bench";
  d.anatomy.retina_vertices = vertices;
  d.anatomy.gel_shells = 0;  // so the laser reaches the retina (the gel measure is a plain O(n) scan)
  d.texture_size_px = 64;
  d.materials = default_materials();
  MembraneSpec erm;
  erm.name = "erm";
  erm.center = {8.0, 0.0};
  erm.size_mm = 3.0;
  d.membranes.push_back(erm);
  d.detachments.push_back({"fluid", {60.0, 300.0}, 20.0, 150.0});
  GuideSpec line;
  line.name = "line";
  line.kind = GuideKind::kCutPath;
  line.points = {{40.0, 200.0}, {45.0, 220.0}, {40.0, 240.0}};
  d.guides.push_back(line);
  GuideSpec ring;
  ring.name = "ring";
  ring.kind = GuideKind::kLaserRing;
  ring.center = {35.0, 60.0};
  d.guides.push_back(ring);
  d.criteria = {{CriterionKind::kMembraneRemoved, "erm", 0.9},
                {CriterionKind::kMembraneReleased, "erm", 0.9}, {CriterionKind::kPathCut, "line", 0.8},
                {CriterionKind::kLaserCoverage, "ring", 0.8},   {CriterionKind::kDrained, "fluid", 0.05},
                {CriterionKind::kRetinaFlat, "", 0.3},          {CriterionKind::kTimeLimit, "", 600.0}};
  return d;
}

struct Bench {
  Scene scene;
  std::unique_ptr<Simulation> sys;
  std::unique_ptr<SessionMetrics> metrics;
  Vec3 port[2];
  explicit Bench(int vertices) : scene(build_scene(bench_case(vertices), {false, false})) {
    InstrumentSceneOptions o;
    for (const auto& p : scene.eye.ports) {
      if (p.name == "working_1") port[0] = p.inner_mm;
      if (p.name == "working_2") port[1] = p.inner_mm;
    }
    o.ports_mm = {port[0], port[1]};
    o.retina_surface = scene.retina;
    sys = std::make_unique<Simulation>(
        scene.world, o, std::vector<InstrumentDescription>{{InstrumentKind::kLightPipe, Gauge::k23, 1, {}}, {InstrumentKind::kEndolaser, Gauge::k23, 0, {}}});
    metrics = std::make_unique<SessionMetrics>(scene, sys.get());
  }
  void aim(std::uint32_t i, const Vec3& target, double insertion, bool trigger = false) {
    InstrumentInput in = InstrumentInput::through_port(port[i == 0 ? 1 : 0], (target - port[i == 0 ? 1 : 0]).normalized(), insertion);
    in.trigger = trigger;
    in.laser_power_mw = 800.0;
    (void)sys->set_input(i, in);
  }
};

void BM_Observe(benchmark::State& state) {
  Bench b(static_cast<int>(state.range(0)));
  std::vector<double> samples;
  int step = 0;
  for (auto _ : state) {
    const double t = step * 1e-3;
    const Vec3 pole = b.scene.eye.wall_point(20.0 * kDeg, (180.0 + 40.0 * std::sin(t)) * kDeg);
    b.aim(0, pole, 8.0);
    // The second instrument reaches to (and a little into) the retina and back.
    const Vec3 target = b.scene.eye.wall_point(35.0 * kDeg, 60.0 * kDeg);
    const double reach = (target - b.port[0]).norm();
    b.aim(1, target, reach - 0.6 + 0.8 * (0.5 + 0.5 * std::sin(6.0 * t)));
    b.sys->step(1e-3);
    const auto t0 = Clock::now();
    const Status st = b.metrics->observe(1e-3);
    const auto t1 = Clock::now();
    benchmark::DoNotOptimize(st);
    samples.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
    state.SetIterationTime(std::chrono::duration<double>(t1 - t0).count());
    ++step;
  }
  state.counters["p50_us"] = percentile(samples, 0.5);
  state.counters["p99_us"] = percentile(samples, 0.99);
  state.counters["retina_contacts"] = b.metrics->totals().retina_contacts;
}

void BM_CriteriaAndScore(benchmark::State& state) {
  Bench b(static_cast<int>(state.range(0)));
  // Half the cut path cut, 16 laser spots on the ring: the scans have real work.
  const Guide& line = b.scene.guides[0];
  Cutter cutter(b.scene.world.surface(b.scene.retina));
  const auto blade = [](const Vec3& p) { return BladeEdge{p - 0.6 * p.normalized(), p + 0.6 * p.normalized()}; };
  for (std::size_t k = 0; k + 1 < line.polyline_mm.size() / 2; ++k) (void)cutter.sweep(blade(line.polyline_mm[k]), blade(line.polyline_mm[k + 1]));
  const Guide& ring = b.scene.guides[1];
  for (std::size_t k = 0; k < 64; k += 4) {
    b.aim(1, ring.polyline_mm[k], 4.0, false);
    b.sys->step(1e-3);
    (void)b.metrics->observe(1e-3);
    b.aim(1, ring.polyline_mm[k], 4.0, true);
    b.sys->step(1e-3);
    (void)b.metrics->observe(1e-3);
  }
  std::vector<double> samples;
  for (auto _ : state) {
    const auto t0 = Clock::now();
    const ScoreCard& card = b.metrics->score();
    const auto t1 = Clock::now();
    benchmark::DoNotOptimize(card.total);
    samples.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
    state.SetIterationTime(std::chrono::duration<double>(t1 - t0).count());
  }
  state.counters["p50_us"] = percentile(samples, 0.5);
  state.counters["p99_us"] = percentile(samples, 0.99);
  state.counters["burns"] = static_cast<double>(b.sys->burns().size());
}

}  // namespace

BENCHMARK(BM_Observe)->Arg(20000)->UseManualTime()->Iterations(3000)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_CriteriaAndScore)->Arg(20000)->UseManualTime()->Iterations(300)->Unit(benchmark::kMicrosecond);
BENCHMARK_MAIN();
