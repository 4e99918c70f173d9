#pragma once
// Fixed-timestep loop driver for the physics thread.
//
// Step k is due at start + k * period on the loop's Clock and simulates time t_s = k * period_s:
// simulation time advances by exactly one period per step whatever the wall clock does, so the
// physics stays deterministic and a replay on a SimulatedClock reproduces it bit for bit.
//
// Catch-up policy (Glenn Fiedler's "Fix Your Timestep!" accumulator with a clamp against the
// "spiral of death", in explicit form):
//   * A step that starts a full period or more after its deadline is *late*. Late steps run
//     back-to-back, without sleeping, so a single slow step (an overrun) is absorbed and the loop
//     returns to its schedule.
//   * At most `max_catchup_steps` late steps run in a row. If the next step would be late too, the
//     backlog is dropped: the schedule is re-anchored to the most recent missed deadline, the
//     skipped slots are added to `dropped_steps` and `backlog_drops` counts the event. The
//     simulation then runs behind the wall clock by the dropped time (`slip_ns`), but never runs
//     faster than real time for long and never skips simulation time.
// Statistics: step duration histogram (median, p99, max), overruns (step longer than the period),
// start jitter histogram (start time minus deadline), late and dropped steps.
#include <atomic>
#include <cstdint>
#include <functional>

#include "rig/runtime/clock.hpp"
#include "rig/runtime/histogram.hpp"

namespace vitreo::runtime {

struct LoopConfig {
  std::int64_t period_ns = 1'000'000;  // 1 kHz
  std::uint32_t max_catchup_steps = 4;
  std::int64_t histogram_bucket_ns = 1000;
  std::size_t histogram_buckets = 8192;  // 1 µs buckets up to 8.192 ms
};

struct LoopStats {
  std::uint64_t steps = 0;          // cumulative, like the counters below
  std::uint64_t window_steps = 0;   // steps in the histograms: stats() since the start (or reset_histograms()),
                                    // window_stats() since the last start_window()
  std::uint64_t overruns = 0;       // steps whose duration exceeded the period
  std::uint64_t late_steps = 0;     // steps started >= one period after their deadline (caught up)
  std::uint64_t dropped_steps = 0;  // deadlines skipped by backlog drops
  std::uint64_t backlog_drops = 0;  // times the backlog was dropped
  std::int64_t slip_ns = 0;         // total wall time given up by drops (dropped_steps * period)
  std::int64_t step_p50_ns = 0, step_p99_ns = 0, step_max_ns = 0;
  double step_mean_ns = 0;
  std::int64_t jitter_p50_ns = 0, jitter_p99_ns = 0, jitter_max_ns = 0;
};

class FixedStepLoop {
 public:
  using StepFn = std::function<void(std::uint64_t step_index, double t_s)>;

  FixedStepLoop(Clock& clock, LoopConfig config, StepFn step);

  // Runs steps until request_stop() or until max_steps more steps have run; returns steps run.
  // The schedule starts at the first call; later calls continue it (and its step indices).
  std::uint64_t run(std::uint64_t max_steps = UINT64_MAX);
  void request_stop() noexcept { stop_.store(true, std::memory_order_release); }
  bool stop_requested() const noexcept { return stop_.load(std::memory_order_acquire); }

  // Loop-thread only (or after run() returned): the histograms are not synchronised.
  LoopStats stats() const;
  const DurationHistogram& step_histogram() const noexcept { return step_hist_; }
  const DurationHistogram& jitter_histogram() const noexcept { return jitter_hist_; }
  void reset_histograms() noexcept;  // both the session's and the window's
  // The same statistics over the steps since the last start_window() (the counters stay
  // cumulative): what one physics_timing_t reports, while stats() keeps the whole session's.
  LoopStats window_stats() const;
  void start_window() noexcept;
  // Index of the next step to run; readable from any thread.
  std::uint64_t next_step_index() const noexcept { return next_index_.load(std::memory_order_relaxed); }
  const LoopConfig& config() const noexcept { return config_; }

 private:
  Clock& clock_;
  LoopConfig config_;
  StepFn step_;
  std::atomic<bool> stop_{false};
  bool started_ = false;
  std::int64_t next_deadline_ns_ = 0;
  std::uint32_t consecutive_late_ = 0;
  std::atomic<std::uint64_t> next_index_{0};
  LoopStats counters_;
  DurationHistogram step_hist_;
  DurationHistogram jitter_hist_;
  DurationHistogram window_step_hist_, window_jitter_hist_;
};

}  // namespace vitreo::runtime
