// USB transport (libusb-1.0, asynchronous transfers, hotplug) and the USB device driver.
// Device → host: interrupt IN 0x81, one VP packet + CRC per transfer. Host → device: bulk OUT 0x02.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "drivers/device.hpp"
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

// The driver for one device, found by vendor and product id and, when given, its serial number
// string (descriptor 3): after a re-plug the device is looked up again by those, so it is found
// whatever bus address it comes back at, and a second device of the same kind is never taken for it.
class UsbDevice final : public Device {
 public:
  UsbDevice(std::uint16_t vid, std::uint16_t pid, Clock& clock, SessionConfig cfg = {}, std::string serial_number = {});
  ~UsbDevice() override;

  // libusb context and hotplug registration; false with a reason.
  bool init(std::string* error);
  Transport transport() const override { return Transport::usb; }
  std::string uri() const override;
  // Handles USB events for up to timeout_ms, runs timeouts, reopens after a loss.
  void poll(int timeout_ms) override;
  DeviceSession& session() override { return session_; }
  const DeviceSession& session() const override { return session_; }
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

  libusb_device_handle* open_matching();

  std::uint16_t vid_, pid_;
  std::string serial_number_;
  Clock& clock_;
  DeviceSession session_;
  libusb_context* ctx_ = nullptr;
  libusb_device_handle* h_ = nullptr;
  std::vector<libusb_transfer*> in_;
  int hotplug_handle_ = 0;
  bool hotplug_ = false;
  int outstanding_ = 0;
  bool gone_ = false;        // a transfer reported the device gone: close at the next poll
  bool closing_ = false;     // close_handle() is cancelling: callbacks do not resubmit
  bool arrived_ = false;     // hotplug says a matching device appeared: try at once
  bool opened_once_ = false;
  std::uint64_t arrivals_ = 0, departures_ = 0;
  std::function<void(std::span<const std::uint8_t>)> raw_tap_;
};

}  // namespace vitreo::drivers
