// A firmware emulator behind a pseudo-terminal: the driver opens a path (a symlink standing in for
// /dev/serial/by-id/...) exactly as it would open a USB-serial adapter. A scripted disconnect
// closes the pty (the driver sees a hang-up, as on a cable pull) and later re-creates it behind
// the same path.
#pragma once

#include <string>

#include "drivers/sim/emulator.hpp"
#include "drivers/sim/simulated_peer.hpp"

namespace vitreo::drivers::sim {

class PtySimDevice final : public SimulatedPeer {
 public:
  // link_path: where the symlink to the pty slave is created (replaced if present).
  PtySimDevice(Script s, std::string link_path);
  ~PtySimDevice() override;
  PtySimDevice(const PtySimDevice&) = delete;
  PtySimDevice& operator=(const PtySimDevice&) = delete;

  // Reads host commands, writes due frames (with byte corruption), handles scripted disconnects.
  void step(std::uint64_t now_us) override;
  // Disconnect/reconnect on demand (the test's cable pull), independent of the script.
  void unplug() override;
  void plug() override;
  bool plugged() const { return master_ >= 0; }
  const std::string& link_path() const { return link_; }
  const std::string& slave_path() const { return slave_name_; }
  FirmwareEmulator& emulator() override { return emu_; }
  std::uint64_t tx_overflows() const { return tx_overflows_; }
  std::uint64_t bytes_written() const { return bytes_written_; }
  std::uint64_t bytes_sent() const override { return bytes_written_; }

 private:
  void open_pty();
  void close_pty();

  FirmwareEmulator emu_;
  std::string link_;
  std::string slave_name_;
  int master_ = -1;
  int slave_keep_ = -1;  // keeps the slave's raw settings alive while no driver has it open
  bool manual_unplug_ = false;
  std::uint64_t tx_overflows_ = 0;
  std::uint64_t bytes_written_ = 0;
  proto::SerialDecoder rx_;
};

}  // namespace vitreo::drivers::sim
