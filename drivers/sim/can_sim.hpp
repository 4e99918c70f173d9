// A firmware emulator on a CAN bus (vcan in tests): answers frames addressed to its node, sends
// its messages as CAN FD single frames or segmented classic frames. Unplugged (on demand or by a
// scripted disconnect) it falls silent, as a node whose cable is pulled: the bus stays up, the
// host's driver notices the silence (lost after its timeout) and finds the node again when it
// answers.
#pragma once

#include "drivers/can.hpp"
#include "drivers/sim/emulator.hpp"
#include "drivers/sim/simulated_peer.hpp"

namespace vitreo::drivers::sim {

class CanSimDevice final : public SimulatedPeer {
 public:
  CanSimDevice(Script s, std::string ifname, std::uint8_t node_id, bool fd);
  bool ok() const { return sock_.is_open(); }
  const std::string& error() const { return error_; }
  void step(std::uint64_t now_us) override;
  void unplug() override;
  void plug() override;
  bool plugged() const { return !manual_unplug_ && !scripted_down_; }
  FirmwareEmulator& emulator() override { return emu_; }
  std::uint64_t frames_written() const { return written_; }
  std::uint64_t bytes_sent() const override { return bytes_written_; }

 private:
  FirmwareEmulator emu_;
  std::uint8_t node_;
  bool fd_;
  CanSocket sock_;
  vp_can_rx rx_{};
  std::uint8_t tid_[256] = {};
  std::string error_;
  std::uint64_t written_ = 0;
  std::uint64_t bytes_written_ = 0;  // payload bytes of the frames written
  bool manual_unplug_ = false, scripted_down_ = false;
};

}  // namespace vitreo::drivers::sim
