// The emulators' calibration imperfections (drivers/sim/emulator.hpp): what each one does to the
// samples on the wire, checked against the same geometry computed independently with Eigen.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <numbers>

#include "drivers/sim/emulator.hpp"

namespace vitreo::drivers::sim {
namespace {

Script parse(const std::string& text) {
  Script s;
  std::string err;
  EXPECT_TRUE(parse_script(text, s, &err)) << err;
  return s;
}

// Starts streaming and returns the first valid sample of the given type decoded from the wire.
vp_message first_sample(FirmwareEmulator& emu, std::uint8_t type, std::uint64_t at_us = 1'000'000) {
  vp_message set{};
  set.type = VP_MSG_CONFIG;
  set.u.config.op = VP_CFG_SET;
  set.u.config.key = VP_CFG_KEY_STREAMING;
  set.u.config.value = 1;
  emu.on_host_message(set, at_us);
  std::vector<proto::Bytes> packets;
  emu.step(at_us, packets);
  for (const proto::Bytes& p : packets) {
    vp_message m{};
    if (vp_decode_packet(p.data(), p.size(), &m) == VP_OK && m.type == type) return m;
  }
  ADD_FAILURE() << "no sample of type " << int(type);
  return {};
}

Eigen::Quaterniond ypr(double yaw, double pitch, double roll) {
  const double d = std::numbers::pi / 180.0;
  return Eigen::AngleAxisd(yaw * d, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch * d, Eigen::Vector3d::UnitY()) *
         Eigen::AngleAxisd(roll * d, Eigen::Vector3d::UnitX());
}

const char* const kTracker = "device tracker\nnoise 0\nloop 0\nkey 0 1 2 3 10 20 30 0\n";

TEST(EmulatorImperfections, TrackerReportsTheOffsetPointInItsOwnFrame) {
  FirmwareEmulator emu(parse(std::string(kTracker) + "tip_offset 0.5 -0.3 14\ntracker_frame 30 -10 5 100 -50 400\n"));
  const vp_message m = first_sample(emu, VP_MSG_POSE_SAMPLE);
  const Eigen::Quaterniond q = ypr(10, 20, 30), f = ypr(30, -10, 5);
  const Eigen::Vector3d expect = f * (Eigen::Vector3d(1, 2, 3) - q * Eigen::Vector3d(0.5, -0.3, 14)) + Eigen::Vector3d(100, -50, 400);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(m.u.pose.tip_mm[i], expect[i], 1e-3) << i;
  const Eigen::Quaterniond got(m.u.pose.q_wxyz[0], m.u.pose.q_wxyz[1], m.u.pose.q_wxyz[2], m.u.pose.q_wxyz[3]);
  EXPECT_LT(got.angularDistance(f * q), 1e-5);
}

TEST(EmulatorImperfections, NoneByDefaultAndZeroIsNone) {
  FirmwareEmulator plain(parse(kTracker)), zero(parse(std::string(kTracker) + "tip_offset 0 0 0\ntracker_frame 0 0 0 0 0 0\n"));
  const vp_message a = first_sample(plain, VP_MSG_POSE_SAMPLE), b = first_sample(zero, VP_MSG_POSE_SAMPLE);
  EXPECT_EQ(proto::encode_packet(a), proto::encode_packet(b));
  EXPECT_FLOAT_EQ(a.u.pose.tip_mm[2], 3.0f);
}

TEST(EmulatorImperfections, PedalsReadTheirPotentiometersRange) {
  FirmwareEmulator emu(parse("device pedals\nloop 0\nkey 0 0.5 1 0\npedal_range 0 0.07 0.91\npedal_range 1 0.1 0.8\n"));
  const vp_message m = first_sample(emu, VP_MSG_PEDAL_STATE);
  EXPECT_NEAR(m.u.pedal.axes[0] / 65535.0, 0.07 + 0.84 * 0.5, 1e-4);
  EXPECT_NEAR(m.u.pedal.axes[1] / 65535.0, 0.8, 1e-4);
}

// A second pedal (the microscope's): its id and four axes on the wire, decoded by the protocol's C
// decoder; the switch word after the last axis.
TEST(EmulatorImperfections, APedalNamesItsIdAndItsAxes) {
  FirmwareEmulator emu(parse("device pedals\npedal_id 1\naxes 4\nloop 0\nkey 0 0.25 0.5 0.75 1 5\n"));
  const vp_message m = first_sample(emu, VP_MSG_PEDAL_STATE);
  EXPECT_EQ(m.u.pedal.pedal_id, 1);
  EXPECT_EQ(m.u.pedal.axis_count, 4);
  for (int a = 0; a < 4; ++a) EXPECT_NEAR(m.u.pedal.axes[a] / 65535.0, 0.25 * (a + 1), 1e-4) << a;
  EXPECT_EQ(m.u.pedal.switches, 5);
  Script s;
  std::string err;
  EXPECT_FALSE(parse_script("device pedals\nkey 0 0 0 0\naxes 4\n", s, &err));
  EXPECT_NE(err.find("line 3: axes must come before the first key"), std::string::npos) << err;
  EXPECT_FALSE(parse_script("device pedals\naxes 4\nkey 0 0 0 0\n", s, &err)) << "a four-axis key has five values";
  EXPECT_FALSE(parse_script("device pedals\naxes 5\nkey 0 0 0 0\n", s, &err));
  EXPECT_NE(err.find("axes must be 1..4"), std::string::npos) << err;
}

TEST(EmulatorImperfections, ClockOffsetAndDriftShowInTimeSync) {
  const std::string base = "device eyeball\nkey 0 0 0 0 0 0\n";
  FirmwareEmulator ideal(parse(base)), skewed(parse(base + "clock_offset_ms 123.5\nclock_drift_ppm 250\n"));
  std::vector<proto::Bytes> ignore;
  const std::uint64_t start = 2'000'000, later = start + 10'000'000;  // 10 s of host time
  ideal.step(start, ignore), skewed.step(start, ignore);
  const double extra = static_cast<double>(skewed.device_time_us(later)) - static_cast<double>(ideal.device_time_us(later));
  EXPECT_NEAR(extra, 123'500.0 + 250e-6 * 10'000'000.0, 1.0);
  vp_message sync{};
  sync.type = VP_MSG_TIME_SYNC;
  sync.u.time_sync.phase = 0;
  sync.u.time_sync.host_tx_us = later;
  skewed.on_host_message(sync, later);
  std::vector<proto::Bytes> packets;
  skewed.step(later, packets);
  bool found = false;
  for (const proto::Bytes& p : packets) {
    vp_message m{};
    if (vp_decode_packet(p.data(), p.size(), &m) == VP_OK && m.type == VP_MSG_TIME_SYNC) {
      EXPECT_EQ(m.u.time_sync.device_rx_us, skewed.device_time_us(later));
      found = true;
    }
  }
  EXPECT_TRUE(found);
}

TEST(EmulatorImperfections, EyeballReadsItsZeroOffsetAtRest) {
  FirmwareEmulator emu(parse("device eyeball\nnoise 0\nloop 0\nkey 0 10 0 0 0 0\neye_zero 6 -4\n"));
  const vp_message m = first_sample(emu, VP_MSG_EYEBALL_STATE);
  const Eigen::Quaterniond got(m.u.eyeball.q_wxyz[0], m.u.eyeball.q_wxyz[1], m.u.eyeball.q_wxyz[2], m.u.eyeball.q_wxyz[3]);
  EXPECT_LT(got.angularDistance(ypr(6, -4, 0) * ypr(10, 0, 0)), 1e-5);
}

TEST(EmulatorImperfections, BadDirectivesAreRefusedWithTheirLine) {
  Script s;
  std::string err;
  EXPECT_FALSE(parse_script("device pedals\nkey 0 0 0 0\npedal_range 0 0.9 0.1\n", s, &err));
  EXPECT_NE(err.find("line 3: pedal_range needs 0 <= LO < HI <= 1"), std::string::npos) << err;
  EXPECT_FALSE(parse_script("device tracker\nclock_offset_ms -5000\nkey 0 0 0 0 0 0 0 0\n", s, &err));
  EXPECT_NE(err.find("line 2"), std::string::npos) << err;
  EXPECT_FALSE(parse_script("device tracker\ntip_offset 1 2\nkey 0 0 0 0 0 0 0 0\n", s, &err));
  EXPECT_FALSE(parse_script("device tracker\ntracker_frame 1 2 3 4 5 nan\nkey 0 0 0 0 0 0 0 0\n", s, &err));
}

}  // namespace
}  // namespace vitreo::drivers::sim
