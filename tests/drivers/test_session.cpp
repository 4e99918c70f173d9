// The transport-independent session: state machine transitions, timeouts, clock mapping. No I/O:
// messages are handed in directly with explicit times.
#include <gtest/gtest.h>

#include <random>
#include <variant>
#include <vector>

#include "drivers/session.hpp"
#include "firmware-protocol/vp.hpp"

namespace {

using namespace vitreo::drivers;
using vitreo::proto::make;

struct Harness {
  explicit Harness(SessionConfig c = {}) : s(c) {
    s.set_send([this](const vp_message& m) { sent.push_back(m); });
    s.set_on_state([this](LinkState, LinkState to, const char*) { states.push_back(to); });
    s.set_on_sample([this](const Sample&) { ++samples; });
  }
  void info(std::uint64_t now, std::uint8_t major = 1) {
    vp_message m = make(VP_MSG_DEVICE_INFO, seq++);
    m.u.device_info.device_type = VP_DEVICE_TRACKER;
    m.u.device_info.proto_major = major;
    s.on_frame(VP_OK, m, now);
  }
  void ack(std::uint64_t now) {
    vp_message m = make(VP_MSG_CONFIG, seq++);
    m.u.config = {VP_CFG_ACK, VP_CFG_KEY_STREAMING, 1};
    s.on_frame(VP_OK, m, now);
  }
  void pose(std::uint64_t now, std::uint64_t device_us) {
    vp_message m = make(VP_MSG_POSE_SAMPLE, seq++);
    m.u.pose.timestamp_us = device_us;
    m.u.pose.q_wxyz[0] = 1;
    m.u.pose.tip_mm[0] = static_cast<float>(device_us % 1000);  // changing values: not stuck
    s.on_frame(VP_OK, m, now);
  }
  DeviceSession s;
  std::vector<vp_message> sent;
  std::vector<LinkState> states;
  int samples = 0;
  std::uint8_t seq = 0;
};

TEST(Session, HandshakeStaleLostSequence) {
  Harness h;
  h.s.transport_up(1000);
  ASSERT_EQ(h.sent.size(), 1u);
  EXPECT_EQ(h.sent[0].type, VP_MSG_CONFIG);
  EXPECT_EQ(h.sent[0].u.config.op, VP_CFG_GET);
  h.s.tick(1000 + 50'000);  // no answer: identify is retransmitted
  EXPECT_EQ(h.sent.size(), 2u);
  h.info(60'000);
  EXPECT_EQ(h.s.state(), LinkState::configuring);
  h.pose(61'000, 5'000'000);  // before the ACK: belongs to an old session, not delivered
  EXPECT_EQ(h.samples, 0);
  h.ack(62'000);
  h.pose(63'000, 5'001'000);
  EXPECT_EQ(h.s.state(), LinkState::streaming);
  EXPECT_EQ(h.samples, 1);
  EXPECT_FALSE(h.s.tick(63'000 + 20'000));
  EXPECT_EQ(h.s.state(), LinkState::streaming) << "exactly the stale timeout is not stale yet";
  EXPECT_FALSE(h.s.tick(63'000 + 20'001));
  EXPECT_EQ(h.s.state(), LinkState::stale);
  h.pose(90'000, 5'028'000);
  EXPECT_EQ(h.s.state(), LinkState::streaming);
  EXPECT_FALSE(h.s.tick(90'000 + 250'000));
  EXPECT_TRUE(h.s.tick(90'000 + 250'001)) << "lost: the transport must be closed";
  EXPECT_EQ(h.s.state(), LinkState::lost);
  EXPECT_EQ(h.states, (std::vector<LinkState>{LinkState::connecting, LinkState::configuring, LinkState::streaming,
                                              LinkState::stale, LinkState::streaming, LinkState::stale, LinkState::lost}));
  h.s.reconnect_attempt(400'000);
  EXPECT_EQ(h.s.state(), LinkState::reconnecting);
  h.s.transport_up(400'100);
  EXPECT_EQ(h.s.state(), LinkState::connecting);
  EXPECT_EQ(h.s.stats().reconnects, 0u) << "re-opening the transport is not finding the device";
  h.info(400'200);
  EXPECT_EQ(h.s.state(), LinkState::configuring);
  EXPECT_EQ(h.s.stats().reconnects, 1u) << "the device identified itself again";
}

// Stuck = bit-identical poses for >= 50 ms of the device's own time (issue 20): not a number of
// samples (a 250 Hz and a 1 kHz tracker alike), not repeats whose timestamps do not advance.
TEST(Session, APoseIdenticalFor50MsOfDeviceTimeIsStuckAndMovingAgainEndsIt) {
  Harness h;
  std::vector<bool> flags;
  h.s.set_on_sample([&](const Sample& x) { flags.push_back(std::get<PoseSample>(x).stuck); });
  h.s.transport_up(1000);
  h.info(2000);
  h.ack(3000);
  auto pose = [&](std::uint64_t now, std::uint64_t device_us, float x) {
    vp_message m = make(VP_MSG_POSE_SAMPLE, h.seq++);
    m.u.pose.timestamp_us = device_us;
    m.u.pose.q_wxyz[0] = 1;
    m.u.pose.tip_mm[0] = x;
    h.s.on_frame(VP_OK, m, now);
  };
  // 4 ms apart (250 Hz): the same pose from device time 10 000 on.
  for (int i = 0; i <= 20; ++i) pose(10'000 + 4000 * i, 5'000'000 + 4000 * i, 1.5f);
  ASSERT_EQ(flags.size(), 21u);
  for (int i = 0; i < 13; ++i) EXPECT_FALSE(flags[static_cast<std::size_t>(i)]) << "sample " << i << ": under 50 ms";
  for (int i = 13; i <= 20; ++i) EXPECT_TRUE(flags[static_cast<std::size_t>(i)]) << "sample " << i << ": 52 ms or more";
  EXPECT_TRUE(h.s.stuck());
  EXPECT_EQ(h.s.stats().stuck_samples, 8u);
  EXPECT_EQ(h.s.stats().stuck_episodes, 1u);
  pose(100'000, 5'084'000, 1.50001f);  // it moved: no longer stuck
  EXPECT_FALSE(flags.back());
  EXPECT_FALSE(h.s.stuck());
  // The same bits with a timestamp that does not advance are repeats of one sample, not 50 ms.
  for (int i = 0; i < 100; ++i) pose(101'000 + 1000 * i, 5'090'000, 2.0f);
  EXPECT_FALSE(h.s.stuck());
  EXPECT_EQ(h.s.stats().stuck_episodes, 1u);
}

// A device configured below 1 kHz is stale after 20 of its periods, not 20 ms: an eyeball
// fixture at 250 Hz sends a sample every 4 ms, so 20 ms would be only five of them.
TEST(Session, StaleAfterTwentyPeriodsOfTheConfiguredRate) {
  Harness h;
  h.s.transport_up(0);
  vp_message m = make(VP_MSG_DEVICE_INFO, h.seq++);
  m.u.device_info.device_type = VP_DEVICE_EYEBALL;
  m.u.device_info.proto_major = VP_PROTO_MAJOR;
  h.s.on_frame(VP_OK, m, 10);
  EXPECT_EQ(h.s.configured_rate_hz(), 250);
  EXPECT_EQ(h.s.stale_after_us(), 80'000u);
  h.ack(20);
  vp_message e = make(VP_MSG_EYEBALL_STATE, h.seq++);
  e.u.eyeball.timestamp_us = 5'000'000;
  e.u.eyeball.q_wxyz[0] = 1;
  h.s.on_frame(VP_OK, e, 1000);
  ASSERT_EQ(h.s.state(), LinkState::streaming);
  h.s.tick(1000 + 79'000);
  EXPECT_EQ(h.s.state(), LinkState::streaming) << "79 ms: fewer than 20 periods";
  h.s.tick(1000 + 81'000);
  EXPECT_EQ(h.s.state(), LinkState::stale);
}

TEST(Session, RefusesDeviceWithOtherProtocolMajor) {
  Harness h;
  h.s.transport_up(0);
  h.info(1000, 2);
  EXPECT_EQ(h.s.state(), LinkState::connecting);
  // A valid frame refused for what it says, not a frame of another version: counted apart, and
  // the refusal names both versions (device_status_t shows it as ERROR with this detail).
  EXPECT_EQ(h.s.stats().protocol_rejected, 1u);
  EXPECT_EQ(h.s.stats().version_errors, 0u);
  EXPECT_NE(h.s.refusal().find("protocol 2."), std::string::npos) << h.s.refusal();
  EXPECT_NE(h.s.refusal().find("this host 1."), std::string::npos) << h.s.refusal();
  EXPECT_FALSE(h.s.has_device_info());
}

TEST(Session, SequenceGapsAreDropsAndErrorsAreCountedByKind) {
  Harness h;
  h.s.transport_up(0);
  h.info(1);
  h.ack(2);
  h.seq = 10;  // sequence numbers 2..9 never arrived
  h.pose(3, 100);
  EXPECT_EQ(h.s.stats().drops, 8u);
  vp_message none{};
  for (int st : {VP_ERR_CRC, VP_ERR_CRC, VP_ERR_FRAMING, VP_ERR_OVERFLOW, VP_ERR_RANGE, VP_ERR_VERSION, VP_ERR_UNKNOWN_TYPE,
                 VP_ERR_LENGTH})
    h.s.on_frame(st, none, 4);
  const auto& s = h.s.stats();
  EXPECT_EQ(s.crc_errors, 2u);
  EXPECT_EQ(s.framing_errors, 2u);
  EXPECT_EQ(s.range_rejected, 1u);
  EXPECT_EQ(s.version_errors, 1u);
  EXPECT_EQ(s.unknown_type, 1u);
  EXPECT_EQ(s.length_errors, 1u);
  EXPECT_EQ(s.rejected(), 8u);
  EXPECT_EQ(s.frames, s.valid + s.rejected());
}

TEST(ClockMapper, TimeSyncGivesTheNtpOffset) {
  ClockMapper c;
  // host 1000 → device receives at its 501000, replies 10 µs later, host receives at 1030
  c.on_sync(1000, 501'000, 501'010, 1030);
  EXPECT_EQ(c.offset_us(), -499'990);
  EXPECT_EQ(c.to_host_us(501'000), 1010u);
  // a later exchange with a long round trip (queued) does not replace a good estimate
  c.on_sync(2000, 502'000, 502'010, 9000);
  EXPECT_EQ(c.offset_us(), -499'990);
}

TEST(ClockMapper, MinimumFilterFindsTheLeastDelayedSampleAndFollowsDrift) {
  ClockMapper c;
  std::mt19937 rng(1);
  std::uniform_int_distribution<int> queue(0, 800);
  const std::int64_t true_offset = 123'456'789;  // host − device
  // device clock 100 ppm slow: device_us = host_us × (1 − 1e-4) − offset
  std::int64_t worst = 0;
  for (int i = 0; i < 20'000; ++i) {  // 20 s at 1 kHz
    const std::uint64_t sample_host = 10'000'000 + static_cast<std::uint64_t>(i) * 1000;
    const std::uint64_t device =
        static_cast<std::uint64_t>(static_cast<double>(sample_host) * (1 - 1e-4)) - static_cast<std::uint64_t>(true_offset - 200'000'000);
    const std::uint64_t rx = sample_host + 150 + static_cast<std::uint64_t>(queue(rng));
    c.on_sample(device, rx);
    if (i > 100) {
      const std::int64_t err = static_cast<std::int64_t>(c.to_host_us(device)) - static_cast<std::int64_t>(sample_host);
      worst = std::max<std::int64_t>(worst, std::llabs(static_cast<long long>(err - 150)));
    }
  }
  // the mapping tracks the sample instant to within the minimum latency plus one drift step
  EXPECT_LT(worst, 400) << "worst mapping error beyond the fixed 150 us latency";
}

}  // namespace
