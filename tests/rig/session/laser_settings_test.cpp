// The endolaser's settings through the rig's model into the core: the rig file's start values, the
// laser_power / laser_duration commands as recorded inputs, and shots whose burns are sized by the
// pulse's energy. Independent reference: a pulse's energy is power × duration, and a burn's diameter
// grows as the square root of the energy (the spot's area in proportion to it; core/instruments),
// so twice the power makes a burn √2 times as wide and twice the power for half as long the same.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "firmware-protocol/vp.h"
#include "tests/rig/session/model_inputs.hpp"

using namespace vitreo;

namespace {

rig::ModelConfig laser_case() { return test::light_case("exercise_laser_tear.toml"); }

telemetry::RecordedInput pedal(bool laser) { return test::pedal_switches(laser ? 1u << rig::PedalMapping{}.laser_switch : 0u); }

// The endolaser 4 mm into its port, aimed at the case's region of interest.
void hold_the_laser(rig::SimulationModel& model) {
  const rig::PreparedCase& c = model.current_case();
  const core::Vec3 port = c.tracker_ports[rig::kToolTracker].position_mm;
  const core::Vec3 tip = port + 4.0 * (c.focus_mm - port).normalized();
  ASSERT_TRUE(model.apply(test::tracker_sample(tip, VP_TOOL_LASER)));
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

  ASSERT_TRUE(model.apply(test::operator_command(15, 400.0)));  // laser_power 400
  const core::BurnSpot doubled = shoot(model);
  EXPECT_EQ(doubled.power_mw, 400.0);
  EXPECT_NEAR(doubled.diameter_mm / first.diameter_mm, std::sqrt(2.0), 1e-9) << "twice the energy";

  ASSERT_TRUE(model.apply(test::operator_command(16, 50.0)));  // laser_duration 50: 400 mW × 50 ms, the first shot's energy
  const core::BurnSpot halved = shoot(model);
  EXPECT_DOUBLE_EQ(halved.duration_s, 0.05);
  EXPECT_NEAR(halved.diameter_mm / first.diameter_mm, 1.0, 1e-9);

  // Out of range (a recording could say so): refused, counted, the settings stay.
  const std::uint64_t refused = model.inputs_refused();
  EXPECT_FALSE(model.apply(test::operator_command(15, 2500.0)));
  EXPECT_FALSE(model.apply(test::operator_command(16, 0.0)));
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
