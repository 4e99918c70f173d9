#include "drivers/can.hpp"

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace vitreo::drivers {

bool CanSocket::open(const std::string& ifname, bool fd, const std::vector<Filter>& filters, bool error_frames,
                     std::string* error) {
  close();
  auto fail = [&](const std::string& what) {
    if (error) *error = ifname + ": " + what + ": " + std::strerror(errno);
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
    return false;
  };
  fd_ = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd_ < 0) return fail("socket(PF_CAN) (no CAN support in this kernel?)");
  const unsigned idx = if_nametoindex(ifname.c_str());
  if (idx == 0) return fail("no such interface");
  if (fd) {
    int on = 1;
    if (setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof on) != 0) return fail("CAN FD not supported");
  }
  if (!filters.empty()) {
    std::vector<can_filter> f;
    for (auto& x : filters) f.push_back(can_filter{x.id, x.mask});
    if (setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_FILTER, f.data(), static_cast<socklen_t>(f.size() * sizeof(can_filter))) != 0)
      return fail("CAN_RAW_FILTER");
  }
  if (error_frames) {
    can_err_mask_t m = CAN_ERR_MASK;
    if (setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &m, sizeof m) != 0) return fail("CAN_RAW_ERR_FILTER");
  }
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(idx);
  if (::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) return fail("bind");
  fd_frames_ = fd;
  return true;
}

void CanSocket::close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

int CanSocket::read(CanRxFrame& f) {
  if (fd_ < 0) return -1;
  canfd_frame fr{};
  for (;;) {
    ssize_t n = ::read(fd_, &fr, sizeof fr);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return (errno == EAGAIN || errno == EWOULDBLOCK) ? 0 : -1;  // ENETDOWN, ENODEV: gone
    if (n != CAN_MTU && n != CANFD_MTU) return 0;                          // not a frame: ignore
    f.fd = n == CANFD_MTU;
    f.error = fr.can_id & CAN_ERR_FLAG;
    f.extended = fr.can_id & CAN_EFF_FLAG;
    f.rtr = fr.can_id & CAN_RTR_FLAG;
    f.id = fr.can_id & (f.error ? CAN_ERR_MASK : f.extended ? CAN_EFF_MASK : CAN_SFF_MASK);
    f.len = fr.len > (f.fd ? 64 : 8) ? static_cast<std::uint8_t>(f.fd ? 64 : 8) : fr.len;
    std::memcpy(f.data, fr.data, f.len);
    return 1;
  }
}

bool CanSocket::write(const proto::CanFrame& f) {
  if (fd_ < 0 || (f.fd && !fd_frames_) || f.data.size() > (f.fd ? 64u : 8u)) return false;
  canfd_frame fr{};
  fr.can_id = f.id | CAN_EFF_FLAG;
  fr.len = static_cast<std::uint8_t>(f.data.size());
  std::memcpy(fr.data, f.data.data(), f.data.size());
  const std::size_t size = f.fd ? CANFD_MTU : CAN_MTU;
  if (::write(fd_, &fr, size) != static_cast<ssize_t>(size)) {
    ++write_errors_;  // ENOBUFS when the TX queue is full: the frame is lost, as on the bus
    return false;
  }
  return true;
}

CanDevice::CanDevice(std::string ifname, std::uint8_t node_id, bool use_fd, Clock& clock, SessionConfig cfg)
    : ifname_(std::move(ifname)), node_(node_id & 0x7F), use_fd_(use_fd), clock_(clock), session_(cfg) {
  vp_can_rx_init(&rx_);
  session_.set_send([this](const vp_message& m) {
    if (use_fd_) {
      if (auto f = proto::encode_canfd(m, node_)) {
        f->id |= VP_CAN_ID_TO_DEVICE;
        sock_.write(*f);
      }
    } else {
      for (auto& f : proto::encode_can_classic(m, node_, tid_[m.type]++)) {
        f.id |= VP_CAN_ID_TO_DEVICE;
        sock_.write(f);
      }
    }
  });
}

std::string CanDevice::uri() const {
  return "can:" + ifname_ + "?node=" + std::to_string(node_) + (use_fd_ ? "&fd=1" : "");
}

void CanDevice::try_open(std::uint64_t now_us) {
  if (opened_once_) session_.reconnect_attempt(now_us);
  opened_once_ = true;
  // kernel-side filter: extended frames from our node, device → host direction
  const std::vector<CanSocket::Filter> filters{
      {CAN_EFF_FLAG | node_, CAN_EFF_FLAG | CAN_RTR_FLAG | static_cast<std::uint32_t>(VP_CAN_ID_TO_DEVICE) | 0x7Fu}};
  std::string err;
  if (sock_.open(ifname_, use_fd_, filters, true, &err)) {
    vp_can_rx_init(&rx_);
    session_.transport_up(now_us);
  } else {
    session_.transport_down(now_us, "cannot open CAN interface");
  }
}

void CanDevice::handle(const CanRxFrame& f, std::uint64_t now_us) {
  if (raw_tap_) raw_tap_(f);
  if (f.error) {
    ++can_stats_.error_frames;
    if (f.id & CAN_ERR_BUSOFF) {
      // the controller left the bus: nothing we send or receive gets through until it restarts
      ++can_stats_.bus_off;
      sock_.close();
      session_.transport_down(now_us, "CAN bus-off");
    } else if (f.id & (CAN_ERR_CRTL | CAN_ERR_PROT)) {
      ++can_stats_.controller_problems;
    }
    return;
  }
  if (!f.extended || f.rtr) {
    ++can_stats_.foreign_frames;
    return;
  }
  session_.on_bytes(f.len);
  vp_message m{};
  std::uint8_t node = 0;
  int st = f.fd ? vp_canfd_decode(f.id, f.data, f.len, &node, &m) : vp_can_rx_push(&rx_, f.id, f.data, f.len, &node, &m);
  if (st == VP_NEED_MORE) return;  // a segment of a classic transfer
  if (st == VP_OK && node != node_) {
    // the kernel filter should have stopped it; counted so a filter failure is visible
    ++can_stats_.foreign_frames;
    return;
  }
  session_.on_frame(st, m, now_us);
}

void CanDevice::poll(int timeout_ms) {
  std::uint64_t now = clock_.now_us();
  if (!sock_.is_open()) {
    if (!opened_once_ || now >= session_.next_reconnect_us()) try_open(now);
    if (!sock_.is_open()) return;
  }
  pollfd p{sock_.fd(), POLLIN, 0};
  if (::poll(&p, 1, timeout_ms) > 0) {
    now = clock_.now_us();
    CanRxFrame f;
    for (int i = 0; i < 10000 && sock_.is_open(); ++i) {
      int r = sock_.read(f);
      if (r == 0) break;
      if (r < 0) {
        sock_.close();
        session_.transport_down(now, "CAN interface down");
        return;
      }
      handle(f, now);
    }
  }
  if (sock_.is_open() && session_.tick(now)) sock_.close();
}

}  // namespace vitreo::drivers
