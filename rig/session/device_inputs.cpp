#include "rig/session/device_inputs.hpp"

#include <type_traits>
#include <variant>

namespace vitreo::rig {

namespace {

template <std::size_t N>
std::array<double, N> widened(const std::array<float, N>& a) {
  std::array<double, N> out{};
  for (std::size_t i = 0; i < N; ++i) out[i] = a[i];
  return out;
}

}  // namespace

telemetry::RecordedInput encode_sample(const drivers::Sample& sample, std::int32_t device_id, std::int64_t sequence) {
  telemetry::RecordedInput in;
  in.device_id = device_id;
  in.sequence = sequence;
  std::visit(
      [&](const auto& s) {
        using T = std::decay_t<decltype(s)>;
        in.host_time_us = static_cast<std::int64_t>(s.t.host_us);
        in.device_time_us = static_cast<std::int64_t>(s.t.device_us);
        if constexpr (std::is_same_v<T, drivers::PoseSample>) {
          telemetry::TrackerSample r;
          r.tip_mm = widened(s.tip_mm);
          r.q_wxyz = widened(s.q_wxyz);
          r.actuation = s.actuation;
          r.quality = s.quality;
          r.instrument_id = s.instrument_id;
          r.tool_type = s.tool_type;
          in.channel = s.instrument_id;
          in.what = r;
        } else if constexpr (std::is_same_v<T, drivers::PedalSample>) {
          telemetry::PedalSample r;
          r.pedal_id = s.pedal_id;
          r.axis_count = s.axis_count;
          r.axes = widened(s.axes);
          r.switches = s.switches;
          in.channel = s.pedal_id;
          in.what = r;
        } else {
          telemetry::EyeFixtureSample r;
          r.q_wxyz = widened(s.q_wxyz);
          r.port_count = s.port_count;
          r.inserted = s.inserted;  // every port the fixture has, the fourth included
          r.depth_mm = widened(s.depth_mm);
          in.what = r;
        }
      },
      sample);
  return in;
}

TrackedPose tracked_pose(const telemetry::TrackerSample& s) {
  TrackedPose pose;
  pose.tip_mm = core::Vec3(s.tip_mm[0], s.tip_mm[1], s.tip_mm[2]);
  pose.orientation = core::Quat(s.q_wxyz[0], s.q_wxyz[1], s.q_wxyz[2], s.q_wxyz[3]);
  pose.actuation = s.actuation;
  return pose;
}

PedalReading pedal_reading(const telemetry::PedalSample& s) {
  PedalReading p;
  p.pedal_id = s.pedal_id;
  p.axis_count = s.axis_count;
  for (std::size_t i = 0; i < s.axes.size(); ++i) p.axes[i] = s.axes[i];
  p.switches = s.switches;
  return p;
}

core::Quat fixture_orientation(const telemetry::EyeFixtureSample& s) {
  return core::Quat(s.q_wxyz[0], s.q_wxyz[1], s.q_wxyz[2], s.q_wxyz[3]);
}

}  // namespace vitreo::rig
