// Collision cost per 1 ms step: two instruments moving against a deforming ~20k-triangle retina
// (build_retina_cap, with its detachment) plus an epiretinal membrane. Reports percentiles of:
//  - collision_us: the instruments' pre-step (eye rotation, shapes, FCL broad phase over the tissue
//    patches, patch refits, contact candidates, waking) — phase 0→1 of Simulation::step;
//  - tissue_us: the tissue step with the contacts resolved in its substeps (phase 1→2);
//  - reference_tissue_us: the same scene stepped with no instruments, so tissue_us − reference is
//    the in-substep contact cost (plus the extra tissue the instruments keep awake);
// and the naive alternative for comparison is in PLATFORM-NOTES (full FCL refit: 1.4–56 ms).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <vector>

#include "core/anatomy/retina_cap.hpp"
#include "core/sim/simulation.hpp"

using namespace vitreo::core;

namespace {

using Clock = std::chrono::steady_clock;

struct Probe {
  Clock::time_point t[4];
};

void probe(int phase, void* user) { static_cast<Probe*>(user)->t[phase] = Clock::now(); }

double us(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::micro>(b - a).count(); }

double percentile(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(std::min<double>(v.size() - 1, std::floor(p * static_cast<double>(v.size()))))];
}

RetinaCapOptions scene_options(int vertices) {
  RetinaCapOptions o;
  o.retina_vertices = vertices;  // 10000 vertices: ~20k triangles
  o.membrane = true;
  return o;
}

constexpr int kWarmup = 300;
constexpr int kSteps = 3000;

// Tip paths. Instrument 0 works in the bullous detachment (centre 60° from the posterior pole on
// the −x side), pushing the free retina in and out; instrument 1 sweeps over the posterior pole just
// above the membrane, brushing it.
Vec3 path(int instrument, int step) {
  const double t = step * 1e-3;
  const double a = 2.0 * std::numbers::pi * 0.5 * t;
  if (instrument == 0) {
    const double th = 60.0 * std::numbers::pi / 180.0;
    const Vec3 radial(-std::sin(th), 0.0, -std::cos(th));
    const Vec3 side = Vec3::UnitY();
    const Vec3 along = radial.cross(side);
    return radial * (9.5 + 1.0 * std::sin(2.0 * std::numbers::pi * 0.7 * t)) + 1.5 * (std::cos(a) * side + std::sin(a) * along);
  }
  return {2.0 * std::cos(a), 2.0 * std::sin(a), -11.25 + 0.15 * std::sin(2.0 * std::numbers::pi * 1.3 * t)};
}

void BM_TwoInstrumentsVsRetinaAndMembrane(benchmark::State& state) {
  for (auto _ : state) {
    RetinaCapScene scene = build_retina_cap(scene_options(static_cast<int>(state.range(0))));
    std::uint32_t tris = 0;
    for (std::uint32_t s = 0; s < scene.world.surface_count(); ++s) tris += scene.world.surface(s).triangle_count();
    InstrumentSceneOptions o;
    o.ports_mm = {Vec3(-9.0, 4.0, 7.0).normalized() * 11.8, Vec3(9.0, 4.0, 7.0).normalized() * 11.8};
    o.retina_surface = scene.retina;
    Simulation sys(scene.world, o, {{InstrumentKind::kForceps, Gauge::k23, 0, {}}, {InstrumentKind::kVitrector, Gauge::k23, 1, {}}});
    Probe pr;
    sys.set_phase_probe(probe, &pr);
    std::vector<double> collision, tissue, candidates, refits;
    double tears = 0.0, tear_steps = 0.0;
    for (int i = 0; i < kWarmup + kSteps; ++i) {
      for (std::uint32_t k = 0; k < 2; ++k) {
        const Vec3 tip = path(static_cast<int>(k), i);
        InstrumentInput in;
        in.tip_fixture_mm = tip;
        in.axis_fixture = (tip - o.ports_mm[k]).normalized();
        (void)sys.set_input(k, in);
      }
      const auto r = sys.step(1e-3);
      if (i < kWarmup) continue;
      tears += r.tissue.tears;
      tear_steps += r.tissue.tears > 0 ? 1.0 : 0.0;
      collision.push_back(us(pr.t[0], pr.t[1]));
      tissue.push_back(us(pr.t[1], pr.t[2]));
      candidates.push_back(r.candidates);
      refits.push_back(r.patches_refit);
    }
    // Reference: the same scene without instruments.
    RetinaCapScene ref = build_retina_cap(scene_options(static_cast<int>(state.range(0))));
    std::vector<double> reference;
    for (int i = 0; i < kWarmup + kSteps; ++i) {
      const auto t0 = Clock::now();
      (void)ref.world.step(1e-3);
      if (i >= kWarmup) reference.push_back(us(t0, Clock::now()));
    }
    state.counters["triangles"] = tris;
    state.counters["tears"] = tears;
    state.counters["steps_with_tears"] = tear_steps;
    state.counters["patches"] = sys.collision_stats().patches;
    state.counters["collision_p50_us"] = percentile(collision, 0.5);
    state.counters["collision_p99_us"] = percentile(collision, 0.99);
    state.counters["collision_max_us"] = percentile(collision, 1.0);
    state.counters["tissue_p50_us"] = percentile(tissue, 0.5);
    state.counters["tissue_p99_us"] = percentile(tissue, 0.99);
    state.counters["reference_tissue_p50_us"] = percentile(reference, 0.5);
    state.counters["reference_tissue_p99_us"] = percentile(reference, 0.99);
    state.counters["candidates_p50"] = percentile(candidates, 0.5);
    state.counters["candidates_max"] = percentile(candidates, 1.0);
    state.counters["patches_refit_p50"] = percentile(refits, 0.5);
  }
}

}  // namespace

BENCHMARK(BM_TwoInstrumentsVsRetinaAndMembrane)->Arg(10000)->Arg(20000)->Iterations(1)->Unit(benchmark::kMillisecond);
