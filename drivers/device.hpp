// One interface for a device on any transport: the rig holds "a device", never "a serial device".
//
// The idea is ArduPilot's AP_HAL::Device (libraries/AP_HAL/Device.h): every bus driver, the
// simulated ones included, answers the same calls, so the code above it never asks which bus it
// talks to. Here a Device is a transport plus the link state machine every transport shares
// (DeviceSession): poll() moves bytes and runs the session's timeouts, session() gives the state,
// the counters and the samples. Serial, CAN and USB drivers implement it; a simulated device
// (drivers/sim/simulated_device.hpp) is one of those real drivers talking to a firmware emulator
// behind a real transport (a pty, a umockdev USB device, a CAN socket), so the same interface
// covers it too. Devices are opened from a URI (drivers/device_uri.hpp, drivers/open_device.hpp).
#pragma once

#include <string>

#include "drivers/session.hpp"

namespace vitreo::drivers {

enum class Transport : std::uint8_t { serial, can, usb };
const char* to_string(Transport t);

namespace sim {
class SimulatedPeer;
}

class Device {
 public:
  virtual ~Device() = default;
  Device() = default;
  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;

  virtual Transport transport() const = 0;
  // Where the device is, as a URI open_device() accepts (serial:/dev/ttyACM0, can:can0?node=5,
  // usb:1209:7a11/4242, sim:tracker?transport=usb).
  virtual std::string uri() const = 0;
  // Waits up to timeout_ms for input (0: do not wait), hands everything that arrived to the
  // session, runs its timeouts and, while the link is lost, the reconnection attempts: a device
  // unplugged and plugged back is found again at the same URI and resumes.
  virtual void poll(int timeout_ms) = 0;
  virtual DeviceSession& session() = 0;
  virtual const DeviceSession& session() const = 0;
  // The firmware emulator on the other side of the transport, for simulated devices (it runs on
  // its own thread, like a device's own firmware); nullptr for real devices.
  virtual sim::SimulatedPeer* simulated_peer() { return nullptr; }
};

}  // namespace vitreo::drivers
