// The USB driver (libusb-1.0, asynchronous interrupt/bulk transfers, hotplug) against firmware
// emulators behind umockdev-simulated USB devices. Runs under umockdev-wrapper (CTest does that);
// skipped with a message when the preload library is not active.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>

#include "drivers/open_device.hpp"
#include "drivers/sim/usb_sim.hpp"
#include "drivers/usb.hpp"

namespace {

using namespace vitreo::drivers;

#define REQUIRE_UMOCKDEV()                                                                       \
  do {                                                                                           \
    if (!sim::UsbSimDevice::mock_environment_available())                                        \
      GTEST_SKIP() << "not under umockdev-wrapper (LD_PRELOAD=libumockdev-preload.so.0): USB " \
                      "simulation unavailable";                                                  \
  } while (0)

struct UsbBench {
  explicit UsbBench(sim::Script s, std::uint16_t pid = kTrackerPid) : device(std::move(s), pid), driver(kVitreoUsbVid, pid, clock) {
    EXPECT_TRUE(device.ok()) << device.error();
    std::string err;
    EXPECT_TRUE(driver.init(&err)) << err;
    device.emulator().set_on_sample_sent([this](const vp_message& m) { sent[m.u.pose.timestamp_us] = m; });
    driver.session().set_on_sample([this](const Sample& x) { got.push_back(x); });
  }
  void run_ms(int ms) {
    for (int i = 0; i < ms; ++i) {
      clock.advance_us(1000);
      device.step(clock.now_us());
      driver.poll(0);
    }
  }
  int invalid_delivered() {
    int bad = 0;
    for (auto& s : got) {
      auto& p = std::get<PoseSample>(s);
      auto it = sent.find(p.t.device_us);
      if (it == sent.end() || std::memcmp(it->second.u.pose.tip_mm, p.tip_mm.data(), 12) != 0 ||
          std::memcmp(it->second.u.pose.q_wxyz, p.q_wxyz.data(), 16) != 0)
        ++bad;
    }
    return bad;
  }
  ManualClock clock;
  sim::UsbSimDevice device;
  UsbDevice driver;
  std::map<std::uint64_t, vp_message> sent;
  std::vector<Sample> got;
};

sim::Script tracker(const std::string& extra = "") {
  sim::Script s;
  std::string err;
  EXPECT_TRUE(sim::parse_script("device tracker\nserial 4242\nkey 0 0 0 20 0 0 0 0\nkey 1000 3 -2 12 10 -5 0 1\n" + extra, s, &err)) << err;
  return s;
}

TEST(UsbUmockdev, ListsAndIdentifiesDevices) {
  REQUIRE_UMOCKDEV();
  sim::UsbSimDevice dev(tracker(), kTrackerPid, 2);
  sim::UsbSimDevice pedals(sim::default_script(sim::DeviceKind::pedals), kPedalsPid, 3);
  ASSERT_TRUE(dev.ok() && pedals.ok()) << dev.error() << pedals.error();
  std::vector<UsbDeviceEntry> list;
  std::string err;
  ASSERT_TRUE(list_usb_devices(list, &err)) << err;
  ASSERT_EQ(list.size(), 2u);
  std::map<int, UsbDeviceEntry> by_pid;
  for (auto& e : list) by_pid[e.pid] = e;
  EXPECT_EQ(by_pid[kTrackerPid].product, "vitreo tracker");
  EXPECT_EQ(by_pid[kTrackerPid].serial, "4242");
  EXPECT_EQ(by_pid[kPedalsPid].product, "vitreo pedals");
  EXPECT_EQ(by_pid[kPedalsPid].address, 3);
}

TEST(UsbUmockdev, HandshakeAndStreamingOverInterruptAndBulk) {
  REQUIRE_UMOCKDEV();
  UsbBench b(tracker());
  std::vector<std::string> states;
  b.driver.session().set_on_state([&](LinkState, LinkState to, const char*) { states.push_back(to_string(to)); });
  b.run_ms(1000);
  EXPECT_EQ(states, (std::vector<std::string>{"connecting", "configuring", "streaming"}));
  ASSERT_TRUE(b.driver.session().has_device_info());
  EXPECT_EQ(b.driver.session().device_info().serial, 4242u);
  EXPECT_GT(b.got.size(), 900u);
  EXPECT_EQ(b.invalid_delivered(), 0);
  EXPECT_EQ(b.driver.session().stats().rejected(), 0u);
  EXPECT_EQ(b.driver.session().stats().drops, 0u);
  EXPECT_GT(b.device.emulator().counters().host_messages, 3u) << "identify, configure, time sync arrived over bulk OUT";
  std::printf("tracker over USB (umockdev): %s\n", to_string(b.driver.session().stats()).c_str());
}

TEST(UsbUmockdev, CorruptedTransfersAreRejectedAndCounted) {
  REQUIRE_UMOCKDEV();
  for (double p : {0.01, 0.10}) {
    UsbBench b(tracker("autostream 1\nseed 3\ncorrupt " + std::to_string(p) + "\nfault 3000 100 nan\n"));
    b.run_ms(5000);
    const auto& st = b.driver.session().stats();
    const auto& c = b.device.emulator().counters();
    std::printf(
        "USB link fault figures @ %4.1f %% corrupted bytes: transfers sent %llu, corrupted %llu, rejected %llu "
        "(crc %llu, range %llu), samples sent %llu, delivered %llu, invalid delivered %d\n",
        p * 100, (unsigned long long)c.frames_sent, (unsigned long long)c.frames_corrupted,
        (unsigned long long)st.rejected(), (unsigned long long)st.crc_errors, (unsigned long long)st.range_rejected,
        (unsigned long long)c.samples_sent, (unsigned long long)st.samples_delivered, b.invalid_delivered());
    EXPECT_EQ(b.invalid_delivered(), 0);
    // USB keeps transfer boundaries: every corrupted transfer is rejected, every clean one delivered
    EXPECT_EQ(st.frames, c.frames_sent);
    EXPECT_GE(st.rejected(), c.frames_corrupted);
    EXPECT_EQ(st.valid + st.rejected(), st.frames);
    EXPECT_GT(st.range_rejected, 0u);
  }
}

TEST(UsbUmockdev, UnplugIsLostAndReplugStreamsAgain) {
  REQUIRE_UMOCKDEV();
  UsbBench b(tracker());
  b.run_ms(300);
  ASSERT_EQ(b.driver.session().state(), LinkState::streaming);
  const std::uint64_t pulled = b.clock.now_us();
  std::uint64_t lost_at = 0;
  b.driver.session().set_on_state([&](LinkState, LinkState to, const char*) {
    if (to == LinkState::lost && !lost_at) lost_at = b.clock.now_us();
  });
  b.device.unplug();
  for (int i = 0; i < 50 && !lost_at; ++i) {
    b.clock.advance_us(1000);
    b.driver.poll(2);
  }
  ASSERT_NE(lost_at, 0u);
  EXPECT_LE(lost_at - pulled, 50'000u) << "hang-up seen within a few polls, not by the 250 ms silence timeout";
  b.run_ms(300);
  EXPECT_NE(b.driver.session().state(), LinkState::streaming);
  const std::size_t before = b.got.size();
  b.device.plug();
  for (int i = 0; i < 600 && b.driver.session().state() != LinkState::streaming; ++i) b.run_ms(1);
  EXPECT_EQ(b.driver.session().state(), LinkState::streaming);
  b.run_ms(200);
  EXPECT_GT(b.got.size(), before + 150);
  EXPECT_EQ(b.driver.session().stats().reconnects, 1u);
  EXPECT_GE(b.driver.hotplug_departures(), 1u);
  EXPECT_EQ(b.invalid_delivered(), 0);
  std::printf("after unplug/replug: %s (hotplug arrivals %llu, departures %llu)\n",
              to_string(b.driver.session().stats()).c_str(), (unsigned long long)b.driver.hotplug_arrivals(),
              (unsigned long long)b.driver.hotplug_departures());
}

// Two trackers of one kind on the bus: a URI with a serial number opens the one it names, also after
// the other one was there first in the list, and after a re-plug finds that one again.
TEST(UsbUmockdev, AUriWithASerialNumberOpensThatDeviceAndFindsItAgain) {
  REQUIRE_UMOCKDEV();
  sim::Script first, second;
  std::string err;
  ASSERT_TRUE(sim::parse_script("device tracker\nserial 4242\nkey 0 0 0 20 0 0 0 0\nkey 1000 1 0 20 0 0 0 0\n", first, &err)) << err;
  ASSERT_TRUE(sim::parse_script("device tracker\nserial 5151\nkey 0 0 0 20 0 0 0 0\nkey 1000 1 0 20 0 0 0 0\n", second, &err)) << err;
  sim::UsbSimDevice a(first, kTrackerPid, 5), b(second, kTrackerPid, 6);
  ASSERT_TRUE(a.ok() && b.ok()) << a.error() << b.error();
  ManualClock clock;
  std::unique_ptr<Device> d = open_device("usb:1209:7a11/5151", clock, {}, &err);
  ASSERT_NE(d, nullptr) << err;
  EXPECT_EQ(d->transport(), Transport::usb);
  EXPECT_EQ(d->uri(), "usb:1209:7a11/5151");
  auto run_ms = [&](int ms) {
    for (int i = 0; i < ms; ++i) {
      clock.advance_us(1000);
      a.step(clock.now_us());
      b.step(clock.now_us());
      d->poll(0);
    }
  };
  run_ms(300);
  ASSERT_EQ(d->session().state(), LinkState::streaming);
  EXPECT_EQ(d->session().device_info().serial, 5151u) << "the device the URI names, not the first of its kind";
  EXPECT_EQ(a.emulator().counters().host_messages, 0u) << "the other tracker was never talked to";

  b.unplug();
  run_ms(100);
  EXPECT_NE(d->session().state(), LinkState::streaming);
  run_ms(300);
  EXPECT_NE(d->session().state(), LinkState::streaming) << "with its device gone, the other tracker is not taken instead";
  EXPECT_EQ(a.emulator().counters().host_messages, 0u);
  b.plug();
  for (int i = 0; i < 600 && d->session().state() != LinkState::streaming; ++i) run_ms(1);
  EXPECT_EQ(d->session().state(), LinkState::streaming);
  EXPECT_EQ(d->session().device_info().serial, 5151u);
  EXPECT_EQ(d->session().stats().reconnects, 1u);
}

TEST(UsbUmockdev, ASimUriRunsItsEmulatorBehindAUmockdevDevice) {
  REQUIRE_UMOCKDEV();
  ManualClock clock;
  OpenOptions o;
  o.sim_script = "device pedals\nserial 2077\nrate_hz 500\nkey 0 0 0 0\nkey 400 0.5 0 0\n";
  std::string err;
  std::unique_ptr<Device> d = open_device("sim:pedals?transport=usb", clock, o, &err);
  ASSERT_NE(d, nullptr) << err;
  EXPECT_EQ(d->transport(), Transport::usb);
  ASSERT_NE(d->simulated_peer(), nullptr);
  for (int i = 0; i < 400 && d->session().stats().samples_delivered < 50; ++i) {
    clock.advance_us(1000);
    d->simulated_peer()->step(clock.now_us());
    d->poll(0);
  }
  EXPECT_GE(d->session().stats().samples_delivered, 50u);
  EXPECT_EQ(d->session().device_info().serial, 2077u);
  EXPECT_EQ(d->session().device_info().device_type, VP_DEVICE_PEDAL);
}

}  // namespace
