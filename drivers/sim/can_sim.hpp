// A firmware emulator on a CAN bus (vcan in tests): answers frames addressed to its node, sends
// its messages as CAN FD single frames or segmented classic frames.
#pragma once

#include "drivers/can.hpp"
#include "drivers/sim/emulator.hpp"

namespace vitreo::drivers::sim {

class CanSimDevice {
 public:
  CanSimDevice(Script s, std::string ifname, std::uint8_t node_id, bool fd);
  bool ok() const { return sock_.is_open(); }
  const std::string& error() const { return error_; }
  void step(std::uint64_t now_us);
  FirmwareEmulator& emulator() { return emu_; }
  std::uint64_t frames_written() const { return written_; }

 private:
  FirmwareEmulator emu_;
  std::uint8_t node_;
  bool fd_;
  CanSocket sock_;
  vp_can_rx rx_{};
  std::uint8_t tid_[256] = {};
  std::string error_;
  std::uint64_t written_ = 0;
};

}  // namespace vitreo::drivers::sim
