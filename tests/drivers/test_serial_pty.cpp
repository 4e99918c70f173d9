// The serial driver against firmware emulators behind real pseudo-terminals: streaming, byte
// corruption at 1 % and 10 %, invalid values, wrong versions, stuck sensors, timestamp jumps,
// disconnect and reconnect. Time is a ManualClock advanced 1 ms per step; the pty itself is real.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>

#include "drivers/serial.hpp"
#include "drivers/sim/pty_sim.hpp"

namespace {

using namespace vitreo::drivers;

std::string temp_dir() {
  char tmpl[] = "/tmp/vitreo-pty-XXXXXX";
  const char* d = mkdtemp(tmpl);
  return d ? d : "/tmp";
}

sim::Script script(const std::string& extra, sim::DeviceKind k = sim::DeviceKind::tracker) {
  sim::Script s = sim::default_script(k);
  std::string text = std::string("device ") + sim::to_string(k) + "\n" + extra;
  // keep the default keys, add the extra directives
  sim::Script parsed;
  std::string err;
  std::string keys;
  for (auto& [t, v] : s.keys) {
    keys += "key " + std::to_string(t / 1000);
    for (double x : v) keys += " " + std::to_string(x);
    keys += "\n";
  }
  EXPECT_TRUE(sim::parse_script(text + keys, parsed, &err)) << err;
  return parsed;
}

// One simulated device, one driver, one manual clock, and a ledger of what was sent.
struct Bench {
  explicit Bench(sim::Script s, SessionConfig cfg = {})
      : dir(temp_dir()), device(std::move(s), dir + "/ttyVITREO0"), driver(dir + "/ttyVITREO0", clock, cfg) {
    device.emulator().set_on_sample_sent([this](const vp_message& m) { sent[timestamp(m)] = m; });
    driver.session().set_on_sample([this](const Sample& x) { got.push_back(x); });
  }
  ~Bench() {
    ::unlink((dir + "/ttyVITREO0").c_str());
    ::rmdir(dir.c_str());
  }
  static std::uint64_t timestamp(const vp_message& m) {
    return m.type == VP_MSG_POSE_SAMPLE ? m.u.pose.timestamp_us
           : m.type == VP_MSG_PEDAL_STATE ? m.u.pedal.timestamp_us
                                          : m.u.eyeball.timestamp_us;
  }
  // Lock-step: after each simulated millisecond, wait (in poll, which returns as soon as bytes
  // arrive) until the driver has read what the device wrote in it. Without this a loaded machine
  // could hold bytes in the pty for a real millisecond while the manual clock runs ahead by 50.
  void run_ms(int ms) {
    for (int i = 0; i < ms; ++i) {
      clock.advance_us(1000);
      const std::uint64_t w0 = device.bytes_written(), r0 = driver.session().stats().bytes;
      device.step(clock.now_us());
      const std::uint64_t target = r0 + (device.bytes_written() - w0);
      driver.poll(0);
      for (int k = 0; k < 50 && device.plugged() && driver.session().stats().bytes < target && port_open(); ++k)
        driver.poll(1);
    }
  }
  bool port_open() const {
    const auto s = driver.session().state();
    return s != LinkState::lost && s != LinkState::reconnecting;
  }
  // Lets the pty deliver what is in flight (the only real-time wait: microseconds in practice).
  void drain() {
    for (int i = 0; i < 5; ++i) driver.poll(5);
  }
  // Delivered samples that are not bit-identical to a valid sample the device sent.
  int invalid_delivered() {
    int bad = 0;
    for (auto& s : got) {
      auto* p = std::get_if<PoseSample>(&s);
      if (!p) continue;
      auto it = sent.find(p->t.device_us);
      if (it == sent.end() || std::memcmp(it->second.u.pose.tip_mm, p->tip_mm.data(), 12) != 0 ||
          std::memcmp(it->second.u.pose.q_wxyz, p->q_wxyz.data(), 16) != 0 ||
          it->second.u.pose.actuation != static_cast<std::uint16_t>(std::lround(p->actuation * 65535.0f)))
        ++bad;
    }
    return bad;
  }
  std::string dir;
  ManualClock clock;
  sim::PtySimDevice device;
  SerialDevice driver;
  std::map<std::uint64_t, vp_message> sent;
  std::vector<Sample> got;
};

TEST(SerialPty, OpenErrorsAreClear) {
  SerialPort p;
  std::string err;
  EXPECT_FALSE(p.open("/nonexistent/ttyUSB9", 115200, &err));
  EXPECT_NE(err.find("No such file"), std::string::npos) << err;
  EXPECT_FALSE(p.open("/dev/null", 115200, &err));
  EXPECT_NE(err.find("not a serial port"), std::string::npos) << err;
  EXPECT_FALSE(p.open("/dev/null", 12345, &err));
  EXPECT_NE(err.find("baud"), std::string::npos) << err;
}

TEST(SerialPty, TrackerHandshakeThenStreams) {
  Bench b(sim::default_script(sim::DeviceKind::tracker));
  std::vector<std::string> states;
  b.driver.session().set_on_state([&](LinkState, LinkState to, const char*) { states.push_back(to_string(to)); });
  b.run_ms(1000);
  b.drain();
  EXPECT_EQ(states, (std::vector<std::string>{"connecting", "configuring", "streaming"}));
  const auto& st = b.driver.session().stats();
  ASSERT_TRUE(b.driver.session().has_device_info());
  EXPECT_EQ(b.driver.session().device_info().serial, 1001u);
  EXPECT_EQ(b.driver.session().device_info().device_type, VP_DEVICE_TRACKER);
  EXPECT_GT(b.got.size(), 900u);
  EXPECT_EQ(st.rejected(), 0u);
  EXPECT_EQ(st.drops, 0u);
  EXPECT_EQ(b.invalid_delivered(), 0);
  EXPECT_EQ(st.samples_delivered, b.got.size());
  // clock mapping: the emulator's device clock = host time since start + 5 s; the mapped time must
  // land within 2 ms of when the sample was really taken
  auto& first = std::get<PoseSample>(b.got.front());
  auto& last = std::get<PoseSample>(b.got.back());
  const std::int64_t start = static_cast<std::int64_t>(first.t.received_us) - static_cast<std::int64_t>(first.t.device_us - 5'000'000);
  for (auto* s : {&first, &last}) {
    const std::int64_t truth = static_cast<std::int64_t>(s->t.device_us) - 5'000'000 + start;
    EXPECT_LE(std::llabs(static_cast<long long>(s->t.host_us) - truth), 2000);
  }
  EXPECT_LE(st.latency_max_us, 3000u);
  std::uint64_t prev = 0;
  for (auto& s : b.got) {
    auto& p = std::get<PoseSample>(s);
    EXPECT_GE(p.t.host_us, prev);
    EXPECT_EQ(p.t.device_serial, 1001u);
    prev = p.t.host_us;
  }
  std::printf("tracker over pty: %s\n", to_string(st).c_str());
}

TEST(SerialPty, PedalsAndEyeballStream) {
  for (auto k : {sim::DeviceKind::pedals, sim::DeviceKind::eyeball}) {
    Bench b(sim::default_script(k));
    b.run_ms(2000);
    b.drain();
    EXPECT_EQ(b.driver.session().state(), LinkState::streaming);
    EXPECT_GT(b.got.size(), k == sim::DeviceKind::pedals ? 900u : 450u);
    EXPECT_EQ(b.driver.session().stats().rejected(), 0u);
    bool saw_press = false, saw_insert = false;
    for (auto& s : b.got) {
      if (auto* p = std::get_if<PedalSample>(&s)) saw_press |= p->axes[0] > 0.9f && (p->switches & 1);
      if (auto* e = std::get_if<EyeballSample>(&s)) saw_insert |= e->inserted[0] && e->depth_mm[0] > 11.0f;
    }
    EXPECT_TRUE(k == sim::DeviceKind::pedals ? saw_press : saw_insert) << sim::to_string(k);
  }
}

// The bar of issue 5: at 1 % and 10 % corrupted bytes the driver resynchronises, counts the errors,
// delivers only valid samples (invalid delivered = 0) and keeps streaming.
TEST(SerialPty, CorruptedBytesAtOneAndTenPercent) {
  for (double p : {0.01, 0.10}) {
    SessionConfig cfg;
    cfg.lost_after_us = 5'000'000;  // measure corruption handling, not the loss timeout
    Bench b(script("autostream 1\nseed 7\ncorrupt " + std::to_string(p) + "\n"), cfg);
    b.run_ms(10000);
    b.drain();
    const auto& st = b.driver.session().stats();
    const auto& c = b.device.emulator().counters();
    const int invalid = b.invalid_delivered();
    std::printf(
        "link fault figures @ %4.1f %% corrupted bytes: frames sent %llu, corrupted %llu (bytes %llu), "
        "frames seen %llu, rejected %llu (crc %llu, framing %llu, other %llu), samples sent %llu, delivered %llu, "
        "invalid delivered %d\n",
        p * 100, (unsigned long long)c.frames_sent, (unsigned long long)c.frames_corrupted,
        (unsigned long long)c.bytes_corrupted, (unsigned long long)st.frames, (unsigned long long)st.rejected(),
        (unsigned long long)st.crc_errors, (unsigned long long)st.framing_errors,
        (unsigned long long)(st.rejected() - st.crc_errors - st.framing_errors), (unsigned long long)c.samples_sent,
        (unsigned long long)st.samples_delivered, invalid);
    EXPECT_EQ(invalid, 0);
    EXPECT_GT(c.frames_corrupted, 0u);
    EXPECT_GT(st.crc_errors + st.framing_errors, 0u);
    EXPECT_GT(st.samples_delivered, p < 0.05 ? 5000u : 20u) << "resynchronised after errors";
    // a corrupted frame can take at most one clean neighbour with it (a destroyed delimiter merges
    // the two); every other clean frame must arrive valid
    EXPECT_GE(st.valid + 2 * c.frames_corrupted, c.frames_sent);
    EXPECT_LE(st.samples_delivered, c.samples_sent);
  }
}

TEST(SerialPty, NanOutOfRangeVersionAndUnknownTypeAreRejectedAndCounted) {
  Bench b(script("autostream 1\nfault 200 50 nan\nfault 300 50 range\nfault 400 20 version\nfault 500 20 unknown\n"));
  b.run_ms(800);
  b.drain();
  const auto& st = b.driver.session().stats();
  EXPECT_EQ(st.range_rejected, 100u);  // 50 ms of NaN + 50 ms out of range at 1 kHz
  EXPECT_GE(st.version_errors, 20u);   // samples and heartbeats inside the window
  EXPECT_GE(st.unknown_type, 20u);
  EXPECT_EQ(st.version_errors + st.unknown_type + st.range_rejected, b.device.emulator().counters().invalid_injected);
  EXPECT_EQ(st.crc_errors, 0u);
  EXPECT_EQ(b.invalid_delivered(), 0);
  for (auto& s : b.got) {
    auto& p = std::get<PoseSample>(s);
    for (float x : p.tip_mm) ASSERT_TRUE(std::isfinite(x) && std::fabs(x) < 500.0f);
  }
  EXPECT_EQ(b.driver.session().state(), LinkState::streaming);
}

TEST(SerialPty, StuckSensorAndTimestampJumpAreFlagged) {
  Bench b(script("autostream 1\nfault 200 400 stuck\nfault 700 0 jump 5000\n"));
  b.run_ms(1000);
  b.drain();
  const auto& st = b.driver.session().stats();
  // 400 identical samples at 1 kHz, stuck once 50 ms of device time passed: the last 350.
  EXPECT_GE(st.stuck_samples, 340u);
  EXPECT_LE(st.stuck_samples, 351u);
  EXPECT_EQ(st.stuck_episodes, 1u);
  EXPECT_EQ(st.timestamp_jumps, 1u);
  int flagged = 0;
  for (auto& s : b.got) flagged += std::get<PoseSample>(s).stuck;
  EXPECT_EQ(static_cast<std::uint64_t>(flagged), st.stuck_samples);
  // after the jump the mapping re-converges: the last sample maps close to its reception time
  auto& last = std::get<PoseSample>(b.got.back());
  EXPECT_LE(last.t.received_us - last.t.host_us, 3000u);
}

// Cable pull: the pty closes, the driver sees the hang-up and is "lost" at once (documented
// bound: one poll); a silent device (frames stop, port stays) is lost after lost_after_us. Both
// come back to streaming once the device is back.
TEST(SerialPty, DisconnectIsLostWithinTimeoutAndReconnectStreams) {
  SessionConfig cfg;  // defaults: lost after 250 ms of silence, reconnect attempts every 100 ms
  Bench b(sim::default_script(sim::DeviceKind::tracker), cfg);
  std::vector<std::pair<std::string, std::uint64_t>> log;
  b.driver.session().set_on_state(
      [&](LinkState, LinkState to, const char*) { log.emplace_back(to_string(to), b.clock.now_us()); });
  b.run_ms(300);
  ASSERT_EQ(b.driver.session().state(), LinkState::streaming);

  // 1) cable pull
  const std::uint64_t pulled = b.clock.now_us();
  b.device.unplug();
  b.run_ms(1);
  b.drain();
  EXPECT_EQ(b.driver.session().state(), LinkState::lost);
  EXPECT_LE(log.back().second - pulled, 1000u);
  b.run_ms(500);
  EXPECT_EQ(b.driver.session().state(), LinkState::reconnecting);
  b.device.plug();
  b.run_ms(300);
  b.drain();
  EXPECT_EQ(b.driver.session().state(), LinkState::streaming);
  EXPECT_EQ(b.driver.session().stats().reconnects, 1u);

  // 2) device goes silent (frames stop, port stays open)
  const std::size_t before = b.got.size();
  std::uint64_t silent_from = 0;
  std::vector<std::string> states;
  b.driver.session().set_on_state([&](LinkState, LinkState to, const char*) {
    states.push_back(to_string(to));
    if (to == LinkState::lost) {
      EXPECT_LE(b.clock.now_us() - silent_from, cfg.lost_after_us + 2000);
    }
  });
  silent_from = b.clock.now_us();
  for (int i = 0; i < 400; ++i) {  // keep the port, send nothing
    b.clock.advance_us(1000);
    b.driver.poll(0);
  }
  ASSERT_GE(states.size(), 2u);
  EXPECT_EQ(states[0], "stale");
  EXPECT_EQ(states[1], "lost");
  b.run_ms(500);
  b.drain();
  EXPECT_EQ(b.driver.session().state(), LinkState::streaming);
  EXPECT_GT(b.got.size(), before + 200);
  EXPECT_EQ(b.invalid_delivered(), 0);
  std::printf("after pull + silence: %s\n", to_string(b.driver.session().stats()).c_str());
}

TEST(SerialPty, ScriptedDisconnectReconnects) {
  Bench b(script("fault 500 300 disconnect\n"));
  b.run_ms(2000);
  b.drain();
  const auto& st = b.driver.session().stats();
  EXPECT_EQ(st.disconnects, 1u);
  EXPECT_EQ(st.reconnects, 1u);
  EXPECT_EQ(b.driver.session().state(), LinkState::streaming);
}

TEST(SerialPty, CalibrationRequestGetsItsResult) {
  Bench b(sim::default_script(sim::DeviceKind::tracker));
  std::vector<vp_calib_result> results;
  b.driver.session().set_on_message([&](const vp_message& m) {
    if (m.type == VP_MSG_CALIB_RESULT) results.push_back(m.u.calib_result);
  });
  b.run_ms(100);
  ASSERT_TRUE(b.driver.session().request_calibration(0, 1, 0xBEEF));
  b.run_ms(10);
  b.drain();
  ASSERT_EQ(results.size(), 1u);
  EXPECT_EQ(results[0].token, 0xBEEF);
  EXPECT_EQ(results[0].instrument_id, 1);
  EXPECT_EQ(results[0].result, 0);
  b.device.unplug();
  b.run_ms(2);
  b.drain();
  EXPECT_FALSE(b.driver.session().request_calibration(0, 1, 1)) << "refused while the link is down";
}

// A tracker held still is not stuck: the emulator's default noise (a real tracker's jitter) keeps
// every pose distinct. Without it the same held pose is a stuck sensor after 50 ms — which is the
// detector's job, and why the noise is on by default.
TEST(SerialPty, AHeldPoseWithSensorNoiseIsNeverStuckWithoutItItIs) {
  const char* held = "device tracker\nrate_hz 1000\nautostream 1\nkey 0 1 2 12 0 0 0 0\nkey 5000 1 2 12 0 0 0 0\n";
  for (const char* noise : {"", "noise 0\n"}) {
    sim::Script s;
    std::string err;
    ASSERT_TRUE(sim::parse_script(std::string(held) + noise, s, &err)) << err;
    Bench b(s);
    b.run_ms(500);
    b.drain();
    const auto& st = b.driver.session().stats();
    ASSERT_GT(st.samples_delivered, 400u);
    if (*noise == '\0') {
      EXPECT_EQ(st.stuck_samples, 0u) << "a held, noisy pose was called stuck";
    } else {
      EXPECT_GE(st.stuck_episodes, 1u) << "a noise-free held pose is exactly what a stuck sensor sends";
    }
  }
}

TEST(SimScript, ParseErrorsNameTheLine) {
  sim::Script s;
  std::string err;
  EXPECT_FALSE(sim::parse_script("device tracker\nkey 0 1 2\n", s, &err));
  EXPECT_NE(err.find("line 2"), std::string::npos) << err;
  EXPECT_FALSE(sim::parse_script("device toaster\n", s, &err));
  EXPECT_NE(err.find("toaster"), std::string::npos);
  EXPECT_FALSE(sim::parse_script("device pedals\nkey 0 0 0 0\nfault 1 1 explode\n", s, &err));
  EXPECT_FALSE(sim::parse_script("device pedals\ncorrupt 2\nkey 0 0 0 0\n", s, &err));
  EXPECT_TRUE(sim::parse_script("device pedals # comment\nkey 0 0 0 0\nkey 10 1 0 1\n", s, &err)) << err;
}

// Issue 20: "fault ... jump nan" was taken as a jump of 0 ms. Every number is now a whole finite
// token in range, and nothing may trail a directive.
TEST(SimScript, NonsenseNumbersAndTrailingWordsAreRefused) {
  const std::string base = "device tracker\nkey 0 1 2 3 0 0 0 0\n";
  for (const char* bad : {"fault 100 10 jump nan", "fault 100 10 jump", "fault 100 10 jump inf", "fault nan 10 drop",
                          "fault 100 10 drop 5", "key 10 1 2 nan 0 0 0 0", "key 10 1 2 3 0 0 0 0 9", "key 10 1 2 3x 0 0 0 0",
                          "key 1e300 1 2 3 0 0 0 0", "rate_hz nan", "rate_hz 100 extra", "loop 2", "noise -1", "seed 1e300",
                          "serial 12abc", "corrupt inf"}) {
    sim::Script s;
    std::string err;
    EXPECT_FALSE(sim::parse_script(base + bad + "\n", s, &err)) << bad;
    EXPECT_NE(err.find("line 3"), std::string::npos) << bad << ": " << err;
  }
  sim::Script s;
  std::string err;
  ASSERT_TRUE(sim::parse_script(base + "fault 100 10 jump -250.5\n", s, &err)) << err;
  ASSERT_EQ(s.faults.size(), 1u);
  EXPECT_DOUBLE_EQ(s.faults[0].value, -250.5);
}

}  // namespace
