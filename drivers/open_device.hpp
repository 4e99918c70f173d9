// Opening a device from its URI (drivers/device_uri.hpp): the one place that knows which driver
// serves which transport. The driver is built and returned at once; the transport itself is
// opened by its first poll() and re-opened after every loss, so a device that is not plugged in
// yet is not an error — it shows as lost/reconnecting until it appears.
#pragma once

#include <memory>
#include <string>
#include <string_view>

#include "drivers/device.hpp"
#include "drivers/device_uri.hpp"

namespace vitreo::drivers {

struct OpenOptions {
  SessionConfig session;
  // sim: the emulator's script (drivers/sim/emulator.hpp); empty: the built-in one of its kind.
  std::string sim_script;
  // sim over a pty without link=: where to create the link to the pty.
  std::string sim_link;
};

// nullptr with a reason in *error for a bad URI, a bad script, or a transport this build or this
// process cannot offer (libusb failing to start; sim over USB outside umockdev-wrapper; sim over
// CAN without a CAN interface).
std::unique_ptr<Device> open_device(const DeviceUri& uri, Clock& clock, const OpenOptions& options, std::string* error);
std::unique_ptr<Device> open_device(std::string_view uri, Clock& clock, const OpenOptions& options, std::string* error);

}  // namespace vitreo::drivers
