#pragma once
// The rig's thread layout: one physics thread running the FixedStepLoop (optionally real-time), and
// any number of periodic service threads (render hand-off consumer, telemetry publisher, recorder)
// at normal priority. The threads share nothing but wait-free mailboxes (TripleBuffer, SpscRing)
// that the caller wires into the step and service functions, so the physics thread never takes a
// lock, waits on a condition or makes a blocking call on their behalf. Stopping joins physics first,
// then gives each service one final call so it drains what physics produced last.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "rig/runtime/fixed_step_loop.hpp"
#include "rig/runtime/realtime.hpp"

namespace vitreo::runtime {

struct HarnessConfig {
  LoopConfig loop;
  bool physics_realtime = false;  // the rig turns this on; tests leave it off
  RealtimeConfig physics_rt;
  std::uint64_t max_steps = UINT64_MAX;  // physics stops by itself after this many steps
  // Nice value for service threads. Lowering their priority needs no privilege, so even where
  // SCHED_FIFO is refused the scheduler favours physics over a busy render or telemetry thread.
  int service_nice = 10;
};

class ThreadHarness {
 public:
  ThreadHarness(Clock& physics_clock, HarnessConfig config, FixedStepLoop::StepFn physics_step);
  ~ThreadHarness();
  ThreadHarness(const ThreadHarness&) = delete;
  ThreadHarness& operator=(const ThreadHarness&) = delete;

  // Before start(): a service thread calling fn every period (on the steady wall clock).
  void add_service(std::string name, std::chrono::nanoseconds period, std::function<void()> fn);

  void start();
  // Stops physics, joins it, then stops and joins services (each gets one final call). Idempotent.
  // Rethrows an exception that ended the physics thread (once).
  void stop();
  // Blocks until the physics thread has finished (max_steps reached, stop(), or an exception from
  // the step function, which is rethrown here).
  void wait_physics();
  // Exceptions thrown by service functions are logged and counted; the service keeps running.
  std::uint64_t service_errors() const noexcept { return service_errors_.load(std::memory_order_relaxed); }
  bool physics_done() const noexcept;

  // After wait_physics()/stop(): the loop's statistics and the real-time outcome.
  const FixedStepLoop& loop() const noexcept { return loop_; }
  // Mutable access for the physics thread itself (e.g. TimingReporter resetting histogram windows).
  FixedStepLoop& loop() noexcept { return loop_; }
  const RealtimeOutcome& physics_realtime_outcome() const noexcept { return rt_outcome_; }

 private:
  struct Service {
    std::string name;
    std::chrono::nanoseconds period;
    std::function<void()> fn;
    std::thread thread;
    std::uint64_t calls = 0;
  };
  void join_physics();

  HarnessConfig config_;
  FixedStepLoop loop_;
  RealtimeOutcome rt_outcome_;
  std::thread physics_;
  std::atomic<bool> physics_done_{false};
  std::exception_ptr physics_error_;
  std::atomic<std::uint64_t> service_errors_{0};
  std::vector<std::unique_ptr<Service>> services_;
  std::mutex mu_;  // services' sleep/stop signalling only: never touched by physics
  std::condition_variable cv_;
  bool services_stop_ = false;
  bool started_ = false;
  bool stopped_ = false;
};

}  // namespace vitreo::runtime
