#pragma once
// Time is injected (as in ArduPilot's SITL and Drake's contexts): the loop driver, the replayer and
// the telemetry pacing ask a Clock for "now" and to wait, so tests and replay run on a simulated
// clock that jumps instead of sleeping, and the rig runs on the monotonic wall clock.
#include <atomic>
#include <cstdint>

namespace vitreo::runtime {

class Clock {
 public:
  virtual ~Clock() = default;
  // Monotonic nanoseconds from an arbitrary origin.
  virtual std::int64_t now_ns() const noexcept = 0;
  // Returns once now_ns() >= t_ns (immediately if already past).
  virtual void sleep_until_ns(std::int64_t t_ns) noexcept = 0;
};

// CLOCK_MONOTONIC with absolute-deadline sleeps (no drift from relative sleeps). spin_margin_ns
// busy-waits the last stretch before a deadline, trading a little CPU for wake-up precision where
// the kernel's timer slack is coarse; 0 disables spinning.
class SteadyClock final : public Clock {
 public:
  explicit SteadyClock(std::int64_t spin_margin_ns = 0) : spin_margin_ns_(spin_margin_ns) {}
  std::int64_t now_ns() const noexcept override;
  void sleep_until_ns(std::int64_t t_ns) noexcept override;

 private:
  std::int64_t spin_margin_ns_;
};

// Simulated time: sleeping jumps the clock to the deadline; work "takes time" only when a test (or
// a model of the workload) calls advance(). Thread-safe, but meant for one driving thread.
class SimulatedClock final : public Clock {
 public:
  explicit SimulatedClock(std::int64_t start_ns = 0) : now_(start_ns) {}
  std::int64_t now_ns() const noexcept override { return now_.load(std::memory_order_acquire); }
  void sleep_until_ns(std::int64_t t_ns) noexcept override {
    std::int64_t cur = now_.load(std::memory_order_acquire);
    while (cur < t_ns && !now_.compare_exchange_weak(cur, t_ns, std::memory_order_acq_rel)) {
    }
  }
  void advance(std::int64_t dt_ns) noexcept { now_.fetch_add(dt_ns, std::memory_order_acq_rel); }

 private:
  std::atomic<std::int64_t> now_;
};

}  // namespace vitreo::runtime
