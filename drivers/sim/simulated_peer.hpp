// The device side of a simulated link: a firmware emulator behind a real transport (a pty, a
// umockdev USB device, a CAN socket). It runs on its own thread, as a device's firmware runs on the
// device, and the host's real driver talks to it through the transport alone (the SITL idea:
// simulation implements the same bus the real device sits on, nothing above the bus changes).
#pragma once

#include <cstdint>

namespace vitreo::drivers::sim {

class FirmwareEmulator;

class SimulatedPeer {
 public:
  virtual ~SimulatedPeer() = default;
  // Reads what the host sent, answers it, sends the frames due by now_us (host clock); follows the
  // script's disconnect faults (the transport goes away for their duration, then comes back).
  virtual void step(std::uint64_t now_us) = 0;
  // A cable pull and its re-plug, on demand (tests, demonstrations); a re-plugged device has been
  // power-cycled: it waits to be identified and configured again.
  virtual void unplug() = 0;
  virtual void plug() = 0;
  virtual FirmwareEmulator& emulator() = 0;
  // Bytes handed to the host side of the transport so far, in the unit the host's driver counts
  // them (LinkStats::bytes: serial bytes, CAN frame payloads, USB report bytes). A lockstep session
  // (rig/session/device_hub.hpp) waits until the driver has counted as many: then every sample the
  // emulator made for the step has arrived, however the kernel delayed it.
  virtual std::uint64_t bytes_sent() const = 0;
};

}  // namespace vitreo::drivers::sim
