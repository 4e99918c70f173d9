#include "drivers/session.hpp"

#include <chrono>
#include <cstdio>
#include <cstring>

namespace vitreo::drivers {

std::uint64_t SteadyClock::now_us() {
  return static_cast<std::uint64_t>(
      std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now().time_since_epoch())
          .count());
}

const char* to_string(LinkState s) {
  switch (s) {
    case LinkState::connecting: return "connecting";
    case LinkState::configuring: return "configuring";
    case LinkState::streaming: return "streaming";
    case LinkState::stale: return "stale";
    case LinkState::lost: return "lost";
    case LinkState::reconnecting: return "reconnecting";
  }
  return "?";
}

std::string to_string(const LinkStats& s) {
  char b[640];
  std::snprintf(b, sizeof b,
                "bytes=%llu frames=%llu valid=%llu crc=%llu framing=%llu version=%llu unknown=%llu length=%llu "
                "range=%llu drops=%llu ts_jumps=%llu stuck=%llu stuck_episodes=%llu identity=%llu delivered=%llu disconnects=%llu reconnects=%llu "
                "latency_us(last/mean/max)=%llu/%.0f/%llu",
                (unsigned long long)s.bytes, (unsigned long long)s.frames, (unsigned long long)s.valid,
                (unsigned long long)s.crc_errors, (unsigned long long)s.framing_errors,
                (unsigned long long)s.version_errors, (unsigned long long)s.unknown_type,
                (unsigned long long)s.length_errors, (unsigned long long)s.range_rejected,
                (unsigned long long)s.drops, (unsigned long long)s.timestamp_jumps,
                (unsigned long long)s.stuck_samples, (unsigned long long)s.stuck_episodes, (unsigned long long)s.identity_rejected,
                (unsigned long long)s.samples_delivered,
                (unsigned long long)s.disconnects, (unsigned long long)s.reconnects,
                (unsigned long long)s.latency_last_us, s.latency_mean_us, (unsigned long long)s.latency_max_us);
  return b;
}

// ---- clock mapping ----
namespace {
constexpr std::int64_t kDriftPpm = 200;  // crystal tolerance of both ends, generously
}

void ClockMapper::on_sample(std::uint64_t device_us, std::uint64_t host_rx_us) {
  const std::int64_t observed = static_cast<std::int64_t>(host_rx_us) - static_cast<std::int64_t>(device_us);
  if (!have_) {
    offset_us_ = min_offset_us_ = observed;
    min_host_us_ = host_rx_us;
    have_ = true;
  } else if (!synced_) {
    // the minimum may creep up at the drift allowance since it was observed, so a device clock
    // running slow relative to the host does not leave the estimate behind for ever (computed
    // from the minimum's age: per-sample increments would round to zero at 1 kHz)
    const std::int64_t age = static_cast<std::int64_t>(host_rx_us - min_host_us_);
    const std::int64_t allowed = min_offset_us_ + age * kDriftPpm / 1'000'000;
    if (observed <= allowed) {
      min_offset_us_ = observed;
      min_host_us_ = host_rx_us;
      offset_us_ = observed;
    } else {
      offset_us_ = allowed;
    }
  }
  last_host_us_ = host_rx_us;
}

void ClockMapper::on_sync(std::uint64_t host_tx_us, std::uint64_t device_rx_us, std::uint64_t device_tx_us,
                          std::uint64_t host_rx_us) {
  if (host_rx_us < host_tx_us || device_tx_us < device_rx_us) return;  // nonsense: ignore
  const std::uint64_t rtt = (host_rx_us - host_tx_us) - (device_tx_us - device_rx_us);
  // offset = host − device at the midpoint of the exchange (NTP, RFC 5905 §8)
  const std::int64_t off = ((static_cast<std::int64_t>(host_tx_us) - static_cast<std::int64_t>(device_rx_us)) +
                            (static_cast<std::int64_t>(host_rx_us) - static_cast<std::int64_t>(device_tx_us))) /
                           2;
  if (!synced_ || rtt <= best_rtt_us_ * 2 + 200) {
    offset_us_ = off;
    best_rtt_us_ = synced_ && best_rtt_us_ < rtt ? best_rtt_us_ : rtt;
    synced_ = true;
    have_ = true;
  }
  last_host_us_ = host_rx_us;
}

std::uint64_t ClockMapper::to_host_us(std::uint64_t device_us) const {
  const std::int64_t h = static_cast<std::int64_t>(device_us) + offset_us_;
  return h < 0 ? 0 : static_cast<std::uint64_t>(h);
}

// ---- session ----
void DeviceSession::set_state(LinkState s, std::uint64_t now_us, const char* why) {
  if (s == state_) return;
  LinkState from = state_;
  state_ = s;
  state_since_us_ = now_us;
  if (on_state_) on_state_(from, s, why);
}

std::uint16_t nominal_sample_rate_hz(std::uint8_t device_type) {
  switch (device_type) {
    case VP_DEVICE_PEDAL: return 500;
    case VP_DEVICE_EYEBALL: return 250;
    default: return 1000;  // a tracker, per instrument
  }
}

std::uint16_t DeviceSession::configured_rate_hz() const {
  if (cfg_.sample_rate_hz != 0) return cfg_.sample_rate_hz;
  return have_info_ ? nominal_sample_rate_hz(info_.device_type) : 0;
}

std::uint64_t DeviceSession::stale_after_us() const {
  const std::uint16_t rate = configured_rate_hz();
  const std::uint64_t periods = rate ? 20'000'000u / rate : 0;
  return periods > cfg_.stale_after_us ? periods : cfg_.stale_after_us;
}

void DeviceSession::send(vp_message m) {
  m.seq = tx_seq_++;
  m.version_minor = VP_PROTO_MINOR;
  ++stats_.frames_tx;
  if (send_) send_(m);
}

void DeviceSession::send_identify() {
  vp_message m{};
  m.type = VP_MSG_CONFIG;
  m.u.config = {VP_CFG_GET, VP_CFG_KEY_IDENTIFY, 0};
  send(m);
}

void DeviceSession::send_configure(std::uint64_t now_us) {
  vp_message m{};
  m.type = VP_MSG_CONFIG;
  m.u.config = {VP_CFG_SET, VP_CFG_KEY_SAMPLE_RATE_HZ, configured_rate_hz()};
  send(m);
  m.u.config = {VP_CFG_SET, VP_CFG_KEY_STREAMING, 1};
  send(m);
  m = vp_message{};
  m.type = VP_MSG_TIME_SYNC;
  m.u.time_sync.phase = 0;
  m.u.time_sync.exchange = ++sync_exchange_;
  m.u.time_sync.host_tx_us = now_us;
  sync_tx_us_ = now_us;
  send(m);
}

void DeviceSession::transport_up(std::uint64_t now_us) {
  // a reconnect is counted when the device identifies itself on the re-opened transport: re-opening
  // a CAN socket or a pty link succeeds whether or not the device is there
  recovering_ = state_ == LinkState::reconnecting || stats_.disconnects > 0;
  have_info_ = false;
  configured_ = false;
  last_seq_ = -1;
  have_device_us_ = false;
  last_host_us_ = 0;
  last_payload_.clear();
  stuck_ = false;
  refusal_.clear();
  last_sample_us_ = 0;
  clock_.reset();
  last_frame_us_ = now_us;
  last_heartbeat_us_ = now_us;
  set_state(LinkState::connecting, now_us, "transport open");
  send_identify();
  next_retry_us_ = now_us + cfg_.retry_us;
}

void DeviceSession::transport_down(std::uint64_t now_us, const char* why) {
  last_error_ = why;
  if (state_ == LinkState::lost || state_ == LinkState::reconnecting) {
    next_reconnect_us_ = now_us + cfg_.reconnect_interval_us;
    return;
  }
  ++stats_.disconnects;
  next_reconnect_us_ = now_us + cfg_.reconnect_interval_us;
  set_state(LinkState::lost, now_us, why);
}

void DeviceSession::reconnect_attempt(std::uint64_t now_us) {
  next_reconnect_us_ = now_us + cfg_.reconnect_interval_us;
  set_state(LinkState::reconnecting, now_us, "retrying");
}

void DeviceSession::count_error(int status) {
  switch (status) {
    case VP_ERR_CRC: ++stats_.crc_errors; break;
    case VP_ERR_VERSION: ++stats_.version_errors; break;
    case VP_ERR_UNKNOWN_TYPE: ++stats_.unknown_type; break;
    case VP_ERR_LENGTH: ++stats_.length_errors; break;
    case VP_ERR_RANGE: ++stats_.range_rejected; break;
    default: ++stats_.framing_errors; break;
  }
  last_error_ = vp_status_name(status);
}

void DeviceSession::on_frame(int status, const vp_message& m, std::uint64_t now_us) {
  if (state_ == LinkState::lost || state_ == LinkState::reconnecting) return;
  ++stats_.frames;
  if (status != VP_OK) {
    count_error(status);
    return;
  }
  ++stats_.valid;
  // the sequence counter is per link, over all message types; a gap is frames that never made it
  // here valid (lost on the wire or rejected above)
  if (last_seq_ >= 0) stats_.drops += static_cast<std::uint8_t>(m.seq - static_cast<std::uint8_t>(last_seq_) - 1);
  last_seq_ = m.seq;
  last_frame_us_ = now_us;
  handle(m, now_us);
}

void DeviceSession::handle(const vp_message& m, std::uint64_t now_us) {
  switch (m.type) {
    case VP_MSG_DEVICE_INFO:
      if (m.u.device_info.proto_major != VP_PROTO_MAJOR) {
        // the frame itself parsed (frames carry their own version), but the device announces a
        // protocol we do not speak: refuse to configure it rather than guess
        ++stats_.protocol_rejected;
        char why[128];
        std::snprintf(why, sizeof why, "device speaks protocol %u.%u, this host %u.%u: not configured",
                      static_cast<unsigned>(m.u.device_info.proto_major), static_cast<unsigned>(m.u.device_info.proto_minor),
                      static_cast<unsigned>(VP_PROTO_MAJOR), static_cast<unsigned>(VP_PROTO_MINOR));
        last_error_ = refusal_ = why;
        return;
      }
      if ((cfg_.expected_device_type != 0 && m.u.device_info.device_type != cfg_.expected_device_type) ||
          (cfg_.expected_serial != 0 && m.u.device_info.serial != cfg_.expected_serial)) {
        ++stats_.identity_rejected;
        char why[128];
        std::snprintf(why, sizeof why, "device is type %u serial %u, expected type %u serial %u (0 = any)",
                      static_cast<unsigned>(m.u.device_info.device_type), static_cast<unsigned>(m.u.device_info.serial),
                      static_cast<unsigned>(cfg_.expected_device_type), static_cast<unsigned>(cfg_.expected_serial));
        last_error_ = refusal_ = why;
        return;
      }
      refusal_.clear();
      info_ = m.u.device_info;
      have_info_ = true;
      if (recovering_) {
        ++stats_.reconnects;
        recovering_ = false;
      }
      if (state_ == LinkState::connecting) {
        set_state(LinkState::configuring, now_us, "device identified");
        send_configure(now_us);
        next_retry_us_ = now_us + cfg_.retry_us;
      }
      return;
    case VP_MSG_CONFIG:
      if (m.u.config.op == VP_CFG_ACK && m.u.config.key == VP_CFG_KEY_STREAMING) configured_ = m.u.config.value != 0;
      if (m.u.config.op == VP_CFG_NAK) last_error_ = "device refused a configuration value";
      return;
    case VP_MSG_TIME_SYNC:
      if (m.u.time_sync.phase == 1 && m.u.time_sync.exchange == sync_exchange_ &&
          m.u.time_sync.host_tx_us == sync_tx_us_) {
        clock_.on_sync(m.u.time_sync.host_tx_us, m.u.time_sync.device_rx_us, m.u.time_sync.device_tx_us, now_us);
        if (on_time_sync_) on_time_sync_(m.u.time_sync.host_tx_us, m.u.time_sync.device_rx_us, m.u.time_sync.device_tx_us, now_us);
      }
      return;
    case VP_MSG_STATUS:
      if (m.u.status.severity >= 2) last_error_ = "device reports error code " + std::to_string(m.u.status.code);
      if (on_message_) on_message_(m);
      return;
    case VP_MSG_POSE_SAMPLE: {
      const auto& p = m.u.pose;
      PoseSample s;
      s.instrument_id = p.instrument_id;
      s.tool_type = p.tool_type;
      for (int i = 0; i < 3; ++i) s.tip_mm[i] = p.tip_mm[i];
      for (int i = 0; i < 4; ++i) s.q_wxyz[i] = p.q_wxyz[i];
      s.actuation = p.actuation / 65535.0f;
      s.quality = p.quality_pct / 100.0f;
      // a real tracker's floats always jitter; bit-identical poses for 50 ms are a frozen sensor
      std::uint8_t key[30];
      std::memcpy(key, p.tip_mm, 12);
      std::memcpy(key + 12, p.q_wxyz, 16);
      std::memcpy(key + 28, &p.actuation, 2);
      s.stuck = check_stuck(key, sizeof key, p.timestamp_us);
      deliver(s, p.timestamp_us, now_us);
      return;
    }
    case VP_MSG_PEDAL_STATE: {
      const auto& p = m.u.pedal;
      PedalSample s;
      s.pedal_id = p.pedal_id;
      s.axis_count = p.axis_count;
      for (int i = 0; i < 4; ++i) s.axes[i] = p.axes[i] / 65535.0f;
      s.switches = p.switches;
      deliver(s, p.timestamp_us, now_us);
      return;
    }
    case VP_MSG_EYEBALL_STATE: {
      const auto& p = m.u.eyeball;
      EyeballSample s;
      for (int i = 0; i < 4; ++i) s.q_wxyz[i] = p.q_wxyz[i];
      s.port_count = p.port_count;
      for (int i = 0; i < 4; ++i) {
        s.inserted[i] = p.ports[i].flags & 1u;
        s.depth_mm[i] = p.ports[i].depth_mm;
      }
      std::uint8_t key[32];
      std::memcpy(key, p.q_wxyz, 16);
      for (int i = 0; i < 4; ++i) std::memcpy(key + 16 + 4 * i, &p.ports[i].depth_mm, 4);
      s.stuck = check_stuck(key, sizeof key, p.timestamp_us);
      deliver(s, p.timestamp_us, now_us);
      return;
    }
    default:  // heartbeat, calibration results: keep the link alive, handed to the message hook
      if (m.type == VP_MSG_HEARTBEAT) last_heartbeat_us_ = now_us;
      if (on_message_) on_message_(m);
      return;
  }
}

bool DeviceSession::check_stuck(const void* payload, std::size_t size, std::uint64_t device_us) {
  // Samples before streaming are not delivered; a timestamp that goes back starts afresh.
  const bool same = last_payload_.size() == size && std::memcmp(last_payload_.data(), payload, size) == 0 &&
                    device_us >= same_since_device_us_;
  if (!same) {
    const auto* b = static_cast<const std::uint8_t*>(payload);
    last_payload_.assign(b, b + size);
    same_since_device_us_ = device_us;
    stuck_ = false;
    return false;
  }
  if (device_us - same_since_device_us_ >= cfg_.stuck_after_us) {
    if (!stuck_) ++stats_.stuck_episodes;
    stuck_ = true;
    ++stats_.stuck_samples;
  }
  return stuck_;
}

bool DeviceSession::request_calibration(std::uint8_t procedure, std::uint8_t instrument_id, std::uint16_t token) {
  if (state_ == LinkState::lost || state_ == LinkState::reconnecting) return false;
  vp_message m{};
  m.type = VP_MSG_CALIB_REQUEST;
  m.u.calib_request = {procedure, instrument_id, token};
  send(m);
  return true;
}

void DeviceSession::deliver(Sample s, std::uint64_t device_us, std::uint64_t now_us) {
  // samples before the device acknowledged streaming belong to a previous session of the device
  if (state_ == LinkState::connecting) return;
  if (state_ == LinkState::configuring && !configured_) return;
  if (have_device_us_) {
    const std::uint64_t host_gap = now_us - last_sample_us_;
    if (device_us < last_device_us_ || device_us - last_device_us_ > host_gap + cfg_.jump_tolerance_us) {
      ++stats_.timestamp_jumps;
      clock_.reset();  // the old offset describes a clock that no longer exists
    }
  }
  last_device_us_ = device_us;
  have_device_us_ = true;
  clock_.on_sample(device_us, now_us);
  // consumers interpolate between samples: the mapped time must not step back when the offset
  // estimate improves (a less-delayed sample lowers the minimum)
  std::uint64_t host = clock_.to_host_us(device_us);
  if (host < last_host_us_) host = last_host_us_;
  last_host_us_ = host;
  SampleTime t{device_us, host, now_us, info_.serial};
  const std::uint64_t lat = t.received_us > t.host_us ? t.received_us - t.host_us : 0;
  ++stats_.latency_count;
  stats_.latency_last_us = lat;
  stats_.latency_max_us = lat > stats_.latency_max_us ? lat : stats_.latency_max_us;
  stats_.latency_mean_us += (static_cast<double>(lat) - stats_.latency_mean_us) / static_cast<double>(stats_.latency_count);
  last_sample_us_ = now_us;
  if (state_ != LinkState::streaming) set_state(LinkState::streaming, now_us, "samples arriving");
  std::visit([&](auto& x) { x.t = t; }, s);
  ++stats_.samples_delivered;
  if (on_sample_) on_sample_(s);
}

bool DeviceSession::tick(std::uint64_t now_us) {
  switch (state_) {
    case LinkState::lost:
    case LinkState::reconnecting: return false;
    case LinkState::connecting:
    case LinkState::configuring:
      if (now_us >= next_retry_us_) {
        if (state_ == LinkState::connecting) {
          send_identify();
        } else if (!configured_) {
          send_configure(now_us);
        }
        next_retry_us_ = now_us + cfg_.retry_us;
      }
      break;
    case LinkState::streaming:
      if (now_us - last_sample_us_ > stale_after_us()) set_state(LinkState::stale, now_us, "samples late");
      [[fallthrough]];
    case LinkState::stale:
      // The device's heartbeat (10 Hz) missing while it streams: one miss per gap of two periods.
      if (now_us - last_heartbeat_us_ > cfg_.heartbeat_miss_us) {
        ++stats_.heartbeat_misses;
        last_heartbeat_us_ = now_us;
      }
      if (now_us >= next_sync_us_) {
        vp_message m{};
        m.type = VP_MSG_TIME_SYNC;
        m.u.time_sync.exchange = ++sync_exchange_;
        m.u.time_sync.host_tx_us = now_us;
        sync_tx_us_ = now_us;
        send(m);
        next_sync_us_ = now_us + cfg_.time_sync_interval_us;
      }
      break;
  }
  if (now_us - last_frame_us_ > cfg_.lost_after_us) {
    transport_down(now_us, "no valid frame within the lost timeout");
    return true;
  }
  return false;
}

}  // namespace vitreo::drivers
