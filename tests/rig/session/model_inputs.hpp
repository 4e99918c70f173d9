// Recorded inputs as the rig's devices and operator would give them, for tests that drive a
// rig::SimulationModel directly (typed records, rig/telemetry/input_record.hpp), and a shipped case made light.
#pragma once
#include <cstdint>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "rig/scene_io/case_loader.hpp"
#include "rig/session/device_inputs.hpp"
#include "rig/session/simulation_model.hpp"

namespace vitreo::test {

// A scenes/ case at a light resolution (1500 retina vertices, small textures), cached per test binary.
inline rig::ModelConfig light_case(const std::string& file) {
  rig::ModelConfig m;
  m.cases.push_back(scene_io::read_case_text(std::string(VITREO_SOURCE_DIR) + "/scenes/" + file));
  m.load.retina_vertices = 1500;
  m.load.texture_size_px = 128;
  m.load.cache_dir = (std::filesystem::path(::testing::TempDir()) / "vitreo-model-inputs-cache").string();
  return m;
}

// A tracker's pose sample: the tip (fixture frame, mm), identity orientation, full quality.
inline telemetry::RecordedInput tracker_sample(const core::Vec3& tip, int tool_type, int instrument_id = rig::kToolTracker) {
  telemetry::TrackerSample s;
  s.tip_mm = {tip.x(), tip.y(), tip.z()};
  s.quality = 1.0;
  s.instrument_id = static_cast<std::uint8_t>(instrument_id);
  s.tool_type = static_cast<std::uint8_t>(tool_type);
  telemetry::RecordedInput in;
  in.what = s;
  return in;
}

// The vitrectomy pedal at rest with these switches held.
inline telemetry::RecordedInput pedal_switches(unsigned switches) {
  telemetry::PedalSample s;
  s.pedal_id = 0;  // the vitrectomy pedal
  s.axis_count = 2;
  s.switches = static_cast<std::uint16_t>(switches);
  telemetry::RecordedInput in;
  in.what = s;
  return in;
}

// An accepted operator command (telemetry::CommandCode) as physics records it.
inline telemetry::RecordedInput operator_command(int code, double value) {
  telemetry::OperatorCommand c;
  c.code = static_cast<std::int8_t>(code);
  c.value = value;
  telemetry::RecordedInput in;
  in.what = c;
  return in;
}

}  // namespace vitreo::test
