// Round trips of every message over every framing, and the edge cases of each decoder.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "firmware-protocol/vp.hpp"

namespace {

using namespace vitreo::proto;

const vp_msg_type kAll[] = {VP_MSG_HEARTBEAT,     VP_MSG_DEVICE_INFO,  VP_MSG_TIME_SYNC,  VP_MSG_STATUS,
                            VP_MSG_CONFIG,        VP_MSG_CALIB_REQUEST, VP_MSG_CALIB_RESULT, VP_MSG_POSE_SAMPLE,
                            VP_MSG_PEDAL_STATE,   VP_MSG_EYEBALL_STATE};

// A valid message of each type with every field non-zero where the ranges allow, so a field that an
// encoder forgets or a decoder misplaces changes the text form.
vp_message sample(vp_msg_type t, std::uint8_t seq) {
  const char* text = nullptr;
  switch (t) {
    case VP_MSG_HEARTBEAT: text = "heartbeat uptime_us=18446744073709551615 device_state=2 error_count=65535"; break;
    case VP_MSG_DEVICE_INFO:
      text = "device_info device_type=3 hw_revision=7 serial=4294967295 fw_major=9 fw_minor=8 fw_patch=7 "
             "proto_major=1 proto_minor=0 sample_rate_hz=65535";
      break;
    case VP_MSG_TIME_SYNC:
      text = "time_sync phase=1 exchange=255 host_tx_us=1 device_rx_us=72057594037927936 device_tx_us=3";
      break;
    case VP_MSG_STATUS: text = "status severity=3 code=513 detail=16909060 timestamp_us=99"; break;
    case VP_MSG_CONFIG: text = "config op=3 key=2 value=4294967295"; break;
    case VP_MSG_CALIB_REQUEST: text = "calib_request procedure=2 instrument_id=255 token=65535"; break;
    case VP_MSG_CALIB_RESULT:
      text = "calib_result procedure=1 instrument_id=3 token=7 result=2 residual_mm=0.0625 offset_mm=-500,0.1,500";
      break;
    case VP_MSG_POSE_SAMPLE:
      text = "pose_sample timestamp_us=4294967296 instrument_id=2 tool_type=8 tip_mm=-499.5,0.001,250 "
             "q_wxyz=0.5,-0.5,0.5,-0.5 actuation=65535 quality_pct=100";
      break;
    case VP_MSG_PEDAL_STATE:
      text = "pedal_state timestamp_us=77 pedal_id=1 axis_count=4 axes=1,2,65535,4 switches=65535";
      break;
    case VP_MSG_EYEBALL_STATE:
      text = "eyeball_state timestamp_us=5 q_wxyz=0,0,0,1 port_count=4 port0_flags=1 port0_depth_mm=40 "
             "port1_flags=1 port1_depth_mm=0.5 port2_flags=0 port2_depth_mm=0 port3_flags=1 port3_depth_mm=3";
      break;
  }
  std::string err;
  auto m = parse(text, &err);
  EXPECT_TRUE(m) << err;
  m->seq = seq;
  return *m;
}

TEST(ProtocolCodec, Crc16CheckValue) {
  const char* s = "123456789";
  EXPECT_EQ(vp_crc16(reinterpret_cast<const std::uint8_t*>(s), 9), 0x29B1);
  EXPECT_EQ(vp_crc32c(reinterpret_cast<const std::uint8_t*>(s), 9), 0xE3069283u);
}

TEST(ProtocolCodec, CobsKnownEncodings) {
  // examples from the COBS paper / Wikipedia table
  struct C {
    Bytes in, out;
  } cases[] = {{{0x00}, {0x01, 0x01}},
               {{0x00, 0x00}, {0x01, 0x01, 0x01}},
               {{0x11, 0x22, 0x00, 0x33}, {0x03, 0x11, 0x22, 0x02, 0x33}},
               {{0x11, 0x00, 0x00, 0x00}, {0x02, 0x11, 0x01, 0x01, 0x01}}};
  for (auto& c : cases) {
    std::uint8_t out[16];
    std::size_t n = vp_cobs_encode(c.in.data(), c.in.size(), out, sizeof out);
    EXPECT_EQ(Bytes(out, out + n), c.out);
    std::uint8_t back[16];
    int m = vp_cobs_decode(out, n, back, sizeof back);
    ASSERT_GE(m, 0);
    EXPECT_EQ(Bytes(back, back + m), c.in);
  }
  // 254 non-zero bytes: one full block, code 0xFF
  Bytes big(254);
  for (std::size_t i = 0; i < big.size(); ++i) big[i] = std::uint8_t(i + 1);
  std::vector<std::uint8_t> out(300);
  std::size_t n = vp_cobs_encode(big.data(), big.size(), out.data(), out.size());
  EXPECT_EQ(n, 256u);
  EXPECT_EQ(out[0], 0xFF);
  std::vector<std::uint8_t> back(300);
  EXPECT_EQ(vp_cobs_decode(out.data(), n, back.data(), back.size()), 254);
  EXPECT_EQ(vp_cobs_encode(big.data(), big.size(), out.data(), 100), 0u) << "too small a buffer is refused";
}

TEST(ProtocolCodec, EveryMessageRoundTripsEveryFraming) {
  int seq = 0;
  for (auto t : kAll) {
    vp_message m = sample(t, std::uint8_t(seq++ * 37));
    SCOPED_TRACE(describe(m));
    ASSERT_EQ(vp_validate(&m), VP_OK);
    vp_message out{};
    // packet
    Bytes p = encode_packet(m);
    ASSERT_EQ(p.size(), VP_HEADER_SIZE + vp_payload_size(m.type));
    ASSERT_EQ(vp_decode_packet(p.data(), p.size(), &out), VP_OK);
    EXPECT_EQ(describe(out), describe(m));
    // serial
    Bytes s = encode_serial(m);
    ASSERT_LE(s.size(), VP_SERIAL_MAX_FRAME);
    EXPECT_EQ(s.back(), 0);
    EXPECT_EQ(std::count(s.begin(), s.end(), 0), 1) << "only the delimiter is zero";
    ASSERT_EQ(vp_serial_decode_frame(s.data(), s.size() - 1, &out), VP_OK);
    EXPECT_EQ(describe(out), describe(m));
    // usb
    Bytes u = encode_usb(m);
    ASSERT_LE(u.size(), 64u);
    ASSERT_EQ(vp_usb_decode(u.data(), u.size(), &out), VP_OK);
    EXPECT_EQ(describe(out), describe(m));
    // CAN FD
    auto fd = encode_canfd(m, 42);
    ASSERT_TRUE(fd);
    std::uint8_t node = 0;
    ASSERT_EQ(vp_canfd_decode(fd->id, fd->data.data(), fd->data.size(), &node, &out), VP_OK);
    EXPECT_EQ(node, 42);
    EXPECT_EQ(describe(out), describe(m));
    // classic CAN
    auto frames = encode_can_classic(m, 5, std::uint8_t(seq));
    vp_can_rx rx;
    vp_can_rx_init(&rx);
    int st = VP_NEED_MORE;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      ASSERT_LE(frames[i].data.size(), 8u);
      st = vp_can_rx_push(&rx, frames[i].id, frames[i].data.data(), frames[i].data.size(), &node, &out);
      if (i + 1 < frames.size()) {
        ASSERT_EQ(st, VP_NEED_MORE);
      }
    }
    ASSERT_EQ(st, VP_OK) << vp_status_name(st);
    EXPECT_EQ(node, 5);
    EXPECT_EQ(describe(out), describe(m));
  }
}

TEST(ProtocolCodec, TextFormRejectsGarbage) {
  std::string err;
  EXPECT_FALSE(parse("nonsense a=1", &err));
  EXPECT_NE(err.find("unknown message type"), std::string::npos);
  EXPECT_FALSE(parse("pose_sample tip_mm=1,2", &err));
  EXPECT_FALSE(parse("pose_sample bogus=1", &err));
  EXPECT_NE(err.find("bogus"), std::string::npos);
  EXPECT_FALSE(parse("pedal_state pedal_id=300", &err));
}

TEST(ProtocolCodec, RangeValidation) {
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  auto pose_with = [&](auto f) {
    vp_message m = sample(VP_MSG_POSE_SAMPLE, 1);
    f(m.u.pose);
    Bytes b = encode_usb(m);  // encoders never validate: simulators send bad values on purpose
    vp_message out{};
    return vp_usb_decode(b.data(), b.size(), &out);
  };
  EXPECT_EQ(pose_with([](auto&) {}), VP_OK);
  EXPECT_EQ(pose_with([&](auto& p) { p.tip_mm[1] = nan; }), VP_ERR_RANGE);
  EXPECT_EQ(pose_with([&](auto& p) { p.tip_mm[2] = -inf; }), VP_ERR_RANGE);
  EXPECT_EQ(pose_with([&](auto& p) { p.tip_mm[0] = 500.5f; }), VP_ERR_RANGE);
  EXPECT_EQ(pose_with([&](auto& p) { p.tip_mm[0] = 500.0f; }), VP_OK);
  EXPECT_EQ(pose_with([&](auto& p) { p.q_wxyz[0] = nan; }), VP_ERR_RANGE);
  EXPECT_EQ(pose_with([&](auto& p) { p.q_wxyz[0] = 0.9f; }), VP_ERR_RANGE) << "not a unit quaternion";
  EXPECT_EQ(pose_with([&](auto& p) { p.quality_pct = 101; }), VP_ERR_RANGE);
  EXPECT_EQ(pose_with([&](auto& p) { p.tool_type = VP_TOOL_COUNT; }), VP_ERR_RANGE);
  // PROTOCOL.md §3 and §4 (1.1): 9 blade and 10 sideways blade are tools, 11 is past the last one.
  EXPECT_EQ(pose_with([&](auto& p) { p.tool_type = 9; }), VP_OK);
  EXPECT_EQ(pose_with([&](auto& p) { p.tool_type = 10; }), VP_OK);
  EXPECT_EQ(pose_with([&](auto& p) { p.tool_type = 11; }), VP_ERR_RANGE);
  EXPECT_EQ(pose_with([&](auto& p) { p.tool_type = 255; }), VP_ERR_RANGE);

  vp_message e = sample(VP_MSG_EYEBALL_STATE, 1);
  e.u.eyeball.port_count = 2;  // port 3 in use beyond the count
  EXPECT_EQ(vp_validate(&e), VP_ERR_RANGE);
  e = sample(VP_MSG_EYEBALL_STATE, 1);
  e.u.eyeball.ports[2].depth_mm = 1.0f;  // withdrawn but with depth
  EXPECT_EQ(vp_validate(&e), VP_ERR_RANGE);
  e = sample(VP_MSG_EYEBALL_STATE, 1);
  e.u.eyeball.ports[0].depth_mm = 40.5f;
  EXPECT_EQ(vp_validate(&e), VP_ERR_RANGE);

  vp_message p = sample(VP_MSG_PEDAL_STATE, 1);
  p.u.pedal.axis_count = 2;  // axes[2], axes[3] non-zero
  EXPECT_EQ(vp_validate(&p), VP_ERR_RANGE);
}

TEST(ProtocolCodec, UnknownVersionsAndTypesAreReportedNotParsed) {
  vp_message m = sample(VP_MSG_POSE_SAMPLE, 3), out{};
  Bytes p = encode_packet(m);
  for (unsigned major : {0u, 2u, 15u}) {
    Bytes q = p;
    q[0] = std::uint8_t(major << 4);
    EXPECT_EQ(vp_decode_packet(q.data(), q.size(), &out), VP_ERR_VERSION) << major;
  }
  for (unsigned t = 0; t < 256; ++t) {
    Bytes q = p;
    q[1] = std::uint8_t(t);
    int st = vp_decode_packet(q.data(), q.size(), &out);
    if (vp_payload_size(std::uint8_t(t)) == 0) {
      EXPECT_EQ(st, VP_ERR_UNKNOWN_TYPE) << t;
    } else if (t != VP_MSG_POSE_SAMPLE) {
      EXPECT_EQ(st, VP_ERR_LENGTH) << t << ": a known type with another type's length";
    }
  }
  // a newer minor may append fields; an older/equal minor must match exactly
  Bytes longer = p;
  longer.push_back(0xAA);
  longer[3] = std::uint8_t(longer[3] + 1);
  EXPECT_EQ(vp_decode_packet(longer.data(), longer.size(), &out), VP_ERR_LENGTH);
  longer[0] = 0x10 | (VP_PROTO_MINOR + 1);
  EXPECT_EQ(vp_decode_packet(longer.data(), longer.size(), &out), VP_OK);
  EXPECT_EQ(out.version_minor, VP_PROTO_MINOR + 1);
  // an older minor (1.0, before the blades) is read when its length is exact
  Bytes older = p;
  older[0] = 0x10;
  EXPECT_EQ(vp_decode_packet(older.data(), older.size(), &out), VP_OK);
  EXPECT_EQ(out.version_minor, 0);
  EXPECT_EQ(vp_decode_packet(p.data(), 3, &out), VP_ERR_TRUNCATED);
  EXPECT_EQ(vp_decode_packet(p.data(), p.size() - 1, &out), VP_ERR_TRUNCATED);
}

TEST(ProtocolCodec, SerialStreamResynchronisesAfterGarbage) {
  vp_message a = sample(VP_MSG_POSE_SAMPLE, 1), b = sample(VP_MSG_PEDAL_STATE, 2);
  Bytes stream = {0x13, 0x37, 0x42};  // mid-frame start: tail of a frame we never saw
  stream.push_back(0);
  Bytes fa = encode_serial(a), fb = encode_serial(b);
  stream.insert(stream.end(), fa.begin(), fa.end());
  stream.insert(stream.end(), 200, 0x55);  // a frame that never ends (lost delimiter)
  stream.push_back(0);
  stream.insert(stream.end(), fb.begin(), fb.end());
  SerialDecoder dec;
  std::vector<int> statuses;
  std::vector<std::string> ok;
  dec.feed(stream, [&](int st, const vp_message& m) {
    statuses.push_back(st);
    if (st == VP_OK) ok.push_back(describe(m));
  });
  EXPECT_EQ(statuses, (std::vector<int>{VP_ERR_FRAMING, VP_OK, VP_ERR_OVERFLOW, VP_OK}));
  EXPECT_EQ(ok, (std::vector<std::string>{describe(a), describe(b)}));
}

TEST(ProtocolCodec, CanReassemblyErrors) {
  vp_message m = sample(VP_MSG_POSE_SAMPLE, 9), out{};
  auto frames = encode_can_classic(m, 3, 7);
  ASSERT_EQ(frames.size(), 7u);  // 45-byte packet + 2 CRC = 47 bytes in 7-byte chunks
  std::uint8_t node;
  auto push = [&](vp_can_rx& rx, const CanFrame& f) {
    return vp_can_rx_push(&rx, f.id, f.data.data(), f.data.size(), &node, &out);
  };
  vp_can_rx rx;
  // continuation without start
  vp_can_rx_init(&rx);
  EXPECT_EQ(push(rx, frames[1]), VP_ERR_SEQUENCE);
  // lost middle frame: toggle mismatch
  vp_can_rx_init(&rx);
  EXPECT_EQ(push(rx, frames[0]), VP_NEED_MORE);
  EXPECT_EQ(push(rx, frames[2]), VP_ERR_SEQUENCE);
  // duplicated frame
  vp_can_rx_init(&rx);
  push(rx, frames[0]);
  push(rx, frames[1]);
  EXPECT_EQ(push(rx, frames[1]), VP_ERR_SEQUENCE);
  // corrupted payload byte: CRC catches what the per-frame CAN CRC could not (a reordered/replaced chunk)
  vp_can_rx_init(&rx);
  auto bad = frames;
  bad[3].data[2] ^= 0x01;
  int st = VP_NEED_MORE;
  for (auto& f : bad) st = push(rx, f);
  EXPECT_EQ(st, VP_ERR_CRC);
  // two sources interleaved: separate slots by CAN ID
  auto other = encode_can_classic(sample(VP_MSG_POSE_SAMPLE, 10), 4, 7);
  vp_can_rx_init(&rx);
  int done = 0;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    done += push(rx, frames[i]) == VP_OK;
    done += push(rx, other[i]) == VP_OK;
  }
  EXPECT_EQ(done, 2);
  // reserved ID bits set: a different ID scheme, rejected
  vp_can_rx_init(&rx);
  EXPECT_EQ(vp_can_rx_push(&rx, frames[0].id | 0x80u, frames[0].data.data(), 8, &node, &out), VP_ERR_FRAMING);
}

TEST(ProtocolCodec, CanFdPaddingRules) {
  vp_message m = sample(VP_MSG_CONFIG, 1), out{};
  auto f = encode_canfd(m, 1);
  ASSERT_TRUE(f);
  EXPECT_EQ(f->data.size(), 12u);  // 11-byte packet rounds up to the 12-byte FD length
  Bytes longer = f->data;
  longer.resize(16);
  EXPECT_EQ(vp_canfd_decode(f->id, longer.data(), longer.size(), nullptr, &out), VP_ERR_LENGTH);
  EXPECT_EQ(vp_canfd_decode(f->id, f->data.data(), 8, nullptr, &out), VP_ERR_TRUNCATED);
}

// Random bytes into every decoder: never a crash, never VP_OK for something that does not
// re-encode to the same bytes (i.e. nothing is "misparsed"). The libFuzzer targets do this with
// coverage guidance; this is the deterministic version that runs in every build.
TEST(ProtocolCodec, RandomInputNeverMisparsed) {
  std::mt19937 rng(1234);
  vp_serial_rx srx;
  vp_serial_rx_init(&srx);
  vp_can_rx crx;
  vp_can_rx_init(&crx);
  int accepted = 0;
  for (int i = 0; i < 200000; ++i) {
    std::uint8_t buf[64];
    std::size_t n = rng() % 65;
    for (std::size_t k = 0; k < n; ++k) buf[k] = std::uint8_t(rng());
    if (n >= 4 && (rng() & 1)) {  // make it more interesting: valid-looking header
      buf[0] = 0x10;
      buf[1] = std::uint8_t(rng() % 2 ? VP_MSG_CONFIG : VP_MSG_CALIB_REQUEST);
      buf[3] = std::uint8_t(n - 4);
    }
    vp_message m{};
    if (vp_decode_packet(buf, n, &m) == VP_OK) {
      ++accepted;
      Bytes again = encode_packet(m);
      ASSERT_EQ(again, Bytes(buf, buf + n));
    }
    std::size_t used;
    vp_serial_rx_push(&srx, buf, n, &used, &m);
    std::uint8_t node;
    vp_can_rx_push(&crx, rng() & 0x1FFFFFFF, buf, n % 9, &node, &m);
    vp_canfd_decode(rng() & 0x1FFFFFFF, buf, n, &node, &m);
  }
  EXPECT_GT(accepted, 0) << "the generator does hit valid packets";
}

}  // namespace
