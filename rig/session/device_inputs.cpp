#include "rig/session/device_inputs.hpp"

#include <type_traits>
#include <variant>

namespace vitreo::rig {

telemetry::DeviceInput encode_sample(const drivers::Sample& sample, std::int32_t device_id, std::int64_t sequence) {
  telemetry::DeviceInput in;
  in.device_id = device_id;
  in.sequence = sequence;
  std::visit(
      [&](const auto& s) {
        using T = std::decay_t<decltype(s)>;
        in.host_time_us = static_cast<std::int64_t>(s.t.host_us);
        in.device_time_us = static_cast<std::int64_t>(s.t.device_us);
        std::uint8_t n = 0;
        auto put = [&](double v) { in.values[n++] = v; };
        if constexpr (std::is_same_v<T, drivers::PoseSample>) {
          in.device_kind = static_cast<std::int8_t>(InputKind::Tracker);
          in.channel = s.instrument_id;
          for (float c : s.tip_mm) put(c);
          for (float c : s.q_wxyz) put(c);
          put(s.actuation);
          put(s.quality);
          put(s.instrument_id);
          put(s.tool_type);
        } else if constexpr (std::is_same_v<T, drivers::PedalSample>) {
          in.device_kind = static_cast<std::int8_t>(InputKind::Pedals);
          in.channel = s.pedal_id;
          put(s.pedal_id);
          put(s.axis_count);
          for (float a : s.axes) put(a);
          put(s.switches);
        } else {
          in.device_kind = static_cast<std::int8_t>(InputKind::Eyeball);
          for (float c : s.q_wxyz) put(c);
          put(s.port_count);
          for (int i = 0; i < 3; ++i) put(s.inserted[static_cast<std::size_t>(i)] ? 1.0 : 0.0);
          for (int i = 0; i < 3; ++i) put(s.depth_mm[static_cast<std::size_t>(i)]);
        }
        in.n_values = n;
      },
      sample);
  return in;
}

bool decode_tracker(const telemetry::DeviceInput& in, DecodedTracker& out) {
  if (in.device_kind != static_cast<std::int8_t>(InputKind::Tracker) || in.n_values < 11) return false;
  const double* v = in.values;
  // The instrument id and tool type are bytes on the wire (a recording could say anything else, and
  // converting a double beyond int's range is undefined).
  if (!(v[9] >= 0.0 && v[9] <= 255.0 && v[10] >= 0.0 && v[10] <= 255.0)) return false;
  out.pose.tip_mm = core::Vec3(v[0], v[1], v[2]);
  out.pose.orientation = core::Quat(v[3], v[4], v[5], v[6]);
  out.pose.actuation = v[7];
  out.quality = v[8];
  out.instrument_id = static_cast<int>(v[9]);
  out.tool_type = static_cast<int>(v[10]);
  return true;
}

bool decode_pedals(const telemetry::DeviceInput& in, PedalReading& out) {
  if (in.device_kind != static_cast<std::int8_t>(InputKind::Pedals) || in.n_values < 7) return false;
  out.pedal_id = static_cast<int>(in.values[0]);
  out.axis_count = static_cast<int>(in.values[1]);
  for (int i = 0; i < 4; ++i) out.axes[i] = in.values[2 + i];
  out.switches = static_cast<std::uint16_t>(in.values[6]);
  return true;
}

bool decode_eyeball(const telemetry::DeviceInput& in, DecodedEyeball& out) {
  if (in.device_kind != static_cast<std::int8_t>(InputKind::Eyeball) || in.n_values < 11) return false;
  out.orientation = core::Quat(in.values[0], in.values[1], in.values[2], in.values[3]);
  out.port_count = static_cast<int>(in.values[4]);
  for (int i = 0; i < 3; ++i) {
    out.inserted[i] = in.values[5 + i] != 0.0;
    out.depth_mm[i] = in.values[8 + i];
  }
  return true;
}

}  // namespace vitreo::rig
