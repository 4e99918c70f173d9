// Fixed-step loop on a SimulatedClock: the step function "takes time" by advancing the clock, so
// overruns, catch-up and backlog drops are exact and nothing sleeps.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "rig/runtime/clock.hpp"
#include "rig/runtime/fixed_step_loop.hpp"
#include "rig/runtime/histogram.hpp"

using namespace vitreo::runtime;

namespace {
constexpr std::int64_t kUs = 1000;
constexpr std::int64_t kMs = 1000 * kUs;
}  // namespace

TEST(DurationHistogram, QuantilesOfKnownInputs) {
  DurationHistogram h(1 * kUs, 4096);
  // 1..1000 µs once each: median = 500 µs, p99 = 990 µs, max = 1000 µs.
  for (int i = 1000; i >= 1; --i) h.record(i * kUs);
  EXPECT_EQ(h.count(), 1000u);
  EXPECT_EQ(h.quantile_ns(0.5), 500 * kUs);
  EXPECT_EQ(h.quantile_ns(0.99), 990 * kUs);
  EXPECT_EQ(h.quantile_ns(1.0), 1000 * kUs);
  EXPECT_EQ(h.quantile_ns(0.0), 1 * kUs);
  EXPECT_EQ(h.max_ns(), 1000 * kUs);
  EXPECT_EQ(h.min_ns(), 1 * kUs);
  EXPECT_DOUBLE_EQ(h.mean_ns(), 500.5 * kUs);
  // Sub-bucket values report the bucket's lower edge: exact to one bucket width.
  DurationHistogram g(1 * kUs, 4096);
  g.record(300 * kUs + 999);
  g.record(300 * kUs + 1);
  EXPECT_EQ(g.quantile_ns(0.5), 300 * kUs + 1);  // clamped to the exact minimum
  // Beyond the range: the overflow bucket reports the exact maximum.
  g.record(50 * kMs);
  EXPECT_EQ(g.quantile_ns(1.0), 50 * kMs);
  EXPECT_EQ(g.quantile_ns(0.99), 50 * kMs);
  g.reset();
  EXPECT_EQ(g.count(), 0u);
  EXPECT_EQ(g.quantile_ns(0.5), 0);
}

TEST(FixedStepLoop, RunsOnScheduleWithSimulationTimeFromTheStepIndex) {
  SimulatedClock clock(5 * kMs);
  std::vector<std::int64_t> starts;
  std::vector<double> times;
  std::vector<std::uint64_t> indices;
  FixedStepLoop loop(clock, LoopConfig{}, [&](std::uint64_t k, double t_s) {
    starts.push_back(clock.now_ns());
    indices.push_back(k);
    times.push_back(t_s);
    clock.advance(300 * kUs);  // a 300 µs step
  });
  EXPECT_EQ(loop.run(10), 10u);
  for (std::size_t k = 0; k < 10; ++k) {
    EXPECT_EQ(starts[k], 5 * kMs + static_cast<std::int64_t>(k) * kMs) << k;
    EXPECT_EQ(indices[k], k);
    EXPECT_DOUBLE_EQ(times[k], static_cast<double>(k) * 1e-3);
  }
  const LoopStats s = loop.stats();
  EXPECT_EQ(s.steps, 10u);
  EXPECT_EQ(s.overruns, 0u);
  EXPECT_EQ(s.late_steps, 0u);
  EXPECT_EQ(s.dropped_steps, 0u);
  EXPECT_EQ(s.step_p50_ns, 300 * kUs);
  EXPECT_EQ(s.step_max_ns, 300 * kUs);
  EXPECT_EQ(s.jitter_max_ns, 0);
  // A second run continues the same schedule and indices.
  EXPECT_EQ(loop.run(2), 2u);
  EXPECT_EQ(indices.back(), 11u);
  EXPECT_EQ(starts.back(), 5 * kMs + 11 * kMs);
}

TEST(FixedStepLoop, OneOverrunIsCaughtUpBackToBack) {
  SimulatedClock clock;
  std::vector<std::int64_t> starts;
  LoopConfig cfg;
  cfg.max_catchup_steps = 4;
  FixedStepLoop loop(clock, cfg, [&](std::uint64_t k, double) {
    starts.push_back(clock.now_ns());
    clock.advance(k == 3 ? 2500 * kUs : 100 * kUs);  // step 3 takes 2.5 periods
  });
  loop.run(10);
  // Step 3 runs 0..3.5 ms late end at 5.5 ms; steps 4 and 5 (due 4, 5 ms) start late back-to-back,
  // step 6 (due 6 ms) is on time again.
  EXPECT_EQ(starts[4], 5500 * kUs);
  EXPECT_EQ(starts[5], 5600 * kUs);
  EXPECT_EQ(starts[6], 6000 * kUs);
  const LoopStats s = loop.stats();
  EXPECT_EQ(s.overruns, 1u);
  EXPECT_EQ(s.late_steps, 1u) << "only step 4 started >= one period late (1.5 ms); step 5 was 0.6 ms late";
  EXPECT_EQ(s.dropped_steps, 0u);
  EXPECT_EQ(s.backlog_drops, 0u);
  EXPECT_EQ(s.jitter_max_ns, 1500 * kUs);
  EXPECT_EQ(s.step_max_ns, 2500 * kUs);
  EXPECT_EQ(s.step_p50_ns, 100 * kUs);
}

TEST(FixedStepLoop, BacklogBeyondTheCatchUpBudgetIsDroppedAndCounted) {
  SimulatedClock clock;
  std::vector<std::int64_t> starts;
  std::vector<std::uint64_t> indices;
  LoopConfig cfg;
  cfg.max_catchup_steps = 3;
  FixedStepLoop loop(clock, cfg, [&](std::uint64_t k, double) {
    starts.push_back(clock.now_ns());
    indices.push_back(k);
    clock.advance(k == 5 ? 10100 * kUs : 100 * kUs);  // a 10.1 ms stall at step 5
  });
  loop.run(12);
  // Step 5 ends at 15.1 ms. Steps 6, 7, 8 are late and run back-to-back (15.1, 15.2, 15.3 ms).
  // Step 9 (due 9 ms, 6.4 ms late) would be the 4th late step: the 6 whole missed periods are
  // dropped, its deadline becomes 15 ms, and it runs at once; step 10 is due at 16 ms.
  EXPECT_EQ(starts[6], 15100 * kUs);
  EXPECT_EQ(starts[7], 15200 * kUs);
  EXPECT_EQ(starts[8], 15300 * kUs);
  EXPECT_EQ(starts[9], 15400 * kUs);
  EXPECT_EQ(starts[10], 16000 * kUs);
  EXPECT_EQ(starts[11], 17000 * kUs);
  for (std::size_t i = 0; i < indices.size(); ++i) EXPECT_EQ(indices[i], i) << "no step index is skipped";
  const LoopStats s = loop.stats();
  EXPECT_EQ(s.steps, 12u);
  EXPECT_EQ(s.overruns, 1u);
  EXPECT_EQ(s.late_steps, 3u);
  EXPECT_EQ(s.dropped_steps, 6u);
  EXPECT_EQ(s.backlog_drops, 1u);
  EXPECT_EQ(s.slip_ns, 6 * kMs);
  EXPECT_EQ(s.jitter_max_ns, 9100 * kUs);  // step 6: due 6 ms, started 15.1 ms
}

TEST(FixedStepLoop, ZeroCatchUpDropsImmediately) {
  SimulatedClock clock;
  LoopConfig cfg;
  cfg.max_catchup_steps = 0;
  std::vector<std::int64_t> starts;
  FixedStepLoop loop(clock, cfg, [&](std::uint64_t k, double) {
    starts.push_back(clock.now_ns());
    clock.advance(k == 0 ? 3500 * kUs : 10 * kUs);
  });
  loop.run(3);
  EXPECT_EQ(starts[1], 3500 * kUs);  // re-anchored to the 3 ms deadline, 0.5 ms late
  EXPECT_EQ(starts[2], 4000 * kUs);
  EXPECT_EQ(loop.stats().dropped_steps, 2u);
  EXPECT_EQ(loop.stats().late_steps, 0u);
}

TEST(FixedStepLoop, HistogramQuantilesFromAKnownStepTimeMix) {
  SimulatedClock clock;
  // 1000 steps: 980 at 200 µs, 15 at 600 µs, 5 at 900 µs → median 200, p99 600, max 900.
  FixedStepLoop loop(clock, LoopConfig{}, [&](std::uint64_t k, double) {
    const std::uint64_t r = (k * 7919) % 1000;  // a permutation of 0..999
    clock.advance(r < 980 ? 200 * kUs : (r < 995 ? 600 * kUs : 900 * kUs));
  });
  loop.run(1000);
  const LoopStats s = loop.stats();
  EXPECT_EQ(s.step_p50_ns, 200 * kUs);
  EXPECT_EQ(s.step_p99_ns, 600 * kUs);
  EXPECT_EQ(s.step_max_ns, 900 * kUs);
  EXPECT_EQ(s.overruns, 0u);
  EXPECT_EQ(s.jitter_max_ns, 0);
}

TEST(FixedStepLoop, StopRequestedFromTheStepEndsTheRun) {
  SimulatedClock clock;
  FixedStepLoop* self = nullptr;
  FixedStepLoop loop(clock, LoopConfig{}, [&](std::uint64_t k, double) {
    if (k == 6) self->request_stop();
  });
  self = &loop;
  EXPECT_EQ(loop.run(), 7u);
  EXPECT_EQ(loop.next_step_index(), 7u);
}
