// Decoding LCM bytes from outside: the packets that crashed the rig (issue 20) and their relatives,
// built by hand (lcm_bytes.hpp), through the checked layer (lcm_decode.hpp), a checked subscription
// and a live CommandServer over memq.
#include <gtest/gtest.h>

#include <lcm/lcm.h>

#include <climits>
#include <stdexcept>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>

#include "rig/telemetry/channels.hpp"
#include "rig/telemetry/commands.hpp"
#include "rig/telemetry/lcm_decode.hpp"
#include "rig/telemetry/lcm_subscribe.hpp"
#include "tests/rig/telemetry/lcm_bytes.hpp"
#include "tests/rig/telemetry/physics_stand_in.hpp"
#include "vitreo_lcm/command_ack_t.hpp"
#include "vitreo_lcm/device_input_t.hpp"
#include "vitreo_lcm/operator_command_t.hpp"
#include "vitreo_lcm/recording_header_t.hpp"
#include "vitreo_lcm/score_t.hpp"

using namespace vitreo::telemetry;
using vitreo::test::LcmBytes;
using Cmd = vitreo_lcm::operator_command_t;

namespace {

// An operator_command_t as bytes; source_len overrides the source's length field when set.
LcmBytes command_bytes(const std::string& source, std::int64_t seq, std::int8_t code, const std::string& arg = "",
                       bool lie = false, std::int32_t source_len = 0) {
  LcmBytes b;
  b.i64(Cmd::getHash()).i64(1234);
  if (lie) {
    b.str_len(source_len).raw(source);
  } else {
    b.str(source);
  }
  b.i64(seq).i8(code).f64(0.0).str(arg);
  return b;
}

template <class Msg>
DecodeError decode(const LcmBytes& b) {
  Msg m;
  return decode_message(b.data().data(), b.size(), m);
}

void publish_raw(lcm::LCM& lc, const char* channel, const LcmBytes& b) {
  ASSERT_EQ(lcm_publish(lc.getUnderlyingLCM(), channel, b.data().data(), static_cast<unsigned>(b.size())), 0);
}

void drain(lcm::LCM& lc) {
  while (lc.handleTimeout(0) > 0) {
  }
}

}  // namespace

TEST(LcmDecode, AWellFormedHandBuiltCommandDecodesToItsFields) {
  const LcmBytes b = command_bytes("instructor-ui", 7, Cmd::ZOOM, "");
  Cmd m;
  ASSERT_EQ(decode_message(b.data().data(), b.size(), m), DecodeError::None);
  EXPECT_EQ(m.utime_us, 1234);
  EXPECT_EQ(m.source, "instructor-ui");
  EXPECT_EQ(m.seq, 7);
  EXPECT_EQ(m.command, std::int8_t{Cmd::ZOOM});
  EXPECT_EQ(m.arg, "");
}

// The packet that made vitreo segfault 47 ms later (an over-read that moved the cursor backwards).
TEST(LcmDecode, CommandWithSourceLengthIntMinIsRefused) {
  EXPECT_EQ(decode<Cmd>(command_bytes("x", 1, Cmd::PAUSE, "", true, INT_MIN)), DecodeError::Malformed);
}

// The packet that threw std::length_error through liblcm's dispatch.
TEST(LcmDecode, CommandWithSourceLengthZeroIsRefused) {
  EXPECT_EQ(decode<Cmd>(command_bytes("", 1, Cmd::PAUSE, "", true, 0)), DecodeError::Malformed);
}

TEST(LcmDecode, EveryOtherLieAboutAStringLengthIsRefused) {
  for (std::int32_t len : {-1, -2, INT_MIN + 1, 1 << 30, INT_MAX, 200}) {
    EXPECT_EQ(decode<Cmd>(command_bytes("abc", 1, Cmd::PAUSE, "", true, len)), DecodeError::Malformed) << len;
  }
}

TEST(LcmDecode, AStringWithoutItsTerminatingNulIsRefused) {
  // Length 4 counts "abc" and its NUL; here the fourth byte is 'd'.
  LcmBytes b;
  b.i64(Cmd::getHash()).i64(1).str_len(4).raw("abcd").i64(1).i8(Cmd::PAUSE).f64(0).str("");
  EXPECT_EQ(decode<Cmd>(b), DecodeError::Malformed);
}

// Found by the fuzzer: a NUL inside a string decoded, then re-encoded shorter (the encoder stops
// at the first NUL) — bytes that did not say what the message said.
TEST(LcmDecode, AStringWithANulInsideIsRefused) {
  LcmBytes b;
  b.i64(Cmd::getHash()).i64(1).str_len(4).raw(std::string("a\0b", 3)).i8(0).i64(1).i8(Cmd::PAUSE).f64(0).str("");
  EXPECT_EQ(decode<Cmd>(b), DecodeError::Malformed);
}

TEST(LcmDecode, NegativeOrImpossibleArrayCountsAreRefused) {
  for (std::int16_t n : {std::int16_t{-1}, std::int16_t{-32768}, std::int16_t{32767}, std::int16_t{3}}) {
    LcmBytes b;
    b.i64(vitreo_lcm::device_input_t::getHash()).i64(1).i64(2).i64(3).i32(4).i8(1).i32(0).i64(5);
    b.i16(n).f64(1.0);  // at most one value follows, whatever the count says
    b.i16(0);
    EXPECT_EQ(decode<vitreo_lcm::device_input_t>(b), DecodeError::Malformed) << n;
  }
  LcmBytes score;
  score.i64(vitreo_lcm::score_t::getHash()).i64(1).i64(2).str("case").boolean(true).f64(50.0).i16(-5);
  EXPECT_EQ(decode<vitreo_lcm::score_t>(score), DecodeError::Malformed);
}

TEST(LcmDecode, RecordingHeaderWithLengthIntMinIsRefused) {
  LcmBytes b;
  b.i64(vitreo_lcm::recording_header_t::getHash()).i64(1).i32(1).str_len(INT_MIN).bytes(64, 'x');
  EXPECT_EQ(decode<vitreo_lcm::recording_header_t>(b), DecodeError::Malformed);
}

TEST(LcmDecode, WrongFingerprintTruncationTrailingBytesAndSizeAreRefused) {
  LcmBytes good = command_bytes("a", 1, Cmd::PAUSE);
  LcmBytes wrong;
  wrong.i64(Cmd::getHash() ^ 1).raw(std::string(good.data().begin() + 8, good.data().end()));
  EXPECT_EQ(decode<Cmd>(wrong), DecodeError::Malformed);
  Cmd m;
  for (std::size_t cut = 0; cut < good.size(); ++cut) {
    EXPECT_EQ(decode_message(good.data().data(), cut, m), DecodeError::Malformed) << cut;
  }
  LcmBytes trailing = good;
  trailing.i8(0);
  EXPECT_EQ(decode<Cmd>(trailing), DecodeError::TrailingBytes);
  EXPECT_EQ(decode_message(good.data().data(), good.size(), m, good.size() - 1), DecodeError::Oversized);
  EXPECT_EQ(decode_message(nullptr, 0, m), DecodeError::Malformed);
}

// The original failure: an exception crossing liblcm's C dispatch left the LCM object inside
// lcm_handle, so the *next* message aborted the process. A checked subscription keeps both a
// throwing handler and an undecodable packet on its side.
TEST(CheckedSubscription, MalformedPacketsAndThrowingHandlersNeverStopTheNextMessage) {
  lcm::LCM lc("memq://");
  ASSERT_TRUE(lc.good());
  struct Handler {
    int calls = 0;
    std::vector<std::string> sources;
    void operator()(const Cmd& c) {
      ++calls;
      if (c.source == "throw") throw std::runtime_error("handler failed on purpose");
      sources.push_back(c.source);
    }
  } h;
  ReceiveStats stats;
  CheckedSubscription sub = subscribe_to<Cmd>(lc, kChanCommand, &h, &stats.channel(kChanCommand));
  publish_raw(lc, kChanCommand, command_bytes("x", 1, Cmd::PAUSE, "", true, INT_MIN));
  publish_raw(lc, kChanCommand, command_bytes("", 1, Cmd::PAUSE, "", true, 0));
  publish_raw(lc, kChanCommand, LcmBytes().bytes(kDefaultMaxMessageBytes + 1, 0));
  publish_raw(lc, kChanCommand, command_bytes("throw", 2, Cmd::PAUSE));
  publish_raw(lc, kChanCommand, command_bytes("after", 3, Cmd::RESUME));
  drain(lc);
  EXPECT_EQ(h.calls, 2);
  ASSERT_EQ(h.sources, std::vector<std::string>{"after"});
  const auto rows = stats.snapshot();
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].channel, kChanCommand);
  EXPECT_EQ(rows[0].received, 5u);
  EXPECT_EQ(rows[0].rejected, 3u);
  EXPECT_EQ(rows[0].handler_errors, 1u);
  EXPECT_NE(rows[0].last_error.find("handler failed on purpose"), std::string::npos) << rows[0].last_error;
}

TEST(CommandServer, MalformedCommandsAreCountedNeverAnsweredAndValidOnesStillAcknowledged) {
  lcm::LCM lc("memq://");
  ASSERT_TRUE(lc.good());
  CommandServer server(lc);
  struct Acks {
    std::vector<vitreo_lcm::command_ack_t> got;
    void operator()(const vitreo_lcm::command_ack_t& a) { got.push_back(a); }
  } acks;
  CheckedSubscription ack_sub = subscribe_to<vitreo_lcm::command_ack_t>(lc, kChanCommandAck, &acks);
  vitreo::test::PhysicsStandIn physics;
  physics.ctx.case_count = 2;

  publish_raw(lc, kChanCommand, command_bytes("x", 1, Cmd::PAUSE, "", true, INT_MIN));
  publish_raw(lc, kChanCommand, command_bytes("", 1, Cmd::PAUSE, "", true, 0));
  publish_raw(lc, kChanCommand, command_bytes("ok", 1, Cmd::PAUSE));
  drain(lc);
  physics.step(server);
  publish_raw(lc, kChanCommand, command_bytes("ok", 2, Cmd::NEXT_CASE, "", true, -7));
  publish_raw(lc, kChanCommand, command_bytes("ok", 3, Cmd::NEXT_CASE));
  drain(lc);
  physics.step(server);
  drain(lc);
  ASSERT_EQ(acks.got.size(), 2u);
  EXPECT_TRUE(acks.got[0].accepted) << acks.got[0].reason;
  EXPECT_EQ(acks.got[0].seq, 1);
  EXPECT_TRUE(acks.got[1].accepted) << acks.got[1].reason;
  EXPECT_EQ(acks.got[1].seq, 3);
  EXPECT_EQ(server.receive_counters().received(), 5u);
  EXPECT_EQ(server.receive_counters().rejected(), 3u);
  EXPECT_EQ(ack_sub.counters().rejected(), 0u);
}

TEST(CommandServer, RefusesSourcesAndArgumentsBeyondItsLimitsAndStaysBounded) {
  lcm::LCM lc("memq://");
  CommandServer server(lc);
  struct Acks {
    std::vector<vitreo_lcm::command_ack_t> got;
    void operator()(const vitreo_lcm::command_ack_t& a) { got.push_back(a); }
  } acks;
  CheckedSubscription ack_sub = subscribe_to<vitreo_lcm::command_ack_t>(lc, kChanCommandAck, &acks);
  vitreo::test::PhysicsStandIn physics;
  publish_raw(lc, kChanCommand, command_bytes(std::string(40, 'a'), 1, Cmd::TOGGLE_LABELS));
  publish_raw(lc, kChanCommand, command_bytes("with space", 1, Cmd::TOGGLE_LABELS));
  publish_raw(lc, kChanCommand, command_bytes("bell\a", 1, Cmd::TOGGLE_LABELS));
  publish_raw(lc, kChanCommand, command_bytes("ok", 1, Cmd::TOGGLE_LABELS, std::string(65, 'a')));
  drain(lc);
  ASSERT_EQ(acks.got.size(), 4u);
  for (const auto& a : acks.got) EXPECT_FALSE(a.accepted);
  EXPECT_NE(acks.got[0].reason.find("printable"), std::string::npos) << acks.got[0].reason;
  EXPECT_NE(acks.got[3].reason.find("argument longer"), std::string::npos) << acks.got[3].reason;
  const auto level = spdlog::get_level();
  spdlog::set_level(spdlog::level::err);  // 300 refusals are expected below
  // Many invented sources: each is answered, and the sequence memory stays bounded (the oldest is
  // forgotten, so a real sender heard from recently keeps its protection against replays).
  publish_raw(lc, kChanCommand, command_bytes("real", 10, Cmd::TOGGLE_LABELS));
  drain(lc);
  for (int i = 0; i < 300; ++i) {
    publish_raw(lc, kChanCommand, command_bytes("s" + std::to_string(i), 1, Cmd::TOGGLE_LABELS));
    if (i % 50 == 0) publish_raw(lc, kChanCommand, command_bytes("real", 11 + i, Cmd::TOGGLE_LABELS));
    drain(lc);
    physics.step(server);
  }
  publish_raw(lc, kChanCommand, command_bytes("real", 5, Cmd::TOGGLE_LABELS));  // a replay
  drain(lc);
  physics.step(server);
  drain(lc);
  spdlog::set_level(level);
  EXPECT_FALSE(acks.got.back().accepted);
  EXPECT_NE(acks.got.back().reason.find("duplicate or reordered"), std::string::npos) << acks.got.back().reason;
}
