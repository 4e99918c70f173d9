#include "drivers/serial.hpp"

#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace vitreo::drivers {
namespace {
speed_t to_speed(int baud) {
  switch (baud) {
    case 9600: return B9600;
    case 19200: return B19200;
    case 38400: return B38400;
    case 57600: return B57600;
    case 115200: return B115200;
    case 230400: return B230400;
    case 460800: return B460800;
    case 921600: return B921600;
    case 1000000: return B1000000;
    case 2000000: return B2000000;
    case 3000000: return B3000000;
    default: return B0;
  }
}
}  // namespace

SerialPort& SerialPort::operator=(SerialPort&& o) noexcept {
  if (this != &o) {
    close();
    fd_ = o.fd_;
    o.fd_ = -1;
  }
  return *this;
}

bool SerialPort::open(const std::string& path, int baud, std::string* error) {
  close();
  const speed_t speed = to_speed(baud);
  if (speed == B0) {
    if (error) *error = "unsupported baud rate " + std::to_string(baud);
    return false;
  }
  int fd = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    if (error) *error = path + ": " + std::strerror(errno);
    return false;
  }
  termios t{};
  if (tcgetattr(fd, &t) != 0) {
    if (error) *error = path + ": not a serial port (" + std::strerror(errno) + ")";
    ::close(fd);
    return false;
  }
  cfmakeraw(&t);
  t.c_cflag |= CLOCAL | CREAD;
  t.c_cflag &= ~static_cast<tcflag_t>(CRTSCTS | CSTOPB);
  t.c_iflag &= ~static_cast<tcflag_t>(IXON | IXOFF | IXANY);
  t.c_cc[VMIN] = 0;  // non-blocking reads; poll() does the waiting
  t.c_cc[VTIME] = 0;
  cfsetispeed(&t, speed);
  cfsetospeed(&t, speed);
  if (tcsetattr(fd, TCSANOW, &t) != 0) {
    if (error) *error = path + ": tcsetattr: " + std::strerror(errno);
    ::close(fd);
    return false;
  }
  tcflush(fd, TCIOFLUSH);  // bytes from before we opened belong to nobody's frame
  fd_ = fd;
  return true;
}

void SerialPort::close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

long SerialPort::read_some(std::uint8_t* buf, std::size_t cap) {
  if (fd_ < 0) return -1;
  for (;;) {
    ssize_t n = ::read(fd_, buf, cap);
    if (n > 0) return n;
    // 0 is "no data" for a raw tty with VMIN=VTIME=0 (n_tty returns before checking O_NONBLOCK);
    // a hang-up shows as POLLHUP and EIO instead
    if (n == 0) return 0;
    if (errno == EINTR) continue;
    if (errno == EAGAIN || errno == EWOULDBLOCK) return 0;
    return -1;  // EIO after a hang-up, ENXIO, ...
  }
}

bool SerialPort::write_frame(std::span<const std::uint8_t> bytes) {
  if (fd_ < 0) return false;
  std::size_t off = 0;
  int spins = 0;
  while (off < bytes.size()) {
    ssize_t n = ::write(fd_, bytes.data() + off, bytes.size() - off);
    if (n > 0) {
      off += static_cast<std::size_t>(n);
    } else if (n < 0 && errno == EINTR) {
      continue;
    } else if (n < 0 && errno == EAGAIN && off > 0 && spins++ < 1000) {
      pollfd p{fd_, POLLOUT, 0};
      ::poll(&p, 1, 1);  // finish a started frame rather than leave half of it
    } else {
      return false;
    }
  }
  return true;
}

SerialDevice::SerialDevice(std::string path, Clock& clock, SessionConfig cfg, int baud)
    : path_(std::move(path)), clock_(clock), baud_(baud), session_(cfg) {
  session_.set_send([this](const vp_message& m) {
    auto f = proto::encode_serial(m);
    if (!f.empty()) port_.write_frame(f);
  });
}

std::string SerialDevice::uri() const {
  return "serial:" + path_ + (baud_ != 921600 ? "?baud=" + std::to_string(baud_) : "");
}

void SerialDevice::try_open(std::uint64_t now_us) {
  std::string err;
  if (opened_once_) session_.reconnect_attempt(now_us);
  if (port_.open(path_, baud_, &err)) {
    opened_once_ = true;
    decoder_.reset();
    session_.transport_up(now_us);
  } else if (!opened_once_) {
    // first attempt failed: behave like a later loss, so the retry cadence is the same
    opened_once_ = true;
    session_.transport_down(now_us, "cannot open port");
  }
}

void SerialDevice::poll(int timeout_ms) {
  std::uint64_t now = clock_.now_us();
  if (!port_.is_open()) {
    if (!opened_once_ || now >= session_.next_reconnect_us()) try_open(now);
    if (!port_.is_open()) return;
  }
  pollfd p{port_.fd(), POLLIN, 0};
  int r = ::poll(&p, 1, timeout_ms);
  now = clock_.now_us();
  if (r > 0) {
    std::uint8_t buf[4096];
    for (;;) {
      long n = port_.read_some(buf, sizeof buf);
      if (n == 0 && (p.revents & (POLLHUP | POLLERR | POLLNVAL))) n = -1;
      if (n == 0) break;
      if (n < 0) {
        port_.close();
        session_.transport_down(now, "port hung up");
        return;
      }
      std::span<const std::uint8_t> chunk(buf, static_cast<std::size_t>(n));
      if (raw_tap_) raw_tap_(chunk);
      session_.on_bytes(chunk.size());
      decoder_.feed(chunk, [&](int st, const vp_message& m) { session_.on_frame(st, m, now); });
    }
  }
  if (session_.tick(now)) port_.close();
}

}  // namespace vitreo::drivers
