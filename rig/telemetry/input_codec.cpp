// RecordedInput <-> device_input_t: each kind's wire layout, written once per direction, and the
// range of every number read (RECORDING.md, "Inputs").
#include "rig/telemetry/input_codec.hpp"

#include <cmath>
#include <cstring>
#include <type_traits>

#include "rig/telemetry/commands.hpp"

namespace vitreo::telemetry {

namespace {

// A payload's code is its index + 1: a kind moved in InputPayload would silently renumber recordings.
template <class T, std::size_t I>
constexpr bool coded_at() {
  return std::is_same_v<std::variant_alternative_t<I, InputPayload>, T> && static_cast<std::size_t>(T::kKind) == I + 1;
}
static_assert(coded_at<TrackerSample, 0>() && coded_at<EyeFixtureSample, 1>() && coded_at<PedalSample, 2>() &&
              coded_at<LinkChange, 3>() && coded_at<SessionEnd, 4>() && coded_at<OperatorCommand, 5>() &&
              coded_at<CaseSwitch, 6>() && std::variant_size_v<InputPayload> == 7);

// How many values each kind travels in, by code (index 0 unused).
constexpr std::size_t kValueCount[] = {0, 11, 13, 7, 2, 1, 3, 1};

struct Writer {
  double (&out)[kMaxInputValues];
  std::size_t n = 0;
  void put(double v) noexcept { out[n++] = v; }
  template <std::size_t N>
  void put(const std::array<double, N>& a) noexcept {
    for (double v : a) put(v);
  }

  void operator()(const TrackerSample& s) noexcept {
    put(s.tip_mm);
    put(s.q_wxyz);
    put(s.actuation);
    put(s.quality);
    put(s.instrument_id);
    put(s.tool_type);
  }
  void operator()(const EyeFixtureSample& s) noexcept {
    put(s.q_wxyz);
    put(s.port_count);
    for (bool b : s.inserted) put(b ? 1.0 : 0.0);
    put(s.depth_mm);
  }
  void operator()(const PedalSample& s) noexcept {
    put(s.pedal_id);
    put(s.axis_count);
    put(s.axes);
    put(s.switches);
  }
  void operator()(const LinkChange& s) noexcept {
    put(static_cast<double>(s.event));
    put(s.device_type);
  }
  void operator()(const SessionEnd& s) noexcept { put(static_cast<double>(s.steps_run)); }
  void operator()(const OperatorCommand& s) noexcept {
    put(s.code);
    put(s.value);
    put(s.pan_y_mm);
  }
  void operator()(const CaseSwitch& s) noexcept { put(s.index); }
};

// Reads the values back in the same order; an integer field must be a whole number in its range.
struct Reader {
  const double* v;
  std::size_t i = 0;
  const char* why = nullptr;

  double take() noexcept { return v[i++]; }
  template <std::size_t N>
  void take(std::array<double, N>& a) noexcept {
    for (double& x : a) x = take();
  }
  template <class Int>
  void take_whole(Int& out, double lo, double hi, const char* problem) noexcept {
    const double x = take();
    if (x >= lo && x <= hi && x == std::floor(x)) out = static_cast<Int>(x);
    else if (!why) why = problem;
  }

  void operator()(TrackerSample& s) noexcept {
    take(s.tip_mm);
    take(s.q_wxyz);
    s.actuation = take();
    s.quality = take();
    take_whole(s.instrument_id, 0, 255, "a tracker sample whose instrument id is no byte");
    take_whole(s.tool_type, 0, 255, "a tracker sample whose tool type is no byte");
  }
  void operator()(EyeFixtureSample& s) noexcept {
    take(s.q_wxyz);
    take_whole(s.port_count, 0, static_cast<double>(kFixturePorts), "an eye fixture sample with more than 4 ports");
    for (bool& b : s.inserted) {
      int flag = 0;
      take_whole(flag, 0, 1, "an eye fixture sample whose port is neither in nor out");
      b = flag != 0;
    }
    take(s.depth_mm);
  }
  void operator()(PedalSample& s) noexcept {
    take_whole(s.pedal_id, 0, 255, "a pedal sample whose pedal id is no byte");
    take_whole(s.axis_count, 0, 4, "a pedal sample with more than 4 axes");
    take(s.axes);
    take_whole(s.switches, 0, 65535, "a pedal sample whose switches are no 16 bits");
  }
  void operator()(LinkChange& s) noexcept {
    std::uint8_t event = 0;
    take_whole(event, 1, 3, "a link change that is not up, lost or stuck");
    s.event = static_cast<LinkEvent>(event);
    take_whole(s.device_type, 0, 3, "a link change of an unknown device type");
  }
  void operator()(SessionEnd& s) noexcept {
    take_whole(s.steps_run, 1, static_cast<double>(kMaxRecordedStep) + 1, "a session-end marker whose step count is out of range");
  }
  void operator()(OperatorCommand& s) noexcept {
    take_whole(s.code, 1, kLastCommandCode, "an operator command with an unknown code");
    s.value = take();
    s.pan_y_mm = take();
  }
  void operator()(CaseSwitch& s) noexcept { take_whole(s.index, 0, 4096, "a case index out of range"); }
};

// The payload of the kind with this code, default-constructed (code 1..7).
InputPayload payload_of_code(std::int8_t code) noexcept {
  switch (static_cast<InputKind>(code)) {
    case InputKind::Tracker: return TrackerSample{};
    case InputKind::EyeFixture: return EyeFixtureSample{};
    case InputKind::Pedal: return PedalSample{};
    case InputKind::LinkChange: return LinkChange{};
    case InputKind::SessionEnd: return SessionEnd{};
    case InputKind::OperatorCommand: return OperatorCommand{};
    case InputKind::CaseSwitch: return CaseSwitch{};
  }
  return TrackerSample{};  // not reached: callers check the code first
}

}  // namespace

std::size_t input_values(const InputPayload& p, double (&out)[kMaxInputValues]) noexcept {
  Writer w{out};
  std::visit(w, p);
  return w.n;
}

vitreo_lcm::device_input_t to_lcm(const RecordedInput& in) {
  vitreo_lcm::device_input_t m;
  m.host_time_us = in.host_time_us;
  m.device_time_us = in.device_time_us;
  m.step = in.step;
  m.device_id = in.device_id;
  m.device_kind = static_cast<std::int8_t>(kind_of(in.what));
  m.channel = in.channel;
  m.sequence = in.sequence;
  double values[kMaxInputValues];
  const std::size_t n = input_values(in.what, values);
  m.n_values = static_cast<std::int16_t>(n);
  m.values.assign(values, values + n);
  m.n_raw = 0;  // format 3 keeps no frame bytes: the decoded fields are what physics consumed
  return m;
}

const char* from_lcm(const vitreo_lcm::device_input_t& m, RecordedInput& out) noexcept {
  if (m.n_values < 0 || static_cast<std::size_t>(m.n_values) > kMaxInputValues) return "more than 16 values";
  if (m.n_raw != 0) return "raw frame bytes, which format 3 does not keep";
  if (m.values.size() != static_cast<std::size_t>(m.n_values) || !m.raw.empty()) return "counts and arrays disagree";
  if (m.step < 0 || m.step > kMaxRecordedStep) return "step out of range";
  if (m.device_kind < 1 || m.device_kind > static_cast<std::int8_t>(std::variant_size_v<InputPayload>))
    return "an input of an unknown kind";
  if (static_cast<std::size_t>(m.n_values) != kValueCount[m.device_kind]) return "a value count that does not fit its kind";
  for (double v : m.values) {
    if (!std::isfinite(v)) return "a value that is not a finite number";
  }
  RecordedInput in;
  in.host_time_us = m.host_time_us;
  in.device_time_us = m.device_time_us;
  in.step = m.step;
  in.device_id = m.device_id;
  in.channel = m.channel;
  in.sequence = m.sequence;
  in.what = payload_of_code(m.device_kind);
  Reader r{m.values.data()};
  std::visit(r, in.what);
  if (r.why) return r.why;
  if (const auto* end = std::get_if<SessionEnd>(&in.what); end && end->steps_run != in.step + 1)
    return "a session-end marker whose step count is not its own step + 1";
  out = in;
  return nullptr;
}

bool operator==(const RecordedInput& a, const RecordedInput& b) noexcept {
  if (a.host_time_us != b.host_time_us || a.device_time_us != b.device_time_us || a.step != b.step ||
      a.device_id != b.device_id || a.channel != b.channel || a.sequence != b.sequence || a.what.index() != b.what.index())
    return false;
  // Bit patterns of the wire values, not values: NaN == NaN, -0 != +0.
  double va[kMaxInputValues], vb[kMaxInputValues];
  const std::size_t na = input_values(a.what, va), nb = input_values(b.what, vb);
  return na == nb && std::memcmp(va, vb, sizeof(double) * na) == 0;
}

}  // namespace vitreo::telemetry
