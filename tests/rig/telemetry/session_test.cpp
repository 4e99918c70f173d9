// A whole session with a stand-in for the simulation: a simulated device thread feeds a
// latest-sample mailbox at its own (jittery) pace, the physics thread runs at 1 kHz on the wall
// clock, takes whatever sample is newest each step, records it and integrates a toy model; telemetry
// and recorder threads run beside it. Which sample each step sees depends on thread timing, so only
// the recording can reproduce the run: replaying it step by step on a simulated clock must end in
// the same state bits, and far faster than real time.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <thread>

#include "rig/runtime/clock.hpp"
#include "rig/runtime/fixed_step_loop.hpp"
#include "rig/runtime/thread_harness.hpp"
#include "rig/runtime/triple_buffer.hpp"
#include "rig/telemetry/commands.hpp"
#include "rig/telemetry/publisher.hpp"
#include "rig/telemetry/recording.hpp"

using namespace vitreo;
using telemetry::RecordedInput;

namespace {
// Stand-in for the core: deterministic, sensitive to every input bit and to the step it arrives at.
struct ToyModel {
  double x[3] = {0, 0, 12.0}, v[3] = {0, 0, 0}, target[3] = {0, 0, 12.0};
  std::uint64_t inputs = 0;
  void apply(const RecordedInput& in) {
    const auto& tip = std::get<telemetry::TrackerSample>(in.what).tip_mm;
    for (std::size_t i = 0; i < 3; ++i) target[i] = tip[i];
    ++inputs;
  }
  void step(double dt) {
    for (int i = 0; i < 3; ++i) {
      v[i] = 0.98 * v[i] + dt * 400.0 * (target[i] - x[i]);
      x[i] += dt * v[i];
    }
  }
  std::uint64_t hash() const {
    std::uint64_t h = 1469598103934665603ULL;
    auto mix = [&](double d) {
      std::uint64_t b;
      std::memcpy(&b, &d, sizeof b);
      h = (h ^ b) * 1099511628211ULL;
    };
    for (int i = 0; i < 3; ++i) {
      mix(x[i]);
      mix(v[i]);
    }
    return h ^ inputs;
  }
};

std::int64_t mono_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}
}  // namespace

TEST(Session, RecordedSessionReplaysToTheSameStateHash) {
  const std::string path = ::testing::TempDir() + "session-" + std::to_string(::getpid()) + ".lcmlog";
  constexpr std::uint64_t kSteps = 400;
  const double dt = 1e-3;

  runtime::TripleBuffer<RecordedInput> tracker_box;
  telemetry::TelemetryPublisher pub(telemetry::PublisherConfig{"memq://", 1024});
  telemetry::TelemetrySource& physics_tx = pub.add_source("physics");
  telemetry::CommandServer commands(pub.lcm());
  telemetry::RecordingHeader header;
  header.case_id = "toy";
  header.config_text = "toy model, tracker at ~5 kHz";
  header.snapshot_hash = "0000000000000001";
  telemetry::Recorder recorder(path, header);

  ToyModel live;
  std::int64_t last_seq = -1;
  runtime::SteadyClock wall;
  runtime::HarnessConfig cfg;
  cfg.max_steps = kSteps;
  runtime::ThreadHarness h(wall, cfg, [&](std::uint64_t k, double t_s) {
    telemetry::AcceptedCommand cmd;
    while (commands.poll(cmd)) {
    }
    if (tracker_box.update() && tracker_box.read_slot().sequence != last_seq) {
      RecordedInput in = tracker_box.read_slot();
      last_seq = in.sequence;
      in.step = static_cast<std::int64_t>(k);
      recorder.push(in);
      live.apply(in);
    }
    live.step(dt);
    if (k % 4 == 0) {
      telemetry::InstrumentState st;
      st.step = static_cast<std::int64_t>(k);
      st.t_s = t_s;
      for (int i = 0; i < 3; ++i) st.tip_mm[i] = live.x[i];
      physics_tx.push(st);
    }
  });
  h.add_service("telemetry", std::chrono::milliseconds(2), [&] {
    pub.pump();
    pub.handle_incoming();
  });
  h.add_service("recorder", std::chrono::milliseconds(10), [&] { recorder.pump(wall.now_ns()); });

  std::atomic<bool> stop_device{false};
  std::thread device([&] {  // a simulated tracker: ~5 kHz with scheduler jitter
    for (std::int64_t seq = 0; !stop_device.load(std::memory_order_acquire); ++seq) {
      RecordedInput& s = tracker_box.write_slot();
      s.host_time_us = mono_us();
      s.device_time_us = seq * 200;
      s.device_id = 1;
      s.sequence = seq;
      const double a = static_cast<double>(seq) * 0.01;
      telemetry::TrackerSample pose;
      pose.tip_mm = {3.0 * std::sin(a), 2.0 * std::cos(1.3 * a), 12.0 - 0.5 * std::sin(0.7 * a)};
      s.what = pose;
      tracker_box.publish();
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
  });
  h.start();
  h.wait_physics();
  stop_device.store(true, std::memory_order_release);
  device.join();
  h.stop();
  ASSERT_TRUE(recorder.finish(telemetry::RecordingEnd{static_cast<std::int64_t>(kSteps), live.hash(), "toy done"}));
  ASSERT_EQ(h.loop().stats().steps, kSteps);
  ASSERT_EQ(recorder.dropped(), 0u);
  ASSERT_GT(live.inputs, kSteps / 2) << "the device kept up";

  // Replay: same model, inputs handed to the steps that consumed them, simulated clock.
  const telemetry::Recording rec = telemetry::read_recording(path);
  EXPECT_EQ(rec.verdict, telemetry::RecordingVerdict::Complete) << rec.describe();
  EXPECT_EQ(rec.header.case_id, "toy");
  ASSERT_EQ(rec.inputs.size(), live.inputs);
  ToyModel replayed;
  telemetry::InputCursor cursor(rec);
  runtime::SimulatedClock sim;
  runtime::FixedStepLoop loop(sim, runtime::LoopConfig{}, [&](std::uint64_t k, double) {
    cursor.feed_through_step(static_cast<std::int64_t>(k), [&](const RecordedInput& in) { replayed.apply(in); });
    replayed.step(dt);
  });
  const std::int64_t t0 = wall.now_ns();
  loop.run(kSteps);
  const double replay_s = static_cast<double>(wall.now_ns() - t0) * 1e-9;
  EXPECT_TRUE(cursor.done());
  EXPECT_EQ(replayed.hash(), live.hash()) << "replay diverged";
  const double speedup = (static_cast<double>(kSteps) * dt) / std::max(replay_s, 1e-9);
  std::printf("session: %llu steps, %llu inputs recorded, live hash %016llx, replay hash %016llx, replay %.0fx real time\n",
              static_cast<unsigned long long>(kSteps), static_cast<unsigned long long>(live.inputs),
              static_cast<unsigned long long>(live.hash()), static_cast<unsigned long long>(replayed.hash()), speedup);
  EXPECT_GE(speedup, 5.0);
  // Telemetry flowed and nothing the test pushed was lost.
  EXPECT_EQ(pub.published(), kSteps / 4);
  std::remove(path.c_str());
}
