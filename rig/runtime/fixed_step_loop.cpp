#include "rig/runtime/fixed_step_loop.hpp"

#include <stdexcept>
#include <utility>

namespace vitreo::runtime {

FixedStepLoop::FixedStepLoop(Clock& clock, LoopConfig config, StepFn step)
    : clock_(clock),
      config_(config),
      step_(std::move(step)),
      step_hist_(config.histogram_bucket_ns, config.histogram_buckets),
      jitter_hist_(config.histogram_bucket_ns, config.histogram_buckets),
      window_step_hist_(config.histogram_bucket_ns, config.histogram_buckets),
      window_jitter_hist_(config.histogram_bucket_ns, config.histogram_buckets) {
  if (config_.period_ns <= 0) throw std::invalid_argument("FixedStepLoop: period_ns must be > 0");
  if (!step_) throw std::invalid_argument("FixedStepLoop: no step function");
}

std::uint64_t FixedStepLoop::run(std::uint64_t max_steps) {
  const std::int64_t period = config_.period_ns;
  const double period_s = static_cast<double>(period) * 1e-9;
  if (!started_) {
    next_deadline_ns_ = clock_.now_ns();
    started_ = true;
  }
  std::uint64_t ran = 0;
  while (ran < max_steps && !stop_requested()) {
    std::int64_t now = clock_.now_ns();
    if (now < next_deadline_ns_) {
      clock_.sleep_until_ns(next_deadline_ns_);
      now = clock_.now_ns();
    }
    std::int64_t lateness = now - next_deadline_ns_;
    if (lateness >= period) {
      if (consecutive_late_ >= config_.max_catchup_steps) {
        // Catch-up budget spent: give up the backlog instead of running ever faster.
        const std::int64_t missed = lateness / period;
        counters_.dropped_steps += static_cast<std::uint64_t>(missed);
        counters_.slip_ns += missed * period;
        ++counters_.backlog_drops;
        next_deadline_ns_ += missed * period;
        lateness = now - next_deadline_ns_;
        consecutive_late_ = 0;
      } else {
        ++consecutive_late_;
        ++counters_.late_steps;
      }
    } else {
      consecutive_late_ = 0;
    }
    jitter_hist_.record(lateness);
    window_jitter_hist_.record(lateness);

    const std::uint64_t index = next_index_.load(std::memory_order_relaxed);
    const std::int64_t t0 = clock_.now_ns();
    step_(index, static_cast<double>(index) * period_s);
    const std::int64_t dt = clock_.now_ns() - t0;
    step_hist_.record(dt);
    window_step_hist_.record(dt);
    if (dt > period) ++counters_.overruns;
    ++counters_.steps;
    next_index_.store(index + 1, std::memory_order_relaxed);
    next_deadline_ns_ += period;
    ++ran;
  }
  return ran;
}

namespace {
LoopStats with_histograms(LoopStats s, const DurationHistogram& step, const DurationHistogram& jitter) {
  s.window_steps = step.count();
  s.step_p50_ns = step.quantile_ns(0.5);
  s.step_p99_ns = step.quantile_ns(0.99);
  s.step_max_ns = step.max_ns();
  s.step_mean_ns = step.mean_ns();
  s.jitter_p50_ns = jitter.quantile_ns(0.5);
  s.jitter_p99_ns = jitter.quantile_ns(0.99);
  s.jitter_max_ns = jitter.max_ns();
  return s;
}
}  // namespace

LoopStats FixedStepLoop::stats() const { return with_histograms(counters_, step_hist_, jitter_hist_); }

LoopStats FixedStepLoop::window_stats() const { return with_histograms(counters_, window_step_hist_, window_jitter_hist_); }

void FixedStepLoop::start_window() noexcept {
  window_step_hist_.reset();
  window_jitter_hist_.reset();
}

void FixedStepLoop::reset_histograms() noexcept {
  step_hist_.reset();
  jitter_hist_.reset();
  start_window();
}

}  // namespace vitreo::runtime
