#include "drivers/sim/pty_sim.hpp"

#include <fcntl.h>
#include <pty.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <stdexcept>

namespace vitreo::drivers::sim {

PtySimDevice::PtySimDevice(Script s, std::string link_path) : emu_(std::move(s)), link_(std::move(link_path)) {
  open_pty();
  if (master_ < 0) throw std::runtime_error("cannot create a pty for the simulated device");
}

PtySimDevice::~PtySimDevice() { close_pty(); }

void PtySimDevice::unplug() {
  manual_unplug_ = true;
  close_pty();
}

void PtySimDevice::plug() {
  manual_unplug_ = false;
  open_pty();
}

void PtySimDevice::open_pty() {
  if (master_ >= 0) return;
  termios t{};
  cfmakeraw(&t);  // raw from birth: no echo back into the emulator, no line buffering
  t.c_cflag |= CLOCAL | CREAD;
  char name[256] = {};
  int m = -1, sl = -1;
  if (openpty(&m, &sl, name, &t, nullptr) != 0) return;
  fcntl(m, F_SETFL, fcntl(m, F_GETFL) | O_NONBLOCK);
  fcntl(m, F_SETFD, FD_CLOEXEC);
  fcntl(sl, F_SETFD, FD_CLOEXEC);
  master_ = m;
  slave_keep_ = sl;
  slave_name_ = name;
  ::unlink(link_.c_str());
  if (::symlink(slave_name_.c_str(), link_.c_str()) != 0) std::perror("symlink");
  rx_.reset();
  emu_.reset_link();  // a re-plugged device has been power-cycled
}

void PtySimDevice::close_pty() {
  if (master_ < 0) return;
  ::unlink(link_.c_str());
  ::close(slave_keep_);
  ::close(master_);
  master_ = slave_keep_ = -1;
}

void PtySimDevice::step(std::uint64_t now_us) {
  const bool scripted_down = emu_.disconnected(now_us);
  if (scripted_down && master_ >= 0) close_pty();
  if (!scripted_down && master_ < 0 && !manual_unplug_) open_pty();
  if (master_ < 0) {
    std::vector<proto::Bytes> discard;
    emu_.step(now_us, discard);  // time goes on for an unplugged device
    return;
  }
  std::uint8_t buf[1024];
  for (;;) {
    ssize_t n = ::read(master_, buf, sizeof buf);
    if (n <= 0) break;
    rx_.feed(std::span<const std::uint8_t>(buf, static_cast<std::size_t>(n)), [&](int st, const vp_message& m) {
      if (st == VP_OK) emu_.on_host_message(m, now_us);
    });
  }
  std::vector<proto::Bytes> packets;
  emu_.step(now_us, packets);
  for (auto& p : packets) {
    proto::Bytes f = proto::frame_serial(p);
    emu_.corrupt(f);
    ssize_t n = ::write(master_, f.data(), f.size());
    if (n > 0) bytes_written_ += static_cast<std::uint64_t>(n);
    if (n != static_cast<ssize_t>(f.size())) ++tx_overflows_;  // UART FIFO overflow: frame lost
  }
}

}  // namespace vitreo::drivers::sim
