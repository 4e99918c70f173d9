// Thin C++ host helpers over the C99 codec: owning buffers, a text form of every message (used by
// the test vectors, the device tool and logs), and a stream decoder with a callback.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "firmware-protocol/vp.h"

namespace vitreo::proto {

using Bytes = std::vector<std::uint8_t>;

// "pose_sample seq=3 timestamp_us=... tip_mm=1,2,3 ..." — floats with 9 significant digits, so
// the text round-trips bit-exactly through parse().
std::string describe(const vp_message& m);
// Inverse of describe(); nullopt (and a reason in *error) on anything it does not understand.
std::optional<vp_message> parse(std::string_view text, std::string* error = nullptr);

// Encoders: empty vector on failure (unknown type); they never validate ranges.
Bytes encode_packet(const vp_message& m);
Bytes encode_serial(const vp_message& m);
Bytes encode_usb(const vp_message& m);
struct CanFrame {
  std::uint32_t id = 0;
  bool fd = false;
  Bytes data;
};
// Framing of an already-encoded packet (simulators corrupt packets before framing them).
Bytes frame_serial(std::span<const std::uint8_t> packet);
Bytes frame_usb(std::span<const std::uint8_t> packet);
std::optional<CanFrame> encode_canfd(const vp_message& m, std::uint8_t node_id);
std::vector<CanFrame> encode_can_classic(const vp_message& m, std::uint8_t node_id,
                                         std::uint8_t transfer_id);

// Streaming serial decoder: feeds arbitrary chunks, calls back per frame with the decode status.
class SerialDecoder {
 public:
  SerialDecoder() { vp_serial_rx_init(&rx_); }
  template <class F>  // F(int status, const vp_message&)
  void feed(std::span<const std::uint8_t> bytes, F&& on_frame) {
    while (!bytes.empty()) {
      std::size_t used = 0;
      int st = vp_serial_rx_push(&rx_, bytes.data(), bytes.size(), &used, &msg_);
      bytes = bytes.subspan(used);
      if (st != VP_NEED_MORE) on_frame(st, static_cast<const vp_message&>(msg_));
    }
  }
  void reset() { vp_serial_rx_init(&rx_); }

 private:
  vp_serial_rx rx_{};
  vp_message msg_{};
};

inline vp_message make(vp_msg_type type, std::uint8_t seq = 0) {
  vp_message m{};
  m.type = static_cast<std::uint8_t>(type);
  m.version_minor = VP_PROTO_MINOR;
  m.seq = seq;
  return m;
}

}  // namespace vitreo::proto
