#pragma once
// What physics consumes and a recording stores: one typed record per input, whatever its kind.
//
// Live and replayed sessions must feed the simulation the same bits, so everything that changes it —
// a device's sample, a link going up or down, an operator's command, a case switch, the session's
// end — becomes a RecordedInput before physics sees it, and physics reads only that. Each kind is
// its own struct with named fields; the kind's code on the wire (device_input_t.device_kind) is its
// place in InputPayload plus one. RECORDING.md lists every kind, its code and every field with its
// unit and range; input_codec.hpp turns records into device_input_t and back.
//
// Measured quantities stay doubles as the driver or the command gave them (a float widened to a
// double is exact), so a replay hands physics the recorded bits, not a rounding of them.
#include <array>
#include <cstdint>
#include <variant>

namespace vitreo::telemetry {

// device_input_t.device_kind: the codes RECORDING.md and device_input_t.lcm document.
enum class InputKind : std::int8_t {
  Tracker = 1,
  EyeFixture = 2,
  Pedal = 3,
  LinkChange = 4,
  SessionEnd = 5,
  OperatorCommand = 6,
  CaseSwitch = 7,
};

// A tracked instrument's pose, in the eye fixture's frame (the fixture's orientation is separate).
struct TrackerSample {
  static constexpr InputKind kKind = InputKind::Tracker;
  std::array<double, 3> tip_mm{};
  std::array<double, 4> q_wxyz{1.0, 0.0, 0.0, 0.0};  // the instrument's orientation, unit quaternion
  double actuation = 0.0;         // 0..1 of the handpiece's squeeze
  double quality = 0.0;           // 0..1 of the tracker's confidence
  std::uint8_t instrument_id = 0;  // the tracker's instrument slot (0 tool hand, 1 light pipe, ...)
  std::uint8_t tool_type = 0;      // PROTOCOL.md's tool type (0 universal handpiece, 1 light pipe, ...)
};

// The eyeball fixture: the globe's orientation and, per port, whether an instrument is in and how deep.
inline constexpr std::size_t kFixturePorts = 4;
struct EyeFixtureSample {
  static constexpr InputKind kKind = InputKind::EyeFixture;
  std::array<double, 4> q_wxyz{1.0, 0.0, 0.0, 0.0};  // the globe in the fixture, unit quaternion
  std::uint8_t port_count = 0;                        // ports the fixture has, 0..4
  std::array<bool, kFixturePorts> inserted{};
  std::array<double, kFixturePorts> depth_mm{};
};

// A foot pedal: which one (the rig file's pedal mapping says what it does), its axes and switches.
struct PedalSample {
  static constexpr InputKind kKind = InputKind::Pedal;
  std::uint8_t pedal_id = 0;
  std::uint8_t axis_count = 0;       // 0..4
  std::array<double, 4> axes{};      // 0..1 of travel, as the pedal reports it
  std::uint16_t switches = 0;        // bit i: switch i held
};

// A device's link changed state. A lost or stuck tracker must freeze its instrument in replay exactly
// when it did live, so these are recorded like samples; Up ends both.
enum class LinkEvent : std::uint8_t { Up = 1, Lost = 2, Stuck = 3 };
struct LinkChange {
  static constexpr InputKind kKind = InputKind::LinkChange;
  LinkEvent event = LinkEvent::Up;
  std::uint8_t device_type = 0;  // from the device's DEVICE_INFO (1 tracker, 2 pedal, 3 eyeball), 0 before one came
};

// The session's end, recorded at its last step, so a replay knows how long the session ran.
struct SessionEnd {
  static constexpr InputKind kKind = InputKind::SessionEnd;
  std::int64_t steps_run = 0;  // always the record's own step + 1
};

// An accepted operator command: pause, reset, zoom or the laser's settings change the session, so
// they are recorded and replayed like device inputs.
struct OperatorCommand {
  static constexpr InputKind kKind = InputKind::OperatorCommand;
  std::int8_t code = 0;  // telemetry::CommandCode, 1..kLastCommandCode
  double value = 0.0;    // the command's value in its unit (zoom: ×, pan x and focus: mm, laser: mW or ms)
  double pan_y_mm = 0.0;  // a pan's y; 0 for every other command
};

// A case (re)loaded at this step: next/previous case and reset take effect when the loader thread has
// the case ready, so the step they land on is recorded.
struct CaseSwitch {
  static constexpr InputKind kKind = InputKind::CaseSwitch;
  std::int32_t index = 0;  // in the session's case list (the header's), 0..4096
};

// The order is the kind codes' order: a payload's code is its index + 1.
using InputPayload =
    std::variant<TrackerSample, EyeFixtureSample, PedalSample, LinkChange, SessionEnd, OperatorCommand, CaseSwitch>;

constexpr InputKind kind_of(const InputPayload& p) noexcept { return static_cast<InputKind>(p.index() + 1); }

struct RecordedInput {
  std::int64_t host_time_us = 0;    // monotonic host clock when the driver received it (µs)
  std::int64_t device_time_us = 0;  // the device's own timestamp (µs); 0 for what no device sent
  std::int64_t step = 0;            // the physics step that consumed it
  std::int32_t device_id = 0;       // the rig file's device id; 0 for what no device sent
  std::int32_t channel = 0;         // the rig file's channel of the device (a tracker's: its instrument slot)
  std::int64_t sequence = 0;        // per device, counting samples and link changes; a command's seq
  InputPayload what;
};

// Same stamp and the same bits in every field (NaN == NaN, -0 != +0): replay must be bit-identical.
bool operator==(const RecordedInput& a, const RecordedInput& b) noexcept;

}  // namespace vitreo::telemetry
