// Transport-independent part of every device driver: the link state machine, validation and
// counting, device→host clock mapping. Transports (serial, USB, CAN) feed it decoded messages and
// decode errors; it never reads a clock itself — "now" is always a parameter, so tests and replay
// drive it with simulated time (the ArduPilot/PX4 habit of injected time).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <variant>
#include <vector>

#include "firmware-protocol/vp.h"

namespace vitreo::drivers {

// A clock the drivers ask for "now"; tests pass a ManualClock.
class Clock {
 public:
  virtual ~Clock() = default;
  virtual std::uint64_t now_us() = 0;
};
class SteadyClock final : public Clock {
 public:
  std::uint64_t now_us() override;
};
class ManualClock final : public Clock {
 public:
  explicit ManualClock(std::uint64_t t_us = 1'000'000) : t_us_(t_us) {}
  std::uint64_t now_us() override { return t_us_; }
  void advance_us(std::uint64_t dt_us) { t_us_ += dt_us; }
  void set_us(std::uint64_t t_us) { t_us_ = t_us; }

 private:
  std::uint64_t t_us_;
};

// Every sample carries the device's timestamp, that timestamp mapped to the host clock, and the
// host time it was received (PX4's timestamp_sample vs timestamp).
struct SampleTime {
  std::uint64_t device_us = 0;
  std::uint64_t host_us = 0;      // device_us mapped into the host clock; never decreases on a link
  std::uint64_t received_us = 0;  // host clock at reception
  std::uint32_t device_serial = 0;  // from DEVICE_INFO: which device took the sample
};
struct PoseSample {
  SampleTime t;
  std::uint8_t instrument_id = 0;
  std::uint8_t tool_type = 0;
  std::array<float, 3> tip_mm{};
  std::array<float, 4> q_wxyz{1, 0, 0, 0};
  float actuation = 0;  // 0..1
  float quality = 0;    // 0..1
  bool stuck = false;   // bit-identical to every sample of the last >= stuck_after_us of device time
};
struct PedalSample {
  SampleTime t;
  std::uint8_t pedal_id = 0;
  std::uint8_t axis_count = 0;
  std::array<float, 4> axes{};  // 0..1 of travel
  std::uint16_t switches = 0;
  bool stuck = false;
};
struct EyeballSample {
  SampleTime t;
  std::array<float, 4> q_wxyz{1, 0, 0, 0};
  std::uint8_t port_count = 0;
  std::array<bool, 4> inserted{};
  std::array<float, 4> depth_mm{};
  bool stuck = false;  // as for poses: the fixture's orientation and port depths frozen
};
using Sample = std::variant<PoseSample, PedalSample, EyeballSample>;

enum class LinkState { connecting, configuring, streaming, stale, lost, reconnecting };
const char* to_string(LinkState s);

struct LinkStats {
  std::uint64_t bytes = 0;            // raw bytes (serial) or transfers' bytes (USB/CAN)
  std::uint64_t frames = 0;           // frames seen, valid or not
  std::uint64_t frames_tx = 0;        // messages the host sent the device (identify, configure, time sync, calibration)
  std::uint64_t valid = 0;            // frames that decoded and validated
  std::uint64_t crc_errors = 0;
  std::uint64_t framing_errors = 0;   // COBS/CAN framing, overflow, segment sequence, truncation
  std::uint64_t version_errors = 0;
  std::uint64_t unknown_type = 0;
  std::uint64_t length_errors = 0;
  std::uint64_t range_rejected = 0;   // NaN/inf/out-of-range fields
  std::uint64_t drops = 0;            // frames missing according to the sequence counter
  std::uint64_t timestamp_jumps = 0;  // device clock stepped backwards or far forwards
  std::uint64_t stuck_samples = 0;   // samples delivered while stuck
  std::uint64_t stuck_episodes = 0;  // times the sensor became stuck
  std::uint64_t identity_rejected = 0;  // DEVICE_INFO of another kind or serial than the rig expects
  std::uint64_t protocol_rejected = 0;  // DEVICE_INFO announcing a protocol major version the host does not speak
  std::uint64_t samples_delivered = 0;
  std::uint64_t disconnects = 0;
  std::uint64_t reconnects = 0;       // the device identified itself again after a loss
  std::uint64_t heartbeat_misses = 0; // streaming, yet no HEARTBEAT for more than heartbeat_miss_us
  std::uint64_t latency_count = 0;
  std::uint64_t latency_last_us = 0;
  std::uint64_t latency_max_us = 0;
  double latency_mean_us = 0;
  std::uint64_t rejected() const {
    return crc_errors + framing_errors + version_errors + unknown_type + length_errors + range_rejected;
  }
};
std::string to_string(const LinkStats& s);

// Maps device timestamps to the host clock. Without a time-sync exchange it keeps the smallest
// observed (host_rx − device_ts): the sample that queued least is the best estimate of the offset,
// and the minimum is allowed to creep up by a drift allowance so a slow device clock is followed.
// A time-sync reply (NTP-style four timestamps) replaces the estimate when its round trip is short.
class ClockMapper {
 public:
  void reset() { *this = ClockMapper{}; }
  void on_sample(std::uint64_t device_us, std::uint64_t host_rx_us);
  void on_sync(std::uint64_t host_tx_us, std::uint64_t device_rx_us, std::uint64_t device_tx_us,
               std::uint64_t host_rx_us);
  bool valid() const { return have_; }
  std::uint64_t to_host_us(std::uint64_t device_us) const;
  std::int64_t offset_us() const { return offset_us_; }

 private:
  bool have_ = false;
  bool synced_ = false;
  std::int64_t offset_us_ = 0;
  std::int64_t min_offset_us_ = 0;
  std::uint64_t min_host_us_ = 0;
  std::uint64_t last_host_us_ = 0;
  std::uint64_t best_rtt_us_ = 0;
};

struct SessionConfig {
  // No sample for this long, or for 20 periods of the configured rate when that is longer: stale
  // (20 ms at a tracker's 1 kHz, 40 ms at the pedals' 500 Hz, 80 ms at the eyeball's 250 Hz).
  std::uint64_t stale_after_us = 20'000;
  std::uint64_t lost_after_us = 250'000;       // no valid frame for this long: lost
  std::uint64_t retry_us = 50'000;             // identify/configure retransmission
  std::uint64_t reconnect_interval_us = 100'000;
  std::uint64_t time_sync_interval_us = 1'000'000;
  std::uint64_t jump_tolerance_us = 100'000;   // device timestamp step counted as a jump
  std::uint64_t heartbeat_miss_us = 200'000;   // two periods of the protocol's 10 Hz heartbeat
  // The rate the host configures; 0: the protocol's nominal rate for the device type that
  // identified itself (PROTOCOL.md §7: tracker 1000 Hz, pedals 500 Hz, eyeball fixture 250 Hz).
  std::uint16_t sample_rate_hz = 0;
  // A pose (tracker) or orientation (eyeball fixture) bit-identical for this long of the device's
  // own time is a frozen sensor: a real one always jitters. Samples whose timestamps do not advance
  // are repeats, not evidence. Pedals at rest legitimately repeat, so they are not checked.
  std::uint64_t stuck_after_us = 50'000;
  // Identity the rig expects at this address (0: any). A device announcing another kind or serial
  // is not configured: the wrong tracker plugged into the tracker's port must not drive the forceps.
  std::uint8_t expected_device_type = 0;       // vp_device_type
  std::uint32_t expected_serial = 0;
};

class DeviceSession {
 public:
  using SendFn = std::function<void(const vp_message&)>;
  using SampleFn = std::function<void(const Sample&)>;
  using StateFn = std::function<void(LinkState from, LinkState to, const char* why)>;
  using MessageFn = std::function<void(const vp_message&)>;

  explicit DeviceSession(SessionConfig cfg = {}) : cfg_(cfg) {}
  void set_send(SendFn f) { send_ = std::move(f); }
  void set_on_sample(SampleFn f) { on_sample_ = std::move(f); }
  void set_on_state(StateFn f) { on_state_ = std::move(f); }
  // Valid messages that are not samples (status, calibration results, heartbeats), for the rig's
  // calibration and diagnostics code.
  void set_on_message(MessageFn f) { on_message_ = std::move(f); }
  // Every completed time-sync exchange, as its four NTP timestamps (host send, device receive,
  // device send, host receive): the clock calibration fits offset and drift through them.
  using TimeSyncFn = std::function<void(std::uint64_t host_tx_us, std::uint64_t device_rx_us, std::uint64_t device_tx_us,
                                        std::uint64_t host_rx_us)>;
  void set_on_time_sync(TimeSyncFn f) { on_time_sync_ = std::move(f); }
  // Asks the device to run a calibration procedure; the CALIB_RESULT echoes `token`.
  // False when the link is not up (connecting/configuring/streaming/stale).
  bool request_calibration(std::uint8_t procedure, std::uint8_t instrument_id, std::uint16_t token);

  // Transport events.
  void transport_up(std::uint64_t now_us);
  void transport_down(std::uint64_t now_us, const char* why);
  void reconnect_attempt(std::uint64_t now_us);
  void on_bytes(std::size_t n) { stats_.bytes += n; }
  void on_frame(int status, const vp_message& m, std::uint64_t now_us);
  // Timeouts and retransmissions; returns true when the transport should be closed (lost).
  bool tick(std::uint64_t now_us);

  LinkState state() const { return state_; }
  const LinkStats& stats() const { return stats_; }
  const vp_device_info& device_info() const { return info_; }
  bool has_device_info() const { return have_info_; }
  // The sensor is stuck now (its last sample was flagged).
  bool stuck() const { return stuck_; }
  const ClockMapper& clock() const { return clock_; }
  const SessionConfig& config() const { return cfg_; }
  std::uint64_t next_reconnect_us() const { return next_reconnect_us_; }
  const std::string& last_error() const { return last_error_; }
  // The device at this address was refused — another kind or serial than expected, or a protocol
  // major version the host does not speak — and is not configured; refusal() says why (empty when
  // it was not). Cleared when the transport comes up again.
  const std::string& refusal() const { return refusal_; }
  // Host time the last sample was delivered (0: none yet on this link).
  std::uint64_t last_sample_us() const { return last_sample_us_; }
  // The rate configured for the device (0 before it identified, when the nominal rate applies).
  std::uint16_t configured_rate_hz() const;
  // How long without a sample makes the link stale (SessionConfig::stale_after_us).
  std::uint64_t stale_after_us() const;

 private:
  void set_state(LinkState s, std::uint64_t now_us, const char* why);
  void send(vp_message m);
  void send_identify();
  void send_configure(std::uint64_t now_us);
  void handle(const vp_message& m, std::uint64_t now_us);
  void deliver(Sample s, std::uint64_t device_us, std::uint64_t now_us);
  void count_error(int status);

  SessionConfig cfg_;
  SendFn send_;
  SampleFn on_sample_;
  StateFn on_state_;
  MessageFn on_message_;
  TimeSyncFn on_time_sync_;
  LinkState state_ = LinkState::lost;
  LinkStats stats_;
  vp_device_info info_{};
  bool have_info_ = false;
  bool configured_ = false;
  bool recovering_ = false;  // the transport was re-opened after a loss; the device not identified yet
  ClockMapper clock_;
  std::uint64_t last_frame_us_ = 0, last_sample_us_ = 0, state_since_us_ = 0, last_heartbeat_us_ = 0;
  std::uint64_t next_retry_us_ = 0, next_sync_us_ = 0, next_reconnect_us_ = 0;
  std::uint64_t last_device_us_ = 0, last_host_us_ = 0;
  bool have_device_us_ = false;
  int last_seq_ = -1;
  std::uint8_t tx_seq_ = 0, sync_exchange_ = 0;
  std::uint64_t sync_tx_us_ = 0;
  // Stuck detection: the payload of the current run of identical samples and where it began.
  bool check_stuck(const void* payload, std::size_t size, std::uint64_t device_us);
  std::vector<std::uint8_t> last_payload_;
  std::uint64_t same_since_device_us_ = 0;
  bool stuck_ = false;
  std::string last_error_;
  std::string refusal_;
};

// PROTOCOL.md §7's nominal sample rate of a device type (vp_device_type); 1000 for an unknown one.
std::uint16_t nominal_sample_rate_hz(std::uint8_t device_type);

}  // namespace vitreo::drivers
