#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <type_traits>
#include <map>
#include <string>

#include "firmware-protocol/vp.hpp"

namespace vitreo::proto {
namespace {

// One list of fields per message drives both describe() and parse(), so the two cannot drift.
template <class V>
bool fields(vp_message& m, V&& v) {
  switch (m.type) {
    case VP_MSG_HEARTBEAT: {
      auto& h = m.u.heartbeat;
      v("uptime_us", h.uptime_us), v("device_state", h.device_state), v("error_count", h.error_count);
      return true;
    }
    case VP_MSG_DEVICE_INFO: {
      auto& d = m.u.device_info;
      v("device_type", d.device_type), v("hw_revision", d.hw_revision), v("serial", d.serial);
      v("fw_major", d.fw_major), v("fw_minor", d.fw_minor), v("fw_patch", d.fw_patch);
      v("proto_major", d.proto_major), v("proto_minor", d.proto_minor);
      v("sample_rate_hz", d.sample_rate_hz);
      return true;
    }
    case VP_MSG_TIME_SYNC: {
      auto& t = m.u.time_sync;
      v("phase", t.phase), v("exchange", t.exchange), v("host_tx_us", t.host_tx_us);
      v("device_rx_us", t.device_rx_us), v("device_tx_us", t.device_tx_us);
      return true;
    }
    case VP_MSG_STATUS: {
      auto& s = m.u.status;
      v("severity", s.severity), v("code", s.code), v("detail", s.detail), v("timestamp_us", s.timestamp_us);
      return true;
    }
    case VP_MSG_CONFIG: {
      auto& c = m.u.config;
      v("op", c.op), v("key", c.key), v("value", c.value);
      return true;
    }
    case VP_MSG_CALIB_REQUEST: {
      auto& c = m.u.calib_request;
      v("procedure", c.procedure), v("instrument_id", c.instrument_id), v("token", c.token);
      return true;
    }
    case VP_MSG_CALIB_RESULT: {
      auto& c = m.u.calib_result;
      v("procedure", c.procedure), v("instrument_id", c.instrument_id), v("token", c.token);
      v("result", c.result), v("residual_mm", c.residual_mm), v("offset_mm", c.offset_mm);
      return true;
    }
    case VP_MSG_POSE_SAMPLE: {
      auto& s = m.u.pose;
      v("timestamp_us", s.timestamp_us), v("instrument_id", s.instrument_id), v("tool_type", s.tool_type);
      v("tip_mm", s.tip_mm), v("q_wxyz", s.q_wxyz), v("actuation", s.actuation);
      v("quality_pct", s.quality_pct);
      return true;
    }
    case VP_MSG_PEDAL_STATE: {
      auto& s = m.u.pedal;
      v("timestamp_us", s.timestamp_us), v("pedal_id", s.pedal_id), v("axis_count", s.axis_count);
      v("axes", s.axes), v("switches", s.switches);
      return true;
    }
    case VP_MSG_EYEBALL_STATE: {
      auto& s = m.u.eyeball;
      v("timestamp_us", s.timestamp_us), v("q_wxyz", s.q_wxyz), v("port_count", s.port_count);
      static const std::array<const char*, 4> flags{"port0_flags", "port1_flags", "port2_flags", "port3_flags"};
      static const std::array<const char*, 4> depth{"port0_depth_mm", "port1_depth_mm", "port2_depth_mm",
                                                    "port3_depth_mm"};
      for (unsigned i = 0; i < VP_MAX_EYE_PORTS; ++i) v(flags[i], s.ports[i].flags), v(depth[i], s.ports[i].depth_mm);
      return true;
    }
    default: return false;
  }
}

std::string fmt(std::uint64_t x) { return std::to_string(x); }
std::string fmt(float f) {
  char b[32];
  std::snprintf(b, sizeof b, "%.9g", static_cast<double>(f));
  return b;
}
std::string fmt(std::uint8_t x) { return std::to_string(x); }
std::string fmt(std::uint16_t x) { return std::to_string(x); }
std::string fmt(std::uint32_t x) { return std::to_string(x); }
template <class T, std::size_t N>
std::string fmt(const T (&a)[N]) {
  std::string s;
  for (std::size_t i = 0; i < N; ++i) s += (i ? "," : "") + fmt(a[i]);
  return s;
}

bool scan(const std::string& s, float& f) {
  char* end = nullptr;
  errno = 0;
  f = std::strtof(s.c_str(), &end);
  return end && *end == '\0' && !s.empty();
}
template <class T>
  requires std::is_unsigned_v<T>
bool scan(const std::string& s, T& x) {
  if (s.empty() || s[0] == '-') return false;
  char* end = nullptr;
  errno = 0;
  unsigned long long v = std::strtoull(s.c_str(), &end, 0);
  if (errno || !end || *end != '\0' || v > std::numeric_limits<T>::max()) return false;
  x = static_cast<T>(v);
  return true;
}
template <class T, std::size_t N>
bool scan(const std::string& s, T (&a)[N]) {
  std::size_t start = 0;
  for (std::size_t i = 0; i < N; ++i) {
    std::size_t comma = s.find(',', start);
    if ((i + 1 < N) != (comma != std::string::npos)) return false;
    if (!scan(s.substr(start, comma == std::string::npos ? std::string::npos : comma - start), a[i])) return false;
    start = comma + 1;
  }
  return true;
}

std::optional<std::uint8_t> type_from_name(std::string_view name) {
  for (unsigned t = 0; t < 256; ++t)
    if (vp_payload_size(static_cast<std::uint8_t>(t)) && name == vp_msg_type_name(static_cast<std::uint8_t>(t)))
      return static_cast<std::uint8_t>(t);
  return std::nullopt;
}

}  // namespace

std::string describe(const vp_message& m) {
  std::string out = vp_msg_type_name(m.type);
  out += " seq=" + std::to_string(m.seq);
  if (m.version_minor != VP_PROTO_MINOR) out += " version_minor=" + std::to_string(m.version_minor);
  vp_message copy = m;
  fields(copy, [&](const char* name, auto& field) { out += std::string(" ") + name + "=" + fmt(field); });
  return out;
}

std::optional<vp_message> parse(std::string_view text, std::string* error) {
  auto fail = [&](std::string why) -> std::optional<vp_message> {
    if (error) *error = std::move(why);
    return std::nullopt;
  };
  std::map<std::string, std::string> kv;
  std::string type_name;
  std::size_t i = 0;
  while (i < text.size()) {
    while (i < text.size() && text[i] == ' ') ++i;
    std::size_t j = text.find(' ', i);
    if (j == std::string_view::npos) j = text.size();
    std::string tok(text.substr(i, j - i));
    i = j;
    if (tok.empty()) continue;
    auto eq = tok.find('=');
    if (type_name.empty() && eq == std::string::npos) {
      type_name = tok;
      continue;
    }
    if (eq == std::string::npos) return fail("expected key=value, got '" + tok + "'");
    kv[tok.substr(0, eq)] = tok.substr(eq + 1);
  }
  auto type = type_from_name(type_name);
  if (!type) return fail("unknown message type '" + type_name + "'");
  vp_message m = make(static_cast<vp_msg_type>(*type));
  bool ok = true;
  auto take = [&](const char* name, auto& field) {
    auto it = kv.find(name);
    if (it == kv.end()) return;  // missing fields stay zero
    if (!scan(it->second, field)) {
      ok = false;
      if (error) *error = std::string("bad value for ") + name + ": '" + it->second + "'";
    }
    kv.erase(it);
  };
  take("seq", m.seq);
  take("version_minor", m.version_minor);
  fields(m, take);
  if (!ok) return std::nullopt;
  if (!kv.empty()) return fail("unknown field '" + kv.begin()->first + "' for " + type_name);
  return m;
}

Bytes encode_packet(const vp_message& m) {
  Bytes b(VP_MAX_PACKET);
  std::size_t n = 0;
  if (vp_encode_packet(&m, b.data(), b.size(), &n) != VP_OK) return {};
  b.resize(n);
  return b;
}
Bytes encode_serial(const vp_message& m) {
  Bytes b(VP_SERIAL_MAX_FRAME);
  std::size_t n = 0;
  if (vp_serial_encode(&m, b.data(), b.size(), &n) != VP_OK) return {};
  b.resize(n);
  return b;
}
Bytes encode_usb(const vp_message& m) {
  Bytes b(VP_USB_MAX_PACKET);
  std::size_t n = 0;
  if (vp_usb_encode(&m, b.data(), b.size(), &n) != VP_OK) return {};
  b.resize(n);
  return b;
}
Bytes frame_usb(std::span<const std::uint8_t> packet) {
  Bytes b(packet.begin(), packet.end());
  std::uint16_t crc = vp_crc16(packet.data(), packet.size());
  b.push_back(std::uint8_t(crc >> 8));
  b.push_back(std::uint8_t(crc));
  return b;
}
Bytes frame_serial(std::span<const std::uint8_t> packet) {
  Bytes raw(packet.begin(), packet.end());
  const std::uint32_t crc = vp_crc32c(packet.data(), packet.size());
  for (int shift : {24, 16, 8, 0}) raw.push_back(std::uint8_t(crc >> shift));
  Bytes out(raw.size() + raw.size() / 254 + 2);
  std::size_t n = vp_cobs_encode(raw.data(), raw.size(), out.data(), out.size());
  out.resize(n);
  out.push_back(0);
  return out;
}
std::optional<CanFrame> encode_canfd(const vp_message& m, std::uint8_t node_id) {
  CanFrame f;
  f.fd = true;
  f.data.resize(VP_CANFD_MAX_DATA);
  std::size_t n = 0;
  if (vp_canfd_encode(&m, node_id, &f.id, f.data.data(), &n) != VP_OK) return std::nullopt;
  f.data.resize(n);
  return f;
}
std::vector<CanFrame> encode_can_classic(const vp_message& m, std::uint8_t node_id, std::uint8_t transfer_id) {
  vp_can_frame8 frames[VP_CAN_MAX_SEGMENTS];
  std::size_t count = 0;
  std::uint32_t id = 0;
  std::vector<CanFrame> out;
  if (vp_can_segment(&m, node_id, transfer_id, &id, frames, VP_CAN_MAX_SEGMENTS, &count) != VP_OK) return out;
  for (std::size_t i = 0; i < count; ++i) out.push_back(CanFrame{id, false, Bytes(frames[i].data, frames[i].data + frames[i].len)});
  return out;
}

}  // namespace vitreo::proto
