#include <gtest/gtest.h>

#include "rig/calibration/clock_sync.hpp"
#include "rig/calibration/pedal_range.hpp"
#include "rig/calibration/ports.hpp"
#include "rig/calibration/registration.hpp"
#include "tests/rig/calibration/synthetic.hpp"

namespace vitreo::rig::calibration {
namespace {

using testing::kNoiseMm;
using testing::Synth;

TEST(Ports, RecoveredThroughANoisyRegistrationWithin0_2mm) {
  Synth s;
  RigidTransform truth;
  truth.rotation = core::Quat(Eigen::AngleAxisd(-0.4, core::Vec3(1, 2, 0.5).normalized()));
  truth.translation_mm = core::Vec3(30.0, -12.0, -250.0);
  auto to_rig = [&](const core::Vec3& e) { return core::Vec3(truth.rotation.conjugate() * (e - truth.translation_mm)); };
  std::vector<core::Vec3> fid_eye = {{0, 0, 12}, {9, 0, 8}, {-9, 0, 8}, {0, 9, 8}, {0, -9, 8}, {13, 0, 0}};
  std::vector<core::Vec3> fid_rig;
  for (const auto& f : fid_eye) fid_rig.push_back(to_rig(f) + s.noise(kNoiseMm));
  const RegistrationResult reg = register_points(fid_rig, fid_eye);
  ASSERT_TRUE(reg.ok) << reg.error;
  // Two pars plana ports, 3.5 mm behind the limbus, at 10 and 2 o'clock.
  for (const core::Vec3& port : {core::Vec3(-9.6, 5.5, 4.6), core::Vec3(9.6, 5.5, 4.6)}) {
    std::vector<core::Vec3> tips;
    for (int i = 0; i < 200; ++i) tips.push_back(reg.rig_to_eye.apply(to_rig(port) + s.noise(kNoiseMm)));
    const PortResult r = measure_port(tips);
    ASSERT_TRUE(r.ok) << r.error;
    EXPECT_LT((r.position_mm - port).norm(), 0.2);
    EXPECT_NEAR(r.outward.dot(port.normalized()), 1.0, 1e-3);
    EXPECT_NEAR(r.spread_mm, kNoiseMm * std::sqrt(3.0), 0.02);
  }
}

TEST(Ports, RefusesAMovingTipAndTooFewSamples) {
  Synth s;
  std::vector<core::Vec3> tips;
  for (int i = 0; i < 100; ++i) tips.push_back(core::Vec3(9.6, 5.5, 4.6) + core::Vec3(0.01 * i, 0, 0));
  PortResult r = measure_port(tips);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("hold it still"), std::string::npos) << r.error;
  tips.resize(5);
  r = measure_port(tips);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("too few samples"), std::string::npos) << r.error;
}

// A pedal whose potentiometer reads `lo` at rest and `hi` fully down, with reading noise.
struct PedalSweep {
  std::vector<double> rest, travel;
};
PedalSweep sweep(Synth& s, double lo, double hi, double noise) {
  PedalSweep p;
  for (int i = 0; i < 200; ++i) p.rest.push_back(lo + s.gauss(noise));
  for (int i = 0; i <= 400; ++i) {  // down and up, pausing at the bottom
    const double travel = i < 150 ? i / 150.0 : i < 250 ? 1.0 : (400 - i) / 150.0;
    p.travel.push_back(lo + (hi - lo) * travel + s.gauss(noise));
  }
  return p;
}

TEST(PedalRange, RecoversRangeWithin2PercentAndMapsItOnto0To1) {
  Synth s;
  const double lo = 0.07, hi = 0.91;
  const PedalSweep p = sweep(s, lo, hi, 0.003);
  const PedalRangeResult r = measure_pedal_range(p.rest, p.travel);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_NEAR(r.range.lo, lo, 0.02 * (hi - lo));
  EXPECT_NEAR(r.range.hi, hi, 0.02 * (hi - lo));
  // Rest jitter never opens the pedal; fully down reads (nearly) 1; half way reads about half.
  for (double x : p.rest) EXPECT_EQ(r.range.apply(x), 0.0);
  EXPECT_GT(r.range.apply(hi), 0.98);
  EXPECT_NEAR(r.range.apply(lo + 0.5 * (hi - lo)), 0.5, 0.03);
  EXPECT_LT(r.range.dead_zone, 0.05);
}

TEST(PedalRange, RefusesAPedalThatWasNotPressed) {
  Synth s;
  const PedalSweep p = sweep(s, 0.07, 0.2, 0.003);
  const PedalRangeResult r = measure_pedal_range(p.rest, p.travel);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("press it all the way down"), std::string::npos) << r.error;
  EXPECT_FALSE(measure_pedal_range({0.1, 0.1}, p.travel).ok);
}

// Exchanges between a host and a device whose clock is offset and drifts, with random queueing.
std::vector<TimeSyncExchange> exchanges(Synth& s, double offset_us, double drift_ppm, int count, double every_us) {
  std::vector<TimeSyncExchange> ex;
  const std::uint64_t host0 = 1'764'000'000'000'000ull;  // a wall-clock host epoch
  auto device = [&](double host_us) {
    return static_cast<std::uint64_t>(host_us + offset_us + drift_ppm * 1e-6 * (host_us - static_cast<double>(host0)));
  };
  for (int i = 0; i < count; ++i) {
    const double t1 = static_cast<double>(host0) + i * every_us;
    // 120 µs each way on the wire, plus exponential queueing (mean 2 ms) in a third of exchanges
    const double up = 120 + (s.uniform(0, 1) < 0.33 ? std::exponential_distribution<double>(1 / 2000.0)(s.rng) : s.uniform(0, 20));
    const double down = 120 + (s.uniform(0, 1) < 0.33 ? std::exponential_distribution<double>(1 / 2000.0)(s.rng) : s.uniform(0, 20));
    const double t2h = t1 + up, t3h = t2h + 50, t4 = t3h + down;
    ex.push_back({static_cast<std::uint64_t>(t1), device(t2h), device(t3h), static_cast<std::uint64_t>(t4)});
  }
  return ex;
}

TEST(ClockSync, RecoversOffsetWithin0_5msAndDrift) {
  Synth s;
  const double offset_us = -3'000'000'000.0 + 12'345.0, drift_ppm = 80.0;
  const auto ex = exchanges(s, offset_us, drift_ppm, 50, 100'000.0);
  const ClockResult r = estimate_clock(ex);
  ASSERT_TRUE(r.ok) << r.error;
  // The truth at the reference time the estimate states.
  const double ref = static_cast<double>(r.reference_host_us);
  const double true_offset_ms = (offset_us + drift_ppm * 1e-6 * (ref - static_cast<double>(ex.front().host_tx_us))) * 1e-3;
  EXPECT_NEAR(r.offset_ms, true_offset_ms, 0.5);
  EXPECT_NEAR(r.drift_ppm, drift_ppm, 20.0);
  EXPECT_NEAR(r.latency_ms, 0.13, 0.05);
  EXPECT_LE(r.used, 26u);
  // device → host with the fitted line inverts the injected clock.
  const double host = ref - 1'000'000.0;
  const double dev = host + offset_us + drift_ppm * 1e-6 * (host - static_cast<double>(ex.front().host_tx_us));
  EXPECT_NEAR(r.device_to_host_us(dev), host, 500.0);
}

TEST(ClockSync, RefusesTooFewOrTooCloseExchanges) {
  Synth s;
  EXPECT_NE(estimate_clock(exchanges(s, 0, 0, 3, 100'000.0)).error.find("too few"), std::string::npos);
  EXPECT_NE(estimate_clock(exchanges(s, 0, 0, 20, 1'000.0)).error.find("span"), std::string::npos);
}

}  // namespace
}  // namespace vitreo::rig::calibration
