// Recorded inputs as the rig's devices and operator would give them, for tests that drive a
// rig::SimulationModel directly (device_inputs.hpp's layouts), and a shipped case made light.
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
inline telemetry::DeviceInput tracker_sample(const core::Vec3& tip, double tool_type, int instrument_id = rig::kToolTracker) {
  telemetry::DeviceInput in;
  in.device_kind = static_cast<std::int8_t>(rig::InputKind::Tracker);
  in.n_values = 11;
  in.values[0] = tip.x();
  in.values[1] = tip.y();
  in.values[2] = tip.z();
  in.values[3] = 1.0;  // q w
  in.values[8] = 1.0;  // quality
  in.values[9] = instrument_id;
  in.values[10] = tool_type;
  return in;
}

// The vitrectomy pedal at rest with these switches held.
inline telemetry::DeviceInput pedal_switches(unsigned switches) {
  telemetry::DeviceInput in;
  in.device_kind = static_cast<std::int8_t>(rig::InputKind::Pedals);
  in.n_values = 7;
  in.values[0] = 0;  // pedal id: vitrectomy
  in.values[1] = 2;  // axis count
  in.values[6] = switches;
  return in;
}

// An accepted operator command (telemetry::CommandCode) as physics records it.
inline telemetry::DeviceInput operator_command(int code, double value) {
  telemetry::DeviceInput in;
  in.device_kind = rig::kCommandKind;
  in.n_values = 2;
  in.values[0] = code;
  in.values[1] = value;
  return in;
}

}  // namespace vitreo::test
