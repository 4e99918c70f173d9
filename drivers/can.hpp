// SocketCAN transport (raw sockets, CAN FD, kernel filters, error frames, bus-off) and the CAN
// device driver. Only Linux kernels with CAN support run it (the tests boot a small VM for that).
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "drivers/device.hpp"
#include "drivers/session.hpp"
#include "firmware-protocol/vp.hpp"

namespace vitreo::drivers {

struct CanRxFrame {
  std::uint32_t id = 0;  // without flags; 29-bit
  bool extended = false, fd = false, error = false, rtr = false;
  std::uint8_t len = 0;
  std::uint8_t data[64] = {};
};

class CanSocket {
 public:
  CanSocket() = default;
  CanSocket(const CanSocket&) = delete;
  CanSocket& operator=(const CanSocket&) = delete;
  ~CanSocket() { close(); }

  struct Filter {
    std::uint32_t id, mask;  // as struct can_filter (flags included)
  };
  // Binds a raw socket to `ifname`; fd: accept/send CAN FD frames; filters: kernel-side
  // acceptance (an empty list means "everything": CAN_RAW_FILTER with zero filters would mean
  // "nothing"); error_frames: deliver controller error frames (bus-off, error passive, ...).
  bool open(const std::string& ifname, bool fd, const std::vector<Filter>& filters, bool error_frames,
            std::string* error);
  void close();
  bool is_open() const { return fd_ >= 0; }
  int fd() const { return fd_; }
  // 1 frame read, 0 none available, -1 the interface went away.
  int read(CanRxFrame& f);
  bool write(const proto::CanFrame& f);
  std::uint64_t write_errors() const { return write_errors_; }

 private:
  int fd_ = -1;
  bool fd_frames_ = false;
  std::uint64_t write_errors_ = 0;
};

struct CanLinkStats {
  std::uint64_t error_frames = 0;
  std::uint64_t bus_off = 0;
  std::uint64_t controller_problems = 0;  // error warning/passive, rx/tx overflow
  std::uint64_t foreign_frames = 0;       // frames passing the filter that are not ours (should be 0)
};

// The driver for one device (node id) on a CAN interface. use_fd: host messages as CAN FD frames;
// the device's frames are accepted in either form.
class CanDevice final : public Device {
 public:
  CanDevice(std::string ifname, std::uint8_t node_id, bool use_fd, Clock& clock, SessionConfig cfg = {});
  Transport transport() const override { return Transport::can; }
  std::string uri() const override;
  void poll(int timeout_ms) override;
  DeviceSession& session() override { return session_; }
  const DeviceSession& session() const override { return session_; }
  const CanLinkStats& can_stats() const { return can_stats_; }
  void set_raw_tap(std::function<void(const CanRxFrame&)> f) { raw_tap_ = std::move(f); }

 private:
  void try_open(std::uint64_t now_us);
  void handle(const CanRxFrame& f, std::uint64_t now_us);

  std::string ifname_;
  std::uint8_t node_;
  bool use_fd_;
  Clock& clock_;
  CanSocket sock_;
  vp_can_rx rx_{};
  DeviceSession session_;
  CanLinkStats can_stats_;
  std::uint8_t tid_[256] = {};
  bool opened_once_ = false;
  std::function<void(const CanRxFrame&)> raw_tap_;
};

}  // namespace vitreo::drivers
