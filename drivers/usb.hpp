// USB transport (libusb-1.0, asynchronous transfers, hotplug) and the USB device driver.
// Device → host: interrupt IN 0x81, one VP packet + CRC per transfer. Host → device: bulk OUT 0x02.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "drivers/session.hpp"

struct libusb_context;
struct libusb_device_handle;
struct libusb_transfer;
struct libusb_device;

namespace vitreo::drivers {

inline constexpr std::uint16_t kVitreoUsbVid = 0x1209;  // pid.codes open-source VID (development)
inline constexpr std::uint16_t kTrackerPid = 0x7A11, kPedalsPid = 0x7A12, kEyeballPid = 0x7A13;

struct UsbDeviceEntry {
  std::uint16_t vid = 0, pid = 0;
  int bus = 0, address = 0;
  std::string product, serial;
};
// Lists vitreo devices (our VID) currently present; false with a reason on libusb failure.
bool list_usb_devices(std::vector<UsbDeviceEntry>& out, std::string* error);

class UsbDevice {
 public:
  UsbDevice(std::uint16_t vid, std::uint16_t pid, Clock& clock, SessionConfig cfg = {});
  ~UsbDevice();
  UsbDevice(const UsbDevice&) = delete;
  UsbDevice& operator=(const UsbDevice&) = delete;

  // libusb context and hotplug registration; false with a reason.
  bool init(std::string* error);
  // Handles USB events for up to timeout_ms, runs timeouts, reopens after a loss.
  void poll(int timeout_ms);
  DeviceSession& session() { return session_; }
  const DeviceSession& session() const { return session_; }
  void set_raw_tap(std::function<void(std::span<const std::uint8_t>)> f) { raw_tap_ = std::move(f); }
  std::uint64_t hotplug_arrivals() const { return arrivals_; }
  std::uint64_t hotplug_departures() const { return departures_; }

 private:
  static void on_in(libusb_transfer* t);
  static void on_out(libusb_transfer* t);
  static int on_hotplug(libusb_context*, libusb_device*, int event, void* self);
  bool try_open(std::uint64_t now_us);
  void close_handle();
  void send(const vp_message& m);

  std::uint16_t vid_, pid_;
  Clock& clock_;
  DeviceSession session_;
  libusb_context* ctx_ = nullptr;
  libusb_device_handle* h_ = nullptr;
  std::vector<libusb_transfer*> in_;
  int hotplug_handle_ = 0;
  bool hotplug_ = false;
  int outstanding_ = 0;
  bool gone_ = false;        // a transfer reported the device gone: close at the next poll
  bool arrived_ = false;     // hotplug says a matching device appeared: try at once
  bool opened_once_ = false;
  std::uint64_t arrivals_ = 0, departures_ = 0;
  std::function<void(std::span<const std::uint8_t>)> raw_tap_;
};

}  // namespace vitreo::drivers
