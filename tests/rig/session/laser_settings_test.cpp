// The endolaser's settings through the rig's model into the core: the rig file's start values, the
// laser_power / laser_duration commands as recorded inputs, and shots whose burns are sized by the
// pulse's energy. Independent reference: a pulse's energy is power × duration, and a burn's diameter
// grows as the square root of the energy (the spot's area in proportion to it; core/instruments),
// so twice the power makes a burn √2 times as wide and twice the power for half as long the same.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "firmware-protocol/vp.h"
#include "rig/scene_io/case_loader.hpp"
#include "rig/session/device_inputs.hpp"
#include "rig/session/simulation_model.hpp"

using namespace vitreo;

namespace {

const std::string kScenes = std::string(VITREO_SOURCE_DIR) + "/scenes";

rig::ModelConfig laser_case() {
  rig::ModelConfig m;
  m.cases.push_back(scene_io::read_case_text(kScenes + "/exercise_laser_tear.toml"));
  m.load.retina_vertices = 1500;
  m.load.texture_size_px = 128;
  m.load.cache_dir = (std::filesystem::path(::testing::TempDir()) / "vitreo-laser-settings-cache").string();
  return m;
}

telemetry::DeviceInput command(int code, double value) {
  telemetry::DeviceInput in;
  in.device_kind = rig::kCommandKind;
  in.n_values = 2;
  in.values[0] = code;
  in.values[1] = value;
  return in;
}

// The vitrectomy pedal at rest, with the laser switch (bit 1 by default) held or not.
telemetry::DeviceInput pedal(bool laser) {
  telemetry::DeviceInput in;
  in.device_kind = static_cast<std::int8_t>(rig::InputKind::Pedals);
  in.n_values = 7;
  in.values[0] = 0;  // pedal id: vitrectomy
  in.values[1] = 2;  // axis count
  in.values[6] = laser ? 1u << rig::PedalMapping{}.laser_switch : 0u;
  return in;
}

// The endolaser 4 mm into its port, aimed at the case's region of interest.
void hold_the_laser(rig::SimulationModel& model) {
  const rig::PreparedCase& c = model.current_case();
  const core::Vec3 port = c.tracker_ports[rig::kToolTracker].position_mm;
  const core::Vec3 tip = port + 4.0 * (c.focus_mm - port).normalized();
  telemetry::DeviceInput in;
  in.device_kind = static_cast<std::int8_t>(rig::InputKind::Tracker);
  in.n_values = 11;
  in.values[0] = tip.x();
  in.values[1] = tip.y();
  in.values[2] = tip.z();
  in.values[3] = 1.0;  // q w
  in.values[8] = 1.0;  // quality
  in.values[9] = 0.0;  // the working hand
  in.values[10] = VP_TOOL_LASER;
  ASSERT_TRUE(model.apply(in));
}

// One shot: the laser switch pressed for a step and released. Returns the burn it made.
core::BurnSpot shoot(rig::SimulationModel& model) {
  const std::size_t before = model.simulation().burns().size();
  hold_the_laser(model);
  EXPECT_TRUE(model.apply(pedal(true)));
  model.step();
  EXPECT_TRUE(model.apply(pedal(false)));
  model.step();
  EXPECT_EQ(model.simulation().burns().size(), before + 1) << "one shot, one burn";
  return model.simulation().burns().empty() ? core::BurnSpot{} : model.simulation().burns().back();
}

TEST(LaserSettings, CommandsSetTheShotsAndTheBurnsAreSizedByTheirEnergy) {
  const rig::ModelConfig mc = laser_case();
  rig::SimulationModel model(mc);
  hold_the_laser(model);
  for (int i = 0; i < 5; ++i) model.step();
  const core::BurnSpot first = shoot(model);
  EXPECT_EQ(first.power_mw, 200.0) << "the console's default";
  EXPECT_DOUBLE_EQ(first.duration_s, 0.1);
  ASSERT_GT(first.diameter_mm, 0.0);

  ASSERT_TRUE(model.apply(command(15, 400.0)));  // laser_power 400
  const core::BurnSpot doubled = shoot(model);
  EXPECT_EQ(doubled.power_mw, 400.0);
  EXPECT_NEAR(doubled.diameter_mm / first.diameter_mm, std::sqrt(2.0), 1e-9) << "twice the energy";

  ASSERT_TRUE(model.apply(command(16, 50.0)));  // laser_duration 50: 400 mW × 50 ms, the first shot's energy
  const core::BurnSpot halved = shoot(model);
  EXPECT_DOUBLE_EQ(halved.duration_s, 0.05);
  EXPECT_NEAR(halved.diameter_mm / first.diameter_mm, 1.0, 1e-9);

  // Out of range (a recording could say so): refused, counted, the settings stay.
  const std::uint64_t refused = model.inputs_refused();
  EXPECT_FALSE(model.apply(command(15, 2500.0)));
  EXPECT_FALSE(model.apply(command(16, 0.0)));
  EXPECT_EQ(model.inputs_refused(), refused + 2);
  EXPECT_EQ(model.laser().power_mw, 400.0);
  EXPECT_EQ(model.laser().duration_ms, 50.0);
}

TEST(LaserSettings, TheRigFilesStartValuesFireTheFirstShotAndTravelWithTheRecording) {
  rig::ModelConfig mc = laser_case();
  mc.laser.power_mw = 800.0;
  mc.laser.duration_ms = 100.0;
  rig::SimulationModel model(mc);
  hold_the_laser(model);
  for (int i = 0; i < 5; ++i) model.step();
  const core::BurnSpot shot = shoot(model);
  EXPECT_EQ(shot.power_mw, 800.0);
  rig::SimulationModel plain(laser_case());
  hold_the_laser(plain);
  for (int i = 0; i < 5; ++i) plain.step();
  EXPECT_NEAR(shot.diameter_mm / shoot(plain).diameter_mm, 2.0, 1e-9) << "4× the energy: twice the diameter";

  // The recording's case list carries them, and a list without them means the defaults.
  rig::ModelConfig replayed;
  rig::decode_case_list(rig::encode_case_list(mc), replayed);
  EXPECT_EQ(replayed.laser.power_mw, 800.0);
  EXPECT_EQ(replayed.laser.duration_ms, 100.0);
  replayed.laser.duration_ms = 123.456789012345678;
  rig::ModelConfig again;
  again.laser.power_mw = 1000.0;  // not what the recording says: replaced
  rig::decode_case_list(rig::encode_case_list(replayed), again);
  EXPECT_EQ(again.laser.duration_ms, 123.456789012345678) << "bit for bit";
  EXPECT_EQ(again.laser.power_mw, 800.0);
  rig::ModelConfig defaults;
  defaults.laser.power_mw = 1000.0;
  rig::decode_case_list(rig::encode_case_list(laser_case()), defaults);
  EXPECT_EQ(defaults.laser.power_mw, 200.0);
  EXPECT_EQ(rig::encode_case_list(laser_case()).find("\nlaser_power_mw"), std::string::npos) << "older recordings' header unchanged";
  // A damaged value is refused as a corruption.
  std::string text = rig::encode_case_list(mc);
  text.replace(text.find("\nlaser_power_mw 800\n"), 20, "\nlaser_power_mw 9e9\n");
  rig::ModelConfig bad;
  EXPECT_THROW(rig::decode_case_list(text, bad), std::runtime_error);
}

}  // namespace
