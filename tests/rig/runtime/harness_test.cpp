// The thread harness with real threads: physics on a SimulatedClock (so it runs as fast as it can),
// a render consumer on a triple buffer and a telemetry consumer on an SPSC ring. Consumers that
// stall never slow physics down or make it wait: physics only ever counts drops.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <stdexcept>
#include <thread>

#include "rig/runtime/clock.hpp"
#include "rig/runtime/spsc_ring.hpp"
#include "rig/runtime/thread_harness.hpp"
#include "rig/runtime/triple_buffer.hpp"

using namespace vitreo::runtime;

namespace {
struct Snapshot {
  std::uint64_t step = 0;
  double t_s = 0;
};
}  // namespace

TEST(ThreadHarness, PhysicsFeedsConsumersWithoutWaitingAndServicesDrainAtStop) {
  SimulatedClock clock;
  TripleBuffer<Snapshot> render_box;
  SpscRing<std::uint64_t> telemetry_ring(1024);
  constexpr std::uint64_t kSteps = 20000;

  HarnessConfig cfg;
  cfg.max_steps = kSteps;
  ThreadHarness h(clock, cfg, [&](std::uint64_t k, double t_s) {
    clock.advance(10'000);  // 10 µs of simulated work
    Snapshot& s = render_box.write_slot();
    s.step = k;
    s.t_s = t_s;
    render_box.publish();
    telemetry_ring.try_push(k);
  });
  std::uint64_t rendered_last = 0, render_frames = 0, render_backwards = 0;
  h.add_service("render", std::chrono::milliseconds(2), [&] {
    if (render_box.update()) {
      const Snapshot& s = render_box.read_slot();
      if (s.step < rendered_last) ++render_backwards;
      rendered_last = s.step;
      ++render_frames;
    }
  });
  std::uint64_t received = 0, last = 0, out_of_order = 0;
  h.add_service("telemetry", std::chrono::milliseconds(1), [&] {
    std::uint64_t v;
    while (telemetry_ring.try_pop(v)) {
      if (received && v <= last) ++out_of_order;
      last = v;
      ++received;
    }
  });
  h.start();
  h.wait_physics();
  EXPECT_TRUE(h.physics_done());
  h.stop();
  EXPECT_EQ(h.loop().stats().steps, kSteps);
  EXPECT_EQ(received + telemetry_ring.dropped(), kSteps) << "every telemetry item delivered or counted";
  EXPECT_EQ(out_of_order, 0u);
  EXPECT_EQ(render_backwards, 0u);
  EXPECT_EQ(rendered_last, kSteps - 1) << "the final drain call sees the last snapshot";
  EXPECT_GE(render_frames, 1u);
}

TEST(ThreadHarness, StalledConsumersDoNotStopPhysics) {
  SimulatedClock clock;
  SpscRing<std::uint64_t> ring(64);
  std::atomic<bool> release{false};
  HarnessConfig cfg;
  cfg.max_steps = 5000;
  ThreadHarness h(clock, cfg, [&](std::uint64_t k, double) {
    clock.advance(1000);
    ring.try_push(k);
  });
  // A consumer that is stuck until physics has finished: if physics waited on it, this deadlocks
  // (and the ctest timeout fails the test).
  h.add_service("stuck", std::chrono::milliseconds(1), [&] {
    while (!release.load(std::memory_order_acquire)) std::this_thread::yield();
  });
  h.start();
  h.wait_physics();
  release.store(true, std::memory_order_release);
  h.stop();
  EXPECT_EQ(h.loop().stats().steps, 5000u);
  EXPECT_EQ(ring.dropped(), 5000u - 64u) << "the ring filled and the rest was dropped, not waited for";
}

TEST(ThreadHarness, PhysicsExceptionIsRethrownToTheCallerAndServiceExceptionsAreContained) {
  SimulatedClock clock;
  HarnessConfig cfg;
  cfg.max_steps = 1000;
  ThreadHarness h(clock, cfg, [&](std::uint64_t k, double) {
    clock.advance(1000);
    if (k == 5) throw std::runtime_error("solver diverged");
  });
  std::atomic<int> calls{0};
  h.add_service("flaky", std::chrono::milliseconds(1), [&] {
    ++calls;
    throw std::runtime_error("sink unavailable");
  });
  h.start();
  EXPECT_THROW(h.wait_physics(), std::runtime_error);
  EXPECT_TRUE(h.physics_done());
  EXPECT_EQ(h.loop().next_step_index(), 5u) << "physics stopped at the failing step";
  EXPECT_NO_THROW(h.stop());  // already collected
  EXPECT_GE(calls.load(), 1);
  EXPECT_EQ(h.service_errors(), static_cast<std::uint64_t>(calls.load()));
}
