// Firmware emulators: the tracker, pedals and eyeball fixture as their firmware behaves on the
// wire — same messages, same sequence counters, same answers to identify/configure/time sync —
// driven by a script (keyframed motion, pedal presses, eye rotations) and able to misbehave on
// purpose. Transport bindings (pty, USB under umockdev, CAN) move the packets.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "firmware-protocol/vp.hpp"

namespace vitreo::drivers::sim {

enum class DeviceKind { tracker, pedals, eyeball };
const char* to_string(DeviceKind k);

enum class FaultKind { nan, range, stuck, jump, version, unknown, drop, disconnect };

struct FaultEvent {
  std::uint64_t at_us = 0;
  std::uint64_t duration_us = 0;
  FaultKind kind = FaultKind::drop;
  double value = 0;  // jump: milliseconds added to the device clock
};

// Script text, one directive per line ('#' starts a comment):
//   device tracker|pedals|eyeball     rate_hz N     serial N     loop 0|1     autostream 0|1
//   tool N  instrument N              (tracker only) tool type (PROTOCOL.md: 0 a universal handpiece,
//                                     9 blade, ...) and tracker channel
//   key <t_ms> <values...>            tracker: x_mm y_mm z_mm yaw_deg pitch_deg roll_deg actuation(0..1)
//                                     pedals:  axis0 axis1 switches           (axes 0..1; with `axes N`, N axes then switches)
//   pedal_id N   axes N               (pedals only, before the first key) the pedal's id (0 the vitrectomy
//                                     pedal, 1 the microscope's) and its axis count 1..4 (default 0 and 2)
//                                     eyeball: yaw_deg pitch_deg depth0_mm depth1_mm depth2_mm (0 = no instrument)
//   corrupt <probability per byte>    drop <probability per frame>           seed N
//   noise <scale>                     sensor noise, 1 by default (0: none): a real tracker and fixture
//                                     never report the same bits twice, and the driver calls a pose
//                                     that does for 50 ms stuck
//   fault <t_ms> <duration_ms> nan|range|stuck|jump|version|unknown|drop|disconnect [value]
// Imperfections to calibrate against (all off by default; rig/calibration/README.md):
//   tip_offset X Y Z                  tracker: the tracked point sits this far (mm, instrument frame)
//                                     behind the real tip, which is what the keys describe
//   tracker_frame YAW PITCH ROLL X Y Z  tracker: the tracker's frame relative to the fixture's (the
//                                     keys' frame): reported = R·true + t (degrees, mm)
//   pedal_range AXIS LO HI            pedals: the potentiometer reads LO at rest and HI fully down
//   clock_offset_ms X  clock_drift_ppm Y   the device clock's extra offset and rate error
//   eye_zero YAW PITCH                eyeball: what the fixture reads with the eye at rest (degrees):
//                                     reported = zero · true
// ("noise 10" gives the 0.05 mm of tracker noise.)
struct Imperfections {
  double tip_offset_mm[3] = {0, 0, 0};
  double frame_ypr_deg[3] = {0, 0, 0};
  double frame_t_mm[3] = {0, 0, 0};
  double pedal_lo[2] = {0, 0}, pedal_hi[2] = {1, 1};
  double clock_offset_ms = 0, clock_drift_ppm = 0;
  double eye_zero_deg[2] = {0, 0};
  bool tracker_any() const;
  bool clock_any() const { return clock_offset_ms != 0 || clock_drift_ppm != 0; }
};
struct Script {
  DeviceKind kind = DeviceKind::tracker;
  std::uint16_t rate_hz = 1000;
  std::uint32_t serial = 1;
  bool loop = true;
  bool autostream = false;
  std::uint8_t tool = VP_TOOL_FORCEPS;
  std::uint8_t instrument = 0;
  std::uint8_t pedal_id = 0, pedal_axes = 2;  // pedals only
  std::vector<std::pair<std::uint64_t, std::vector<double>>> keys;
  std::vector<FaultEvent> faults;
  double corrupt_byte_prob = 0;
  double drop_frame_prob = 0;
  std::uint64_t seed = 1;
  // Gaussian sensor noise, times this scale: tracker tip 5 µm and orientation 0.01° (1 σ, a good
  // optical tracker's jitter), eyeball fixture orientation 0.01° and port depth 2 µm. Pedals have a
  // dead band at rest and none.
  double noise = 1.0;
  Imperfections imperfect;
};
// Parses a script; on error returns false with "line N: reason".
bool parse_script(const std::string& text, Script& out, std::string* error);
// Built-in scripts for the tool's simulate mode and for tests.
Script default_script(DeviceKind k);

struct SimCounters {
  std::uint64_t frames_sent = 0;       // frames handed to the transport
  std::uint64_t samples_sent = 0;      // of which valid samples
  std::uint64_t frames_corrupted = 0;  // frames with at least one corrupted byte
  std::uint64_t bytes_corrupted = 0;
  std::uint64_t frames_dropped = 0;    // never handed to the transport
  std::uint64_t invalid_injected = 0;  // NaN / out of range / wrong version / unknown type
  std::uint64_t host_messages = 0;
};

class FirmwareEmulator {
 public:
  explicit FirmwareEmulator(Script s);

  // A message from the host (identify, configure, time sync, calibration request).
  void on_host_message(const vp_message& m, std::uint64_t now_us);
  // Appends the packets due up to now_us (host clock; the emulator adds its own device offset).
  void step(std::uint64_t now_us, std::vector<proto::Bytes>& packets);
  // True while a scripted disconnect is in progress.
  bool disconnected(std::uint64_t now_us) const;
  // Byte corruption as the wire would do it (serial/USB), counted.
  void corrupt(proto::Bytes& frame);
  // Called for every valid sample sent (tests compare delivered samples against these).
  void set_on_sample_sent(std::function<void(const vp_message&)> f) { on_sent_ = std::move(f); }
  // Forget the host's configuration (what a power cycle does).
  void reset_link();

  const Script& script() const { return s_; }
  SimCounters& counters() { return c_; }
  std::uint64_t device_time_us(std::uint64_t now_us) const;
  bool streaming() const { return streaming_; }

 private:
  bool in_fault(FaultKind k, std::uint64_t t_us) const;
  vp_message make_sample(std::uint64_t t_script_us, std::uint64_t device_us);
  void emit(vp_message m, std::vector<proto::Bytes>& packets, std::uint64_t script_us, bool valid);

  Script s_;
  SimCounters c_;
  std::mt19937_64 rng_;        // faults: corruption, drops
  std::mt19937_64 noise_rng_;  // sensor noise, a stream of its own so noise does not move the faults
  std::function<void(const vp_message&)> on_sent_;
  std::vector<vp_message> replies_;
  bool streaming_ = false;
  std::uint8_t seq_ = 0;
  std::uint64_t start_us_ = 0;
  bool started_ = false;
  std::uint64_t next_sample_us_ = 0, next_heartbeat_us_ = 0;
  std::int64_t device_offset_us_ = -3'000'000'000LL;  // device booted long after the host epoch
  bool have_stuck_ = false;
  vp_message stuck_{};
};

}  // namespace vitreo::drivers::sim
