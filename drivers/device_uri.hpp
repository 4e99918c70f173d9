// Device addresses as URIs: what a rig file and the command line name, and what open_device()
// opens. One text form per transport, so a technician can read where a device is from a log line:
//
//   serial:/dev/ttyACM0[?baud=921600]          a UART or USB-CDC port (a /dev/vitreo/... or
//                                              /dev/serial/by-id/... link survives re-plugging)
//   can:can0?node=5[&fd=1]                     node 5 on SocketCAN interface can0; fd=1 sends the
//                                              host's messages as CAN FD frames (default classic)
//   usb:1209:7a11[/SERIAL]                     vendor:product in hex, optionally the serial number
//                                              string, which picks one device of several
//   sim:tracker?transport=pty|usb|can[&link=PATH][&if=vcan0][&node=N][&fd=1]
//                                              a firmware emulator (drivers/sim) behind a real
//                                              transport, talked to by the real driver
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "drivers/device.hpp"

namespace vitreo::drivers {

struct DeviceUri {
  enum class Scheme : std::uint8_t { serial, can, usb, sim };
  Scheme scheme = Scheme::serial;
  // serial (and sim over a pty: the link the emulator creates; empty = chosen by the opener)
  std::string path;
  int baud = 921600;
  // can (and sim over CAN)
  std::string interface;
  int node = 0;
  bool fd = false;
  // usb (sim over USB: vid/pid from the device kind)
  std::uint16_t vid = 0, pid = 0;
  std::string serial_number;  // empty: the first device with vid:pid
  // sim
  std::string sim_kind;                      // tracker | pedals | eyeball
  Transport sim_transport = Transport::serial;  // pty = serial

  // The transport the driver talks over (a simulated device's too).
  Transport transport() const;
};

// Parses a URI; false with a reason naming the offending part in *error.
bool parse_device_uri(std::string_view text, DeviceUri& out, std::string* error);
// The canonical text of a URI (parse_device_uri(to_string(u)) gives u back).
std::string to_string(const DeviceUri& uri);

// Default CAN node ids of the device kinds (PROTOCOL.md §5.3: trackers 1–15, pedals 16–31,
// eyeball fixtures 32–47): 5, 17, 33.
int default_can_node(std::string_view kind);

}  // namespace vitreo::drivers
