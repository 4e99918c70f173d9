#pragma once
// Telemetry publisher that never blocks its producers.
//
// Each producing thread gets its own TelemetrySource: a bounded SPSC ring of fixed-size items (one
// queue per publisher, like PX4 uORB's per-topic queues, so no two producers ever contend). A
// single telemetry thread owns the lcm::LCM object and calls pump(): it drains every source,
// converts items to the generated vitreo_lcm types and publishes. If the telemetry thread falls
// behind — a slow network, a subscriber handler that stalls it — rings fill and further pushes are
// dropped and counted; the producer's cost stays one copy into a ring slot.
//
// Threading: all LCM calls (publish, subscribe, handle) happen on the thread that calls pump() and
// handle_incoming(); producers only touch their source.
#include <cstdint>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "rig/runtime/fixed_step_loop.hpp"
#include "rig/runtime/spsc_ring.hpp"
#include "rig/telemetry/channels.hpp"
#include "rig/telemetry/items.hpp"
#include "rig/telemetry/lcm_subscribe.hpp"
#include "rig/telemetry/wall_time.hpp"

namespace vitreo::telemetry {

class TelemetrySource {
 public:
  TelemetrySource(std::string name, std::size_t capacity) : name_(std::move(name)), ring_(capacity) {}
  // Producer thread only. Wait-free; false when the ring was full (the item is dropped and counted).
  bool push(const TelemetryItem& item) noexcept { return ring_.try_push(item); }
  std::uint64_t dropped() const noexcept { return ring_.dropped(); }
  std::uint64_t pushed() const noexcept { return ring_.pushed(); }
  const std::string& name() const noexcept { return name_; }

 private:
  friend class TelemetryPublisher;
  std::string name_;
  runtime::SpscRing<TelemetryItem> ring_;
};

struct PublisherConfig {
  std::string url = kDefaultLcmUrl;
  std::size_t default_capacity = 4096;  // items per source (~0.5 KiB each)
};

class TelemetryPublisher {
 public:
  // Throws std::runtime_error when the LCM URL cannot be opened (e.g. udpm without a multicast route).
  explicit TelemetryPublisher(PublisherConfig config = {});

  // Before the producers and the telemetry thread start. The reference stays valid.
  TelemetrySource& add_source(std::string name, std::size_t capacity = 0);

  // Telemetry thread: publishes everything queued; returns the number of messages published.
  std::size_t pump();
  // Telemetry thread: dispatches incoming messages (operator commands) without waiting.
  int handle_incoming(int max_messages = 64);

  lcm::LCM& lcm() noexcept { return lcm_; }
  // What arrives on the channels this process subscribes to (subscriptions count into it).
  ReceiveStats& receive_stats() noexcept { return receive_stats_; }
  // Telemetry thread: one receive_status_t (VITREO_RECEIVE_STATUS) listing every channel counted in
  // receive_stats(); nothing when none is. CHANNELS.md: 1 Hz and once at the end.
  void publish_receive_status(const std::string& process);
  std::uint64_t published() const noexcept { return published_; }
  std::uint64_t publish_errors() const noexcept { return publish_errors_; }
  std::uint64_t dropped() const noexcept;  // sum over sources (any thread)

 private:
  void publish_item(const TelemetryItem& item);

  PublisherConfig config_;
  lcm::LCM lcm_;
  ReceiveStats receive_stats_;
  std::deque<TelemetrySource> sources_;
  std::uint64_t published_ = 0;
  std::uint64_t publish_errors_ = 0;
};

// Physics-side helper: call on_step() from inside the step callback; every `every_steps` steps it
// pushes a PhysicsTiming for the steps since its last report (the loop's window_stats()) and starts
// a new window; the loop's stats() keep the whole session's. Cost: one quantile scan of the window's
// histograms per report (a few µs at 10 Hz), no allocation.
class TimingReporter {
 public:
  TimingReporter(runtime::FixedStepLoop& loop, TelemetrySource& out, std::uint32_t every_steps = 100)
      : loop_(loop), out_(out), every_(every_steps ? every_steps : 1) {}
  // The number of steps between reports that gives `hz` at the loop's period (at least 1).
  static std::uint32_t steps_for_rate(std::int64_t period_ns, double hz);
  void on_step(std::uint64_t step, bool paused);

 private:
  runtime::FixedStepLoop& loop_;
  TelemetrySource& out_;
  std::uint32_t every_;
};

}  // namespace vitreo::telemetry
