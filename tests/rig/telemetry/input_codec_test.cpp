// The typed input records and their one codec (input_codec.hpp): every kind goes to device_input_t
// and back bit for bit, travels under the code and in the value order RECORDING.md documents, and a
// message that no kind's range allows is refused with a reason, never converted.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "rig/telemetry/input_codec.hpp"

using namespace vitreo::telemetry;

namespace {

RecordedInput stamped(InputPayload what) {
  RecordedInput in;
  in.host_time_us = 1'234'567;
  in.device_time_us = -42;
  in.step = 99;
  in.device_id = 3;
  in.channel = 1;
  in.sequence = 7'000'000'001;
  in.what = what;
  return in;
}

// Encoded, put through LCM's own encoder and decoder (as the file holds it), read back.
RecordedInput round_trip(const RecordedInput& in, vitreo_lcm::device_input_t* wire = nullptr) {
  const vitreo_lcm::device_input_t m = to_lcm(in);
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
  EXPECT_EQ(m.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  vitreo_lcm::device_input_t decoded;
  EXPECT_EQ(decoded.decode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  if (wire) *wire = decoded;
  RecordedInput back;
  const char* why = from_lcm(decoded, back);
  EXPECT_EQ(why, nullptr) << why;
  return back;
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

const double kTiny = std::numeric_limits<double>::denorm_min();
const double kThird = 1.0 / 3.0;

}  // namespace

TEST(InputCodec, TrackerSampleRoundTripsUnderCode1) {
  TrackerSample t;
  t.tip_mm = {-0.0, kTiny, 12.5};
  t.q_wxyz = {kThird, -kThird, 0.5, -0.5};
  t.actuation = 0.75;
  t.quality = kThird;
  t.instrument_id = 1;
  t.tool_type = 10;
  vitreo_lcm::device_input_t wire;
  const RecordedInput back = round_trip(stamped(t), &wire);
  EXPECT_TRUE(back == stamped(t));
  const auto& b = std::get<TrackerSample>(back.what);
  EXPECT_TRUE(same_bits(b.tip_mm[0], -0.0));
  EXPECT_TRUE(same_bits(b.tip_mm[1], kTiny));
  EXPECT_EQ(b.q_wxyz, t.q_wxyz);
  EXPECT_EQ(b.instrument_id, 1);
  EXPECT_EQ(b.tool_type, 10);
  // RECORDING.md: tip x y z, q w x y z, actuation, quality, instrument id, tool type.
  EXPECT_EQ(wire.device_kind, 1);
  ASSERT_EQ(wire.n_values, 11);
  EXPECT_EQ(wire.values[2], 12.5);
  EXPECT_EQ(wire.values[3], kThird);
  EXPECT_EQ(wire.values[7], 0.75);
  EXPECT_EQ(wire.values[9], 1.0);
  EXPECT_EQ(wire.values[10], 10.0);
  EXPECT_EQ(wire.n_raw, 0);
  EXPECT_EQ(wire.step, 99);
  EXPECT_EQ(wire.channel, 1);
  EXPECT_EQ(wire.sequence, 7'000'000'001);
}

TEST(InputCodec, EyeFixtureSampleRoundTripsUnderCode2WithAllFourPorts) {
  EyeFixtureSample e;
  e.q_wxyz = {0.5, 0.5, -0.5, 0.5};
  e.port_count = 4;
  e.inserted = {false, true, false, true};
  e.depth_mm = {0.0, 3.25, -0.0, 7.5};  // the fourth port's instrument 7.5 mm in
  vitreo_lcm::device_input_t wire;
  const RecordedInput back = round_trip(stamped(e), &wire);
  EXPECT_TRUE(back == stamped(e));
  const auto& b = std::get<EyeFixtureSample>(back.what);
  EXPECT_EQ(b.port_count, 4);
  EXPECT_TRUE(b.inserted[3]);
  EXPECT_EQ(b.depth_mm[3], 7.5);
  // q w x y z, port count, inserted ×4, depth ×4.
  EXPECT_EQ(wire.device_kind, 2);
  ASSERT_EQ(wire.n_values, 13);
  EXPECT_EQ(wire.values[4], 4.0);
  EXPECT_EQ(wire.values[8], 1.0);
  EXPECT_EQ(wire.values[12], 7.5);
}

TEST(InputCodec, PedalSampleRoundTripsUnderCode3) {
  PedalSample p;
  p.pedal_id = 1;
  p.axis_count = 4;
  p.axes = {kThird, -0.0, kTiny, 1.0};
  p.switches = 0xffff;
  vitreo_lcm::device_input_t wire;
  const RecordedInput back = round_trip(stamped(p), &wire);
  EXPECT_TRUE(back == stamped(p));
  EXPECT_EQ(std::get<PedalSample>(back.what).switches, 0xffff);
  // pedal id, axis count, axes ×4, switches.
  EXPECT_EQ(wire.device_kind, 3);
  ASSERT_EQ(wire.n_values, 7);
  EXPECT_EQ(wire.values[0], 1.0);
  EXPECT_EQ(wire.values[2], kThird);
  EXPECT_EQ(wire.values[6], 65535.0);
}

TEST(InputCodec, LinkChangeRoundTripsUnderCode4) {
  for (LinkEvent ev : {LinkEvent::Up, LinkEvent::Lost, LinkEvent::Stuck}) {
    vitreo_lcm::device_input_t wire;
    const RecordedInput back = round_trip(stamped(LinkChange{ev, 1}), &wire);
    EXPECT_TRUE(back == stamped(LinkChange{ev, 1}));
    EXPECT_EQ(std::get<LinkChange>(back.what).event, ev);
    EXPECT_EQ(wire.device_kind, 4);
    ASSERT_EQ(wire.n_values, 2);
    EXPECT_EQ(wire.values[0], static_cast<double>(ev));
    EXPECT_EQ(wire.values[1], 1.0);
  }
}

TEST(InputCodec, SessionEndRoundTripsUnderCode5) {
  vitreo_lcm::device_input_t wire;
  const RecordedInput back = round_trip(stamped(SessionEnd{100}), &wire);  // step 99: 100 steps ran
  EXPECT_TRUE(back == stamped(SessionEnd{100}));
  EXPECT_EQ(wire.device_kind, 5);
  ASSERT_EQ(wire.n_values, 1);
  EXPECT_EQ(wire.values[0], 100.0);
}

TEST(InputCodec, OperatorCommandRoundTripsUnderCode6) {
  const OperatorCommand pan{10, -2.5, kThird};
  vitreo_lcm::device_input_t wire;
  const RecordedInput back = round_trip(stamped(pan), &wire);
  EXPECT_TRUE(back == stamped(pan));
  EXPECT_EQ(std::get<OperatorCommand>(back.what).pan_y_mm, kThird);
  // code, value, pan y.
  EXPECT_EQ(wire.device_kind, 6);
  ASSERT_EQ(wire.n_values, 3);
  EXPECT_EQ(wire.values[0], 10.0);
  EXPECT_EQ(wire.values[1], -2.5);
  for (std::int8_t code = 1; code <= 16; ++code) EXPECT_TRUE(round_trip(stamped(OperatorCommand{code, 1.0, 0.0})) == stamped(OperatorCommand{code, 1.0, 0.0}));
}

TEST(InputCodec, CaseSwitchRoundTripsUnderCode7) {
  vitreo_lcm::device_input_t wire;
  const RecordedInput back = round_trip(stamped(CaseSwitch{4096}), &wire);
  EXPECT_TRUE(back == stamped(CaseSwitch{4096}));
  EXPECT_EQ(wire.device_kind, 7);
  ASSERT_EQ(wire.n_values, 1);
  EXPECT_EQ(wire.values[0], 4096.0);
}

// What the reader refuses (RECORDING.md's ranges), each from an otherwise valid message.
TEST(InputCodec, RefusesWhatNoKindAllows) {
  auto refused = [](const InputPayload& what, auto&& damage) {
    vitreo_lcm::device_input_t m = to_lcm(stamped(what));
    damage(m);
    RecordedInput out;
    const char* why = from_lcm(m, out);
    return why ? std::string(why) : std::string();
  };
  TrackerSample t;
  t.quality = 1.0;
  EXPECT_NE(refused(t, [](auto& m) { m.values[10] = 1e300; }), "") << "a tool type that is no byte";
  EXPECT_NE(refused(t, [](auto& m) { m.values[10] = -1; }), "");
  EXPECT_NE(refused(t, [](auto& m) { m.values[9] = 0.5; }), "") << "an instrument id that is no whole number";
  EXPECT_NE(refused(t, [](auto& m) { m.values[0] = std::nan(""); }), "");
  EXPECT_NE(refused(t, [](auto& m) { m.values[1] = std::numeric_limits<double>::infinity(); }), "");
  EXPECT_NE(refused(t, [](auto& m) { m.values.pop_back(), m.n_values = 10; }), "") << "a count that does not fit the kind";
  EXPECT_NE(refused(t, [](auto& m) { m.n_values = 12; }), "") << "counts and arrays disagree";
  EXPECT_NE(refused(t, [](auto& m) { m.raw = {1, 2}, m.n_raw = 2; }), "") << "raw bytes";
  EXPECT_NE(refused(t, [](auto& m) { m.step = -1; }), "");
  EXPECT_NE(refused(t, [](auto& m) { m.step = kMaxRecordedStep + 1; }), "");
  for (std::int8_t kind : {std::int8_t{0}, std::int8_t{8}, std::int8_t{-1}}) {
    EXPECT_NE(refused(t, [&](auto& m) { m.device_kind = kind; }), "") << "kind " << int{kind};
  }
  EyeFixtureSample e;
  EXPECT_NE(refused(e, [](auto& m) { m.values[4] = 5; }), "") << "five ports";
  EXPECT_NE(refused(e, [](auto& m) { m.values[8] = 0.5; }), "") << "a port half in";
  PedalSample p;
  EXPECT_NE(refused(p, [](auto& m) { m.values[1] = 5; }), "") << "five axes";
  EXPECT_NE(refused(p, [](auto& m) { m.values[6] = 65536; }), "") << "17 switches";
  EXPECT_NE(refused(LinkChange{}, [](auto& m) { m.values[0] = 4; }), "") << "a link state that is none";
  EXPECT_NE(refused(LinkChange{}, [](auto& m) { m.values[1] = 4; }), "") << "a device type that is none";
  EXPECT_NE(refused(SessionEnd{100}, [](auto& m) { m.values[0] = 99; }), "") << "an end that is not its step + 1";
  EXPECT_NE(refused(SessionEnd{100}, [](auto& m) { m.values[0] = 1e12; }), "");
  EXPECT_NE(refused(OperatorCommand{1, 0, 0}, [](auto& m) { m.values[0] = 17; }), "") << "an unknown command";
  EXPECT_NE(refused(OperatorCommand{1, 0, 0}, [](auto& m) { m.values[0] = 0; }), "");
  EXPECT_NE(refused(CaseSwitch{}, [](auto& m) { m.values[0] = 4097; }), "") << "a case index out of range";
  EXPECT_NE(refused(CaseSwitch{}, [](auto& m) { m.values[0] = -1; }), "");
  EXPECT_EQ(refused(CaseSwitch{}, [](auto&) {}), "") << "the undamaged message is accepted";
}
