#include "drivers/open_device.hpp"

#include <atomic>

#include "drivers/can.hpp"
#include "drivers/serial.hpp"
#include "drivers/sim/can_sim.hpp"
#include "drivers/sim/pty_sim.hpp"
#include "drivers/usb.hpp"
#if VITREO_HAVE_USB_SIM
#include "drivers/sim/usb_sim.hpp"
#endif

namespace vitreo::drivers {

namespace {

// A simulated device: the firmware emulator behind its transport, and the real driver for that
// transport talking to it. Everything but simulated_peer() is the driver's.
class SimulatedDevice final : public Device {
 public:
  SimulatedDevice(std::string uri, std::unique_ptr<sim::SimulatedPeer> peer, std::unique_ptr<Device> driver)
      : uri_(std::move(uri)), peer_(std::move(peer)), driver_(std::move(driver)) {}
  Transport transport() const override { return driver_->transport(); }
  std::string uri() const override { return uri_; }
  void poll(int timeout_ms) override { driver_->poll(timeout_ms); }
  DeviceSession& session() override { return driver_->session(); }
  const DeviceSession& session() const override { return driver_->session(); }
  sim::SimulatedPeer* simulated_peer() override { return peer_.get(); }

 private:
  std::string uri_;
  std::unique_ptr<sim::SimulatedPeer> peer_;  // built first: the transport exists before the driver looks
  std::unique_ptr<Device> driver_;
};

std::uint16_t usb_pid(sim::DeviceKind k) {
  switch (k) {
    case sim::DeviceKind::tracker: return kTrackerPid;
    case sim::DeviceKind::pedals: return kPedalsPid;
    case sim::DeviceKind::eyeball: return kEyeballPid;
  }
  return 0;
}

std::unique_ptr<Device> open_simulated(DeviceUri uri, Clock& clock, const OpenOptions& o, std::string* error) {
  auto fail = [&](const std::string& why) -> std::unique_ptr<Device> {
    if (error) *error = to_string(uri) + ": " + why;
    return nullptr;
  };
  sim::Script script;
  if (o.sim_script.empty()) {
    script = sim::default_script(uri.sim_kind == "tracker"  ? sim::DeviceKind::tracker
                                 : uri.sim_kind == "pedals" ? sim::DeviceKind::pedals
                                                            : sim::DeviceKind::eyeball);
  } else {
    std::string why;
    if (!sim::parse_script(o.sim_script, script, &why)) return fail("bad simulation script: " + why);
  }
  if (sim::to_string(script.kind) != uri.sim_kind) {
    return fail(std::string("the script simulates a ") + sim::to_string(script.kind) + ", the URI names a " + uri.sim_kind);
  }
  switch (uri.sim_transport) {
    case Transport::serial: {
      if (uri.path.empty()) uri.path = o.sim_link;
      if (uri.path.empty()) return fail("no link path for the pty (link=PATH)");
      std::unique_ptr<sim::PtySimDevice> peer;
      try {
        peer = std::make_unique<sim::PtySimDevice>(script, uri.path);
      } catch (const std::exception& e) {
        return fail(e.what());
      }
      auto driver = std::make_unique<SerialDevice>(uri.path, clock, o.session);
      return std::make_unique<SimulatedDevice>(to_string(uri), std::move(peer), std::move(driver));
    }
    case Transport::can: {
      auto peer = std::make_unique<sim::CanSimDevice>(script, uri.interface, static_cast<std::uint8_t>(uri.node), uri.fd);
      if (!peer->ok()) return fail("cannot open " + uri.interface + " for the emulator: " + peer->error());
      auto driver = std::make_unique<CanDevice>(uri.interface, static_cast<std::uint8_t>(uri.node), uri.fd, clock, o.session);
      return std::make_unique<SimulatedDevice>(to_string(uri), std::move(peer), std::move(driver));
    }
    case Transport::usb: {
#if VITREO_HAVE_USB_SIM
      if (!sim::UsbSimDevice::mock_environment_available()) {
        return fail("simulated USB devices need the process to run under umockdev-wrapper");
      }
      // one bus address per simulated device in this process
      static std::atomic<int> next_address{2};
      const std::uint16_t pid = usb_pid(script.kind);
      auto peer = std::make_unique<sim::UsbSimDevice>(script, pid, next_address++);
      if (!peer->ok()) return fail(peer->error());
      auto driver = std::make_unique<UsbDevice>(kVitreoUsbVid, pid, clock, o.session, std::to_string(script.serial));
      std::string why;
      if (!driver->init(&why)) return fail(why);
      return std::make_unique<SimulatedDevice>(to_string(uri), std::move(peer), std::move(driver));
#else
      (void)usb_pid;
      return fail("this build has no USB simulation (umockdev was not found when it was configured)");
#endif
    }
  }
  return fail("unknown transport");
}

}  // namespace

std::unique_ptr<Device> open_device(const DeviceUri& uri, Clock& clock, const OpenOptions& o, std::string* error) {
  switch (uri.scheme) {
    case DeviceUri::Scheme::serial: return std::make_unique<SerialDevice>(uri.path, clock, o.session, uri.baud);
    case DeviceUri::Scheme::can:
      return std::make_unique<CanDevice>(uri.interface, static_cast<std::uint8_t>(uri.node), uri.fd, clock, o.session);
    case DeviceUri::Scheme::usb: {
      auto d = std::make_unique<UsbDevice>(uri.vid, uri.pid, clock, o.session, uri.serial_number);
      std::string why;
      if (!d->init(&why)) {
        if (error) *error = to_string(uri) + ": " + why;
        return nullptr;
      }
      return d;
    }
    case DeviceUri::Scheme::sim: return open_simulated(uri, clock, o, error);
  }
  return nullptr;
}

std::unique_ptr<Device> open_device(std::string_view text, Clock& clock, const OpenOptions& o, std::string* error) {
  DeviceUri uri;
  if (!parse_device_uri(text, uri, error)) return nullptr;
  return open_device(uri, clock, o, error);
}

}  // namespace vitreo::drivers
