// device_status_t's counters by cause and its states, from a real drivers::DeviceSession through
// telemetry_mapping.cpp and LCM (memq) to lcm-gen's decoder: every rejection the session counts
// arrives under its own field, a refused device is ERROR with its reason, and the rate the host
// configures is the protocol's for the device's type. (The whole-session contract, with frames
// refused on a real link, is tests/rig/session/telemetry_contract_test.cpp.)
#include <gtest/gtest.h>

#include <vector>

#include "core/sim/simulation.hpp"
#include "drivers/session.hpp"
#include "tests/core/test_meshes.hpp"
#include "rig/telemetry/publisher.hpp"
#include "rig/telemetry/telemetry_mapping.hpp"
#include "vitreo_lcm/device_status_t.hpp"
#include "vitreo_lcm/event_t.hpp"

using namespace vitreo;
using M = vitreo_lcm::device_status_t;

namespace {

struct Last {
  std::vector<M> got;
  void operator()(const M& m) { got.push_back(m); }
};

vp_message device_info(std::uint8_t seq, std::uint8_t type, std::uint8_t major, std::uint32_t serial = 1001) {
  vp_message m{};
  m.type = VP_MSG_DEVICE_INFO;
  m.seq = seq;
  m.u.device_info.device_type = type;
  m.u.device_info.proto_major = major;
  m.u.device_info.serial = serial;
  return m;
}

// Publishes the session's status through LCM and returns it decoded.
M published(const drivers::DeviceSession& s, std::uint64_t now_us, telemetry::DeviceMeasured measured = {},
            std::string_view calibration = {}) {
  telemetry::TelemetryPublisher pub(telemetry::PublisherConfig{"memq://", 16});
  telemetry::TelemetrySource& src = pub.add_source("devices");
  Last last;
  auto sub = telemetry::subscribe_to<M>(pub.lcm(), telemetry::kChanDeviceStatus, &last);
  src.push(telemetry::device_status_item(7, "tracker-0", "serial:/dev/ttyACM0", s, now_us, measured, calibration));
  pub.pump();
  while (pub.handle_incoming() > 0) {
  }
  EXPECT_EQ(last.got.size(), 1u);
  return last.got.empty() ? M{} : last.got.back();
}

}  // namespace

TEST(DeviceStatusMapping, EveryRejectionArrivesUnderItsOwnCause) {
  drivers::SessionConfig cfg;
  cfg.expected_device_type = VP_DEVICE_TRACKER;
  drivers::DeviceSession s(cfg);
  s.transport_up(1000);
  const M before = published(s, 1000);
  EXPECT_EQ(int{before.state}, int{M::STATE_INACTIVE}) << "identifying";
  EXPECT_EQ(before.detail, "");
  EXPECT_EQ(before.frames_tx, 1) << "the identify request";
  EXPECT_EQ(before.last_sample_age_us, -1) << "no sample yet";
  EXPECT_EQ(before.configured_rate_hz, 0) << "not identified";

  // Frames refused by the decoder, 1..6 of each cause in the receiver's order.
  const vp_message none{};
  int n = 1;
  for (int status : {VP_ERR_CRC, VP_ERR_FRAMING, VP_ERR_VERSION, VP_ERR_UNKNOWN_TYPE, VP_ERR_LENGTH, VP_ERR_RANGE}) {
    for (int i = 0; i < n; ++i) s.on_frame(status, none, 2000);
    ++n;
  }
  // A valid DEVICE_INFO of the wrong kind (a pedal at the tracker's address), then of another
  // protocol major version.
  s.on_frame(VP_OK, device_info(1, VP_DEVICE_PEDAL, VP_PROTO_MAJOR), 3000);
  const M wrong_kind = published(s, 3000);
  EXPECT_EQ(int{wrong_kind.state}, int{M::STATE_ERROR});
  EXPECT_NE(wrong_kind.detail.find("expected type 1"), std::string::npos) << wrong_kind.detail;
  s.on_frame(VP_OK, device_info(2, VP_DEVICE_TRACKER, VP_PROTO_MAJOR + 1), 4000);
  const M m = published(s, 4000, {812.5f, 120.0f, 480.0f, 3, 21.5f, 4.25});
  EXPECT_EQ(int{m.state}, int{M::STATE_ERROR}) << "refused: not silently 'connecting' for ever";
  EXPECT_NE(m.detail.find("protocol 2."), std::string::npos) << m.detail;
  EXPECT_EQ(m.crc_errors, 1);
  EXPECT_EQ(m.framing_errors, 2);
  EXPECT_EQ(m.version_rejected, 3);
  EXPECT_EQ(m.unknown_type_rejected, 4);
  EXPECT_EQ(m.length_rejected, 5);
  EXPECT_EQ(m.range_rejected, 6);
  EXPECT_EQ(m.identity_rejected, 1);
  EXPECT_EQ(m.protocol_rejected, 1);
  EXPECT_EQ(m.frames_rx, 21 + 2) << "every frame, valid or not";
  EXPECT_EQ(m.device_id, 7);
  EXPECT_EQ(m.name, "tracker-0");
  EXPECT_EQ(m.transport, "serial:/dev/ttyACM0");
  // What the hub measures goes through as it is.
  EXPECT_FLOAT_EQ(m.sample_rate_hz, 812.5f);
  EXPECT_DOUBLE_EQ(m.t_s, 4.25) << "the session time the hub took it at";
  EXPECT_FLOAT_EQ(m.latency_p50_us, 120.0f);
  EXPECT_FLOAT_EQ(m.latency_p99_us, 480.0f);
  EXPECT_EQ(m.reader_stalls, 3);
  EXPECT_FLOAT_EQ(m.reader_stall_max_ms, 21.5f);

  // The right device answers: no longer refused, configured at the tracker's 1000 Hz.
  s.on_frame(VP_OK, device_info(3, VP_DEVICE_TRACKER, VP_PROTO_MAJOR), 5000);
  const M ok = published(s, 5000);
  EXPECT_EQ(int{ok.state}, int{M::STATE_INACTIVE}) << "configuring";
  EXPECT_EQ(ok.detail, "");
  EXPECT_EQ(ok.configured_rate_hz, 1000);
  EXPECT_GE(ok.frames_tx, 4) << "identify, rate, streaming, time sync";
}

TEST(DeviceStatusMapping, TheHostConfiguresEachTypeAtItsProtocolRate) {
  for (auto [type, rate] : {std::pair{VP_DEVICE_TRACKER, 1000}, {VP_DEVICE_PEDAL, 500}, {VP_DEVICE_EYEBALL, 250}}) {
    drivers::DeviceSession s;
    std::vector<vp_message> sent;
    s.set_send([&](const vp_message& m) { sent.push_back(m); });
    s.transport_up(0);
    s.on_frame(VP_OK, device_info(0, static_cast<std::uint8_t>(type), VP_PROTO_MAJOR), 10);
    bool configured = false;
    for (const auto& m : sent) {
      if (m.type == VP_MSG_CONFIG && m.u.config.op == VP_CFG_SET && m.u.config.key == VP_CFG_KEY_SAMPLE_RATE_HZ) {
        EXPECT_EQ(m.u.config.value, static_cast<unsigned>(rate)) << "device type " << int{type};
        configured = true;
      }
    }
    EXPECT_TRUE(configured);
    EXPECT_EQ(published(s, 10).configured_rate_hz, rate);
  }
}

TEST(DeviceStatusMapping, StaleIsActiveWithItsReasonAndLostSaysWhy) {
  drivers::DeviceSession s;
  s.transport_up(0);
  s.on_frame(VP_OK, device_info(0, VP_DEVICE_TRACKER, VP_PROTO_MAJOR), 10);
  vp_message ack{};
  ack.type = VP_MSG_CONFIG;
  ack.seq = 1;
  ack.u.config = {VP_CFG_ACK, VP_CFG_KEY_STREAMING, 1};
  s.on_frame(VP_OK, ack, 20);
  vp_message pose{};
  pose.type = VP_MSG_POSE_SAMPLE;
  pose.seq = 2;
  pose.u.pose.q_wxyz[0] = 1;
  pose.u.pose.timestamp_us = 5'000'000;
  s.on_frame(VP_OK, pose, 1000);
  const M streaming = published(s, 1500);
  EXPECT_EQ(int{streaming.state}, int{M::STATE_ACTIVE});
  EXPECT_EQ(streaming.detail, "");
  EXPECT_EQ(streaming.last_sample_age_us, 500);
  s.tick(30'000);  // 29 ms without a sample: stale
  const M stale = published(s, 30'000);
  EXPECT_EQ(int{stale.state}, int{M::STATE_ACTIVE}) << "stale is late samples, not an error";
  EXPECT_EQ(stale.detail, "stale: no sample for 29 ms");
  EXPECT_EQ(stale.last_sample_age_us, 29'000);
  s.transport_down(40'000, "serial port hung up");
  const M lost = published(s, 40'000);
  EXPECT_EQ(int{lost.state}, int{M::STATE_LOST});
  EXPECT_EQ(lost.detail, "serial port hung up");
  // The calibration in force goes out with every status, whatever the link does.
  EXPECT_EQ(lost.calibration, "");
  const M calibrated = published(s, 40'000, {}, "2026-11-26T06:09:37Z vitreo-calibrate 0.1.0");
  EXPECT_EQ(calibrated.calibration, "2026-11-26T06:09:37Z vitreo-calibrate 0.1.0");
}

// event_t from a real core step: a membrane bound by weak attachments, lifted by forceps (the peel
// of tests/core/instruments). Every broken attachment the tissue reports goes out once — as the
// instruments' attachment_broken, with the surface and no hand blamed — not a second time as the
// tissue's own; and through LCM it decodes to what event_t.lcm says.
TEST(EventMapping, ABrokenAttachmentIsPublishedOnce) {
  using namespace vitreo::core;
  auto sheet = [](double z) {
    SurfaceDescription d;
    d.mesh = test::rectangle(4.0, 4.0, 20, 20);
    for (auto& p : d.mesh.positions) p += Vec3(-2.0, -2.0, z);
    d.material.tear_strain = 0.3;
    d.contained_by_globe = false;
    return d;
  };
  Environment env;
  env.apply_pressure = false;
  SolverSettings settings;
  settings.sleeping = false;
  settings.substeps = 8;
  TissueWorld world(GlobeWall::sphere(Vec3::Zero(), 12.0), env, settings);
  const std::uint32_t base = world.add_surface(sheet(0.0));
  for (std::uint32_t v = 0; v < world.surface(base).vertex_slots(); ++v) ASSERT_TRUE(world.surface(base).set_fixed(world.surface(base).vertex_id(v), true));
  const std::uint32_t membrane = world.add_surface(sheet(0.0));
  for (std::uint32_t v = 0; v < world.surface(membrane).vertex_slots(); v += 2) {
    AttachmentDescription a;
    a.surface_a = membrane;
    a.vertex_a = v;
    a.surface_b = base;
    a.vertex_b = v;
    a.break_force_un = 20.0;  // weak: they let go
    world.add_attachment(a);
  }
  InstrumentSceneOptions o;
  o.ports_mm = {Vec3(0, 0, 10)};
  Simulation sys(world, o, {{InstrumentKind::kForceps, Gauge::k23, 0, {}}});
  auto down_to = [](double z, double actuation) {
    InstrumentInput in = InstrumentInput::through_port(Vec3(0, 0, 10), -Vec3::UnitZ(), 10.0 - z);
    in.actuation = actuation;
    return in;
  };
  telemetry::TelemetryPublisher pub(telemetry::PublisherConfig{"memq://", 1 << 14});
  telemetry::TelemetrySource& src = pub.add_source("physics");
  struct Events {
    std::vector<vitreo_lcm::event_t> got;
    void operator()(const vitreo_lcm::event_t& m) { got.push_back(m); }
  } events;
  auto sub = telemetry::subscribe_to<vitreo_lcm::event_t>(pub.lcm(), telemetry::kChanEvent, &events);
  std::size_t broken = 0;
  for (int i = 0; i <= 420; ++i) {
    ASSERT_TRUE(sys.set_input(0, i <= 20 ? down_to(0.05, i / 20.0) : down_to(0.05 + 2.0 * (i - 20) / 400.0, 1.0)));
    broken += sys.step(1e-3).tissue.attachments_broken;
    telemetry::step_event_items(world.events(), sys.events(), i, i * 1e-3, [](std::uint32_t) { return 0; },
                                [&](const telemetry::Event& e) { src.push(e); });
    pub.pump();
    while (pub.handle_incoming() > 0) {
    }
  }
  ASSERT_GT(broken, 0u) << "the peel broke attachments";
  std::size_t published = 0;
  for (const auto& e : events.got) {
    if (e.kind != vitreo_lcm::event_t::KIND_ATTACHMENT_BROKEN) continue;
    ++published;
    EXPECT_EQ(e.what, "attachment_broken");
    EXPECT_EQ(e.tissue_id, static_cast<std::int32_t>(membrane)) << "the surface whose attachment broke";
    EXPECT_EQ(e.instrument_id, -1) << "no instrument is blamed for an attachment";
    EXPECT_GT(e.magnitude, 20.0) << "µN, above the break force";
    EXPECT_DOUBLE_EQ(e.t_s, static_cast<double>(e.step) * 1e-3);
  }
  EXPECT_EQ(published, broken) << "once each";
  for (const auto& e : events.got) EXPECT_NE(e.what, "tissue_attachment_broken");
}
