// The light pipe's pick on its own pedal switch (rig/input/controls.hpp, pick_switch): held, the
// pick stands out of the light pipe's tip in the core; the laser switch fires the endolaser in the
// working hand and leaves the pick in (it used to share the laser's switch).
#include <gtest/gtest.h>

#include "tests/rig/session/model_inputs.hpp"

using namespace vitreo;

namespace {

telemetry::RecordedInput pedal(unsigned switches) { return test::pedal_switches(switches); }

TEST(PickSwitch, ThePickSwitchPutsTheLightPipesPickOutAndTheLaserSwitchDoesNot) {
  rig::ModelConfig mc = test::light_case("exercise_laser_tear.toml");
  rig::SimulationModel model(mc);
  const int light = model.current_case().second_hand;
  ASSERT_GE(light, 0);
  const auto light_pipe = [&]() -> const core::InstrumentState& { return model.simulation().instrument(static_cast<std::uint32_t>(light)); };
  const auto laser = [&]() -> const core::InstrumentState& { return model.simulation().instrument(0); };
  ASSERT_EQ(laser().description.kind, core::InstrumentKind::kEndolaser);
  model.step();
  const int bare = light_pipe().tip.count;  // the untracked light pipe, 6 mm into its port

  const rig::PedalMapping keys;
  ASSERT_TRUE(model.apply(pedal(1u << keys.pick_switch)));
  model.step();
  EXPECT_TRUE(light_pipe().input.trigger);
  EXPECT_EQ(light_pipe().tip.count, bare + 1) << "the pick stands out of the tip";
  EXPECT_FALSE(laser().input.trigger) << "the pick fires no laser";

  ASSERT_TRUE(model.apply(pedal(1u << keys.laser_switch)));
  model.step();
  EXPECT_FALSE(light_pipe().input.trigger);
  EXPECT_EQ(light_pipe().tip.count, bare) << "a laser shot leaves the pick in";
  EXPECT_TRUE(laser().input.trigger);
}

TEST(PickSwitch, APedalConfigMovesThePickToAnotherSwitch) {
  rig::ModelConfig mc = test::light_case("exercise_laser_tear.toml");
  mc.pedals = rig::parse_pedal_mapping("[pedals]\npick_switch = 7\n", "rig.toml");
  rig::SimulationModel model(mc);
  const auto light = static_cast<std::uint32_t>(model.current_case().second_hand);
  ASSERT_TRUE(model.apply(pedal(1u << 4)));  // the default pick switch: nothing now
  model.step();
  EXPECT_FALSE(model.simulation().instrument(light).input.trigger);
  ASSERT_TRUE(model.apply(pedal(1u << 7)));
  model.step();
  EXPECT_TRUE(model.simulation().instrument(light).input.trigger);
}

}  // namespace
