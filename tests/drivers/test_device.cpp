// drivers::Device and open_device(): device URIs (parse, canonical text, refusals), one interface
// over every transport (here serial, over a real pty, and a simulated device opened from a sim: URI),
// and the identity a rig expects at an address (another kind or serial is not configured).
// USB through open_device is tested under umockdev (test_usb_umockdev.cpp), CAN in the VM.
#include <gtest/gtest.h>

#include <unistd.h>

#include <string>

#include "drivers/device_uri.hpp"
#include "drivers/open_device.hpp"
#include "drivers/sim/emulator.hpp"
#include "drivers/sim/pty_sim.hpp"
#include "drivers/sim/simulated_peer.hpp"

namespace {

using namespace vitreo::drivers;

DeviceUri parsed(const std::string& text) {
  DeviceUri u;
  std::string err;
  EXPECT_TRUE(parse_device_uri(text, u, &err)) << text << ": " << err;
  return u;
}

std::string refusal(const std::string& text) {
  DeviceUri u;
  std::string err;
  EXPECT_FALSE(parse_device_uri(text, u, &err)) << text << " was accepted";
  return err;
}

TEST(DeviceUri, EachSchemeParsesToItsFields) {
  const DeviceUri s = parsed("serial:/dev/ttyACM0");
  EXPECT_EQ(s.scheme, DeviceUri::Scheme::serial);
  EXPECT_EQ(s.path, "/dev/ttyACM0");
  EXPECT_EQ(s.baud, 921600);
  EXPECT_EQ(parsed("serial:/dev/vitreo/pedals?baud=115200").baud, 115200);

  const DeviceUri c = parsed("can:can0?node=5");
  EXPECT_EQ(c.scheme, DeviceUri::Scheme::can);
  EXPECT_EQ(c.interface, "can0");
  EXPECT_EQ(c.node, 5);
  EXPECT_FALSE(c.fd);
  EXPECT_TRUE(parsed("can:can1?node=33&fd=1").fd);

  const DeviceUri u = parsed("usb:1209:7a11");
  EXPECT_EQ(u.scheme, DeviceUri::Scheme::usb);
  EXPECT_EQ(u.vid, 0x1209);
  EXPECT_EQ(u.pid, 0x7a11);
  EXPECT_TRUE(u.serial_number.empty());
  EXPECT_EQ(parsed("usb:1209:7A12/2001").serial_number, "2001");
  EXPECT_EQ(parsed("usb:1209:7A12/2001").pid, 0x7a12);

  const DeviceUri p = parsed("sim:tracker?transport=pty");
  EXPECT_EQ(p.scheme, DeviceUri::Scheme::sim);
  EXPECT_EQ(p.sim_kind, "tracker");
  EXPECT_EQ(p.transport(), Transport::serial);
  EXPECT_EQ(parsed("sim:pedals?transport=usb").transport(), Transport::usb);
  const DeviceUri e = parsed("sim:eyeball?transport=can");
  EXPECT_EQ(e.transport(), Transport::can);
  EXPECT_EQ(e.interface, "vcan0");
  EXPECT_EQ(e.node, 33) << "eyeball fixtures take nodes 32–47 (PROTOCOL.md §5.3)";
  EXPECT_EQ(parsed("sim:tracker?transport=can").node, 5);
  EXPECT_EQ(parsed("sim:pedals?transport=can").node, 17);
}

TEST(DeviceUri, CanonicalTextParsesBackToTheSameUri) {
  for (const char* text : {"serial:/dev/ttyACM0", "serial:/dev/ttyUSB1?baud=460800", "can:can0?node=5",
                           "can:vcan0?node=33&fd=1", "usb:1209:7a11", "usb:1209:7a13/3001", "sim:tracker?transport=pty",
                           "sim:tracker?transport=pty&link=/tmp/x", "sim:pedals?transport=usb",
                           "sim:eyeball?transport=can&if=vcan0&node=40&fd=1"}) {
    const std::string canonical = to_string(parsed(text));
    EXPECT_EQ(canonical, text) << "already canonical";
    EXPECT_EQ(to_string(parsed(canonical)), canonical);
  }
  EXPECT_EQ(to_string(parsed("usb:1209:7A11")), "usb:1209:7a11") << "ids in lower-case hex";
  EXPECT_EQ(to_string(parsed("sim:eyeball?transport=can")), "sim:eyeball?transport=can&if=vcan0&node=33");
}

TEST(DeviceUri, BadUrisAreRefusedWithTheReason) {
  EXPECT_NE(refusal("/dev/ttyACM0").find("no scheme"), std::string::npos);
  EXPECT_NE(refusal("i2c:1").find("unknown scheme"), std::string::npos);
  EXPECT_NE(refusal("serial:").find("no device path"), std::string::npos);
  EXPECT_NE(refusal("serial:/dev/x?baud=12").find("baud"), std::string::npos);
  EXPECT_NE(refusal("serial:/dev/x?speed=9600").find("unknown parameter 'speed'"), std::string::npos);
  EXPECT_NE(refusal("can:can0").find("no node id"), std::string::npos);
  EXPECT_NE(refusal("can:can0?node=0").find("node=0"), std::string::npos);
  EXPECT_NE(refusal("can:can0?node=128").find("node=128"), std::string::npos);
  EXPECT_NE(refusal("can:can0?node=5&node=6").find("given twice"), std::string::npos);
  EXPECT_NE(refusal("can:can0?node").find("not key=value"), std::string::npos);
  EXPECT_NE(refusal("usb:1209").find("usb:VVVV:PPPP"), std::string::npos);
  EXPECT_NE(refusal("usb:12g9:7a11").find("usb:VVVV:PPPP"), std::string::npos);
  EXPECT_NE(refusal("usb:1209:7a11/").find("empty serial"), std::string::npos);
  EXPECT_NE(refusal("sim:camera?transport=pty").find("tracker, pedals or eyeball"), std::string::npos);
  EXPECT_NE(refusal("sim:tracker?transport=i2c").find("pty, usb or can"), std::string::npos);
  EXPECT_NE(refusal("sim:tracker?transport=usb&node=3").find("transport=can"), std::string::npos);
  EXPECT_NE(refusal("sim:tracker?transport=can&link=/tmp/x").find("transport=pty"), std::string::npos);
}

std::string temp_link(const std::string& name) {
  return "/tmp/vitreo-device-test-" + std::to_string(::getpid()) + "-" + name;
}

// Steps the emulator and polls the driver in lock-step with a manual clock until the link streams.
bool streams_within(Device& d, sim::SimulatedPeer& peer, ManualClock& clock, int ms) {
  for (int i = 0; i < ms; ++i) {
    clock.advance_us(1000);
    peer.step(clock.now_us());
    for (int k = 0; k < 5; ++k) d.poll(k == 0 ? 0 : 1);
    if (d.session().state() == LinkState::streaming && d.session().stats().samples_delivered > 20) return true;
  }
  return false;
}

TEST(OpenDevice, ASerialUriOpensTheSerialDriverOnThatPath) {
  ManualClock clock;
  const std::string link = temp_link("serial");
  sim::PtySimDevice peer(sim::default_script(sim::DeviceKind::pedals), link);
  std::string err;
  std::unique_ptr<Device> d = open_device("serial:" + link, clock, {}, &err);
  ASSERT_NE(d, nullptr) << err;
  EXPECT_EQ(d->transport(), Transport::serial);
  EXPECT_EQ(d->uri(), "serial:" + link);
  EXPECT_EQ(d->simulated_peer(), nullptr) << "a real device has no emulator behind it";
  EXPECT_TRUE(streams_within(*d, peer, clock, 500)) << to_string(d->session().state());
  EXPECT_EQ(d->session().device_info().device_type, VP_DEVICE_PEDAL);
}

TEST(OpenDevice, ASimUriBringsItsEmulatorAndTheRealDriver) {
  ManualClock clock;
  OpenOptions o;
  o.sim_script = "device eyeball\nrate_hz 250\nserial 3007\nkey 0 0 0 0 0 0\nkey 1000 5 0 0 0 0\n";
  std::string err;
  std::unique_ptr<Device> d = open_device("sim:eyeball?transport=pty&link=" + temp_link("sim"), clock, o, &err);
  ASSERT_NE(d, nullptr) << err;
  EXPECT_EQ(d->transport(), Transport::serial) << "the emulator sits behind a pty; the serial driver reads it";
  ASSERT_NE(d->simulated_peer(), nullptr);
  EXPECT_TRUE(streams_within(*d, *d->simulated_peer(), clock, 500)) << to_string(d->session().state());
  EXPECT_EQ(d->session().device_info().serial, 3007u) << "the device behind the link is the scripted one";

  // a pulled cable: lost at once (hang-up), found again at the same URI after the re-plug
  d->simulated_peer()->unplug();
  for (int i = 0; i < 20; ++i) {
    clock.advance_us(1000);
    d->simulated_peer()->step(clock.now_us());
    d->poll(1);
  }
  EXPECT_TRUE(d->session().state() == LinkState::lost || d->session().state() == LinkState::reconnecting);
  d->simulated_peer()->plug();
  const auto before = d->session().stats().samples_delivered;
  EXPECT_TRUE(streams_within(*d, *d->simulated_peer(), clock, 1000));
  EXPECT_GT(d->session().stats().samples_delivered, before);
  EXPECT_EQ(d->session().stats().reconnects, 1u);
}

TEST(OpenDevice, RefusesWhatItCannotOpenWithAReason) {
  ManualClock clock;
  std::string err;
  EXPECT_EQ(open_device("serial", clock, {}, &err), nullptr);
  EXPECT_NE(err.find("no scheme"), std::string::npos) << err;
  OpenOptions o;
  o.sim_script = "device pedals\nkey 0 0 0 0\n";
  EXPECT_EQ(open_device("sim:tracker?transport=pty&link=" + temp_link("x"), clock, o, &err), nullptr);
  EXPECT_NE(err.find("the script simulates a pedals"), std::string::npos) << err;
  o.sim_script = "device tracker\nbogus 1\n";
  EXPECT_EQ(open_device("sim:tracker?transport=pty&link=" + temp_link("y"), clock, o, &err), nullptr);
  EXPECT_NE(err.find("bad simulation script"), std::string::npos) << err;
  EXPECT_EQ(open_device("sim:tracker?transport=pty", clock, {}, &err), nullptr);
  EXPECT_NE(err.find("no link path"), std::string::npos) << err;
}

TEST(OpenDevice, ADeviceOfAnotherKindOrSerialIsNotConfigured) {
  ManualClock clock;
  const std::string link = temp_link("identity");
  sim::PtySimDevice peer(sim::default_script(sim::DeviceKind::pedals), link);  // the pedals, serial 2001 or so
  OpenOptions o;
  o.session.expected_device_type = VP_DEVICE_TRACKER;  // the rig expects the tracker here
  std::string err;
  std::unique_ptr<Device> d = open_device("serial:" + link, clock, o, &err);
  ASSERT_NE(d, nullptr) << err;
  EXPECT_FALSE(streams_within(*d, peer, clock, 300)) << "the pedals must not drive the tracker's instrument";
  EXPECT_GT(d->session().stats().identity_rejected, 0u);
  EXPECT_EQ(d->session().stats().samples_delivered, 0u);
  EXPECT_NE(d->session().last_error().find("expected type 1"), std::string::npos) << d->session().last_error();

  // the right kind but another unit than the rig file names
  const std::uint32_t serial = peer.emulator().script().serial;
  o.session.expected_device_type = VP_DEVICE_PEDAL;
  o.session.expected_serial = serial + 1;
  std::unique_ptr<Device> other = open_device("serial:" + link, clock, o, &err);
  d.reset();
  EXPECT_FALSE(streams_within(*other, peer, clock, 300));
  EXPECT_GT(other->session().stats().identity_rejected, 0u);
  // and the one it names
  o.session.expected_serial = serial;
  std::unique_ptr<Device> named = open_device("serial:" + link, clock, o, &err);
  other.reset();
  EXPECT_TRUE(streams_within(*named, peer, clock, 500));
  EXPECT_EQ(named->session().stats().identity_rejected, 0u);
}

}  // namespace
