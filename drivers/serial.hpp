// Serial transport (termios, raw, non-blocking) and the serial device driver built on it.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>

#include "drivers/device.hpp"
#include "drivers/session.hpp"
#include "firmware-protocol/vp.hpp"

namespace vitreo::drivers {

// A serial port configured like a bare UART: raw bytes, no echo, no line editing, no flow control.
class SerialPort {
 public:
  SerialPort() = default;
  SerialPort(const SerialPort&) = delete;
  SerialPort& operator=(const SerialPort&) = delete;
  SerialPort(SerialPort&& o) noexcept : fd_(o.fd_) { o.fd_ = -1; }
  SerialPort& operator=(SerialPort&& o) noexcept;
  ~SerialPort() { close(); }

  // Opens and configures; false with a reason in *error.
  bool open(const std::string& path, int baud, std::string* error);
  void close();
  bool is_open() const { return fd_ >= 0; }
  int fd() const { return fd_; }
  // >0 bytes read; 0 nothing available; -1 the port went away (hang-up, EIO: cable pulled).
  long read_some(std::uint8_t* buf, std::size_t cap);
  // Whole frame or nothing: a UART driver that wrote half a frame would corrupt the next one.
  bool write_frame(std::span<const std::uint8_t> bytes);

 private:
  int fd_ = -1;
};

// Device driver over a serial port: frames → session; reopens the same path after a loss (a
// /dev/serial/by-id link survives re-plugging, so the path is the device's identity).
class SerialDevice final : public Device {
 public:
  SerialDevice(std::string path, Clock& clock, SessionConfig cfg = {}, int baud = 921600);
  Transport transport() const override { return Transport::serial; }
  std::string uri() const override;
  // Waits up to timeout_ms for input (0: do not wait), handles everything available, runs the
  // session's timeouts and, when lost, the reconnection attempts.
  void poll(int timeout_ms) override;
  DeviceSession& session() override { return session_; }
  const DeviceSession& session() const override { return session_; }
  const std::string& path() const { return path_; }
  // Called with every chunk of raw bytes read (the tool's raw dump).
  void set_raw_tap(std::function<void(std::span<const std::uint8_t>)> f) { raw_tap_ = std::move(f); }

 private:
  void try_open(std::uint64_t now_us);

  std::string path_;
  Clock& clock_;
  int baud_;
  SerialPort port_;
  proto::SerialDecoder decoder_;
  DeviceSession session_;
  std::function<void(std::span<const std::uint8_t>)> raw_tap_;
  bool opened_once_ = false;
};

}  // namespace vitreo::drivers
