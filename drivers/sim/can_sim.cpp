#include "drivers/sim/can_sim.hpp"

#include <linux/can.h>

#include <algorithm>

namespace vitreo::drivers::sim {

CanSimDevice::CanSimDevice(Script s, std::string ifname, std::uint8_t node_id, bool fd)
    : emu_(std::move(s)), node_(node_id & 0x7F), fd_(fd) {
  vp_can_rx_init(&rx_);
  // frames the host addresses to this node
  const std::uint32_t id = CAN_EFF_FLAG | static_cast<std::uint32_t>(VP_CAN_ID_TO_DEVICE) | node_;
  sock_.open(ifname, fd, {{id, CAN_EFF_FLAG | CAN_RTR_FLAG | static_cast<std::uint32_t>(VP_CAN_ID_TO_DEVICE) | 0x7Fu}},
             false, &error_);
}

void CanSimDevice::unplug() { manual_unplug_ = true; }

void CanSimDevice::plug() {
  if (!manual_unplug_) return;
  manual_unplug_ = false;
  if (!scripted_down_) {
    emu_.reset_link();  // power-cycled: waits to be identified and configured again
    vp_can_rx_init(&rx_);
  }
}

void CanSimDevice::step(std::uint64_t now_us) {
  if (!sock_.is_open()) return;
  const bool scripted = emu_.disconnected(now_us);
  if (scripted_down_ && !scripted && !manual_unplug_) {
    emu_.reset_link();
    vp_can_rx_init(&rx_);
  }
  scripted_down_ = scripted;
  CanRxFrame f;
  if (!plugged()) {
    while (sock_.read(f) == 1) {
    }  // off the bus: the host's frames go nowhere
    std::vector<proto::Bytes> discard;
    emu_.step(now_us, discard);  // time goes on for an unplugged device
    return;
  }
  while (sock_.read(f) == 1) {
    vp_message m{};
    std::uint8_t node = 0;
    const std::uint32_t id = f.id & ~static_cast<std::uint32_t>(VP_CAN_ID_TO_DEVICE);
    int st = f.fd ? vp_canfd_decode(id, f.data, f.len, &node, &m) : vp_can_rx_push(&rx_, id, f.data, f.len, &node, &m);
    if (st == VP_OK) emu_.on_host_message(m, now_us);
  }
  std::vector<proto::Bytes> packets;
  emu_.step(now_us, packets);
  for (auto& p : packets) {
    // framed from the packet bytes, not re-encoded: a faulty packet (wrong version, unknown type)
    // goes out exactly as a broken firmware would send it
    const std::uint8_t type = p.size() > 1 ? p[1] : 0;
    if (fd_) {
      proto::CanFrame fr{vp_can_id(vp_can_default_priority(type), type, node_), true, p};
      fr.data.resize(vp_canfd_round_len(p.size()), 0);
      if (sock_.write(fr)) ++written_, bytes_written_ += fr.data.size();
    } else {
      // classic: segment the packet bytes as vp_can_segment does (tail bytes, CRC for multi-frame)
      const std::uint32_t cid = vp_can_id(vp_can_default_priority(type), type, node_);
      const std::uint8_t tid = tid_[type]++ & 0x1F;
      proto::Bytes s = p;
      if (s.size() > 7) {
        const std::uint16_t crc = vp_crc16(p.data(), p.size());
        s.push_back(static_cast<std::uint8_t>(crc >> 8));
        s.push_back(static_cast<std::uint8_t>(crc));
      }
      std::uint8_t toggle = VP_CAN_TAIL_TOGGLE;
      for (std::size_t off = 0; off < s.size(); off += 7) {
        const std::size_t n = std::min<std::size_t>(7, s.size() - off);
        proto::CanFrame fr{cid, false, proto::Bytes(s.begin() + static_cast<long>(off), s.begin() + static_cast<long>(off + n))};
        std::uint8_t tail = static_cast<std::uint8_t>(toggle | tid);
        if (off == 0) tail |= VP_CAN_TAIL_SOT;
        if (off + n == s.size()) tail |= VP_CAN_TAIL_EOT;
        fr.data.push_back(tail);
        if (sock_.write(fr)) ++written_, bytes_written_ += fr.data.size();
        toggle ^= VP_CAN_TAIL_TOGGLE;
      }
    }
  }
}

}  // namespace vitreo::drivers::sim
