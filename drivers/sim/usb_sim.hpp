// A firmware emulator behind a simulated USB device: umockdev's testbed provides the sysfs entry and
// /dev/bus/usb node, and our usbdevfs ioctl handler answers libusb's URBs as the device's USB
// controller would (the approach of libusb's own umockdev tests). The process must run under
// umockdev-wrapper (LD_PRELOAD of libumockdev-preload).
#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>

#include "drivers/sim/emulator.hpp"
#include "drivers/sim/simulated_peer.hpp"

namespace vitreo::drivers::sim {

class UsbSimDevice final : public SimulatedPeer {
 public:
  // Creates the testbed if needed and adds the device at bus 1, address `address`.
  UsbSimDevice(Script s, std::uint16_t pid, int address = 2);
  ~UsbSimDevice() override;
  UsbSimDevice(const UsbSimDevice&) = delete;
  UsbSimDevice& operator=(const UsbSimDevice&) = delete;

  // False when not running under umockdev-wrapper (callers skip).
  static bool mock_environment_available();
  bool ok() const { return ok_; }
  const std::string& error() const { return error_; }

  // Advances the emulator and queues its frames as interrupt IN reports; a scripted disconnect
  // unplugs the device for its duration.
  void step(std::uint64_t now_us) override;
  // Cable pull: "remove" uevent, every URB fails with ENODEV; plug(): "add" uevent, working again.
  void unplug() override;
  void plug() override;
  FirmwareEmulator& emulator() override { return emu_; }
  std::uint64_t reports_dropped() const;
  std::uint64_t urbs_handled() const;
  std::uint64_t bytes_sent() const override;

  struct Impl;

 private:
  FirmwareEmulator emu_;
  void set_present(bool present);

  std::unique_ptr<Impl> impl_;
  bool manual_unplug_ = false, scripted_down_ = false;
  bool ok_ = false;
  std::string error_;
};

}  // namespace vitreo::drivers::sim
