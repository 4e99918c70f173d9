// The tracker's tool type (firmware-protocol/PROTOCOL.md, POSE_SAMPLE) through the rig's model into
// the core: a handpiece that names the blade puts the case's blade in the working hand, and the
// blade swept across the retina cuts it; the same sweep with a universal handpiece (tool type 0)
// leaves the instrument switch's choice, the forceps, which cuts nothing.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "core/instruments/instrument.hpp"
#include "firmware-protocol/vp.h"
#include "tests/rig/session/model_inputs.hpp"

using namespace vitreo;

namespace {

// exercise_pull_tissue offering a blade and a sideways blade after its forceps and pick, lightened.
rig::ModelConfig blade_case() {
  rig::ModelConfig m = test::light_case("exercise_pull_tissue.toml");
  std::string& text = m.cases[0].text;
  const std::string from = "available = [\"forceps\", \"pick\",";
  const auto at = text.find(from);
  if (at == std::string::npos) throw std::runtime_error("exercise_pull_tissue's instrument list changed");
  text.replace(at, from.size(), "available = [\"forceps\", \"pick\", \"blade\", \"sideways_blade\",");
  return m;
}

// Sweeps the working hand's tip 1.5 mm across the case's region of interest, 0.15 mm into the
// retina, at 15 mm/s; returns the springs the instruments cut.
std::uint32_t sweep_across_the_retina(rig::SimulationModel& model, int tool_type) {
  const rig::PreparedCase& c = model.current_case();
  const core::Vec3 port = c.tracker_ports[rig::kToolTracker].position_mm;
  const core::Vec3 in = (c.focus_mm - port).normalized();
  const core::Vec3 across = in.cross(core::Vec3::UnitZ()).normalized();
  const core::Vec3 centre = c.focus_mm + 0.15 * in;
  const int steps = 100;
  for (int s = 0; s <= steps; ++s) {
    const core::Vec3 tip = centre + (-0.75 + 1.5 * s / steps) * across;
    EXPECT_TRUE(model.apply(test::tracker_sample(tip, tool_type)));
    model.step();
  }
  return c.topology->springs_opened();
}

TEST(ToolType, TheHandpiecesNamesMapToTheCoresKinds) {
  core::InstrumentKind k{};
  ASSERT_TRUE(rig::instrument_kind_of_tool_type(VP_TOOL_BLADE, k));
  EXPECT_EQ(k, core::InstrumentKind::kBlade);
  ASSERT_TRUE(rig::instrument_kind_of_tool_type(VP_TOOL_SIDEWAYS_BLADE, k));
  EXPECT_EQ(k, core::InstrumentKind::kSidewaysBlade);
  ASSERT_TRUE(rig::instrument_kind_of_tool_type(VP_TOOL_FLUTE, k));
  EXPECT_EQ(k, core::InstrumentKind::kDrainageNeedle);
  EXPECT_FALSE(rig::instrument_kind_of_tool_type(VP_TOOL_NONE, k)) << "a universal handpiece names no tool";
  EXPECT_FALSE(rig::instrument_kind_of_tool_type(VP_TOOL_INFUSION, k)) << "the infusion is not held";
  EXPECT_FALSE(rig::instrument_kind_of_tool_type(VP_TOOL_COUNT, k));
  // The scene files' names for the same tools.
  ASSERT_TRUE(rig::instrument_kind("blade", k));
  EXPECT_EQ(k, core::InstrumentKind::kBlade);
  ASSERT_TRUE(rig::instrument_kind("sideways_blade", k));
  EXPECT_EQ(k, core::InstrumentKind::kSidewaysBlade);
}

TEST(ToolType, ABladeNamedByTheHandpieceReachesTheCoreAsABladeAndCuts) {
  const rig::ModelConfig mc = blade_case();
  rig::SimulationModel blade(mc);
  ASSERT_EQ(blade.current_case().tools.size(), 4u);
  EXPECT_EQ(blade.selected_tool(), 0) << "before any sample: the switch's first tool";
  const std::uint32_t blade_cut = sweep_across_the_retina(blade, VP_TOOL_BLADE);
  EXPECT_EQ(blade.selected_tool(), 2);
  const core::InstrumentState& in_hand = blade.simulation().instrument(2);
  EXPECT_EQ(in_hand.description.kind, core::InstrumentKind::kBlade);
  EXPECT_TRUE(in_hand.input.present);
  EXPECT_TRUE(in_hand.inside);
  EXPECT_FALSE(blade.simulation().instrument(0).input.present) << "the forceps stay out";
  EXPECT_GT(blade_cut, 0u) << "the blade's sweep opens the retina";
  RecordProperty("blade_springs_opened", static_cast<int>(blade_cut));

  rig::SimulationModel universal(mc);
  const std::uint32_t forceps_cut = sweep_across_the_retina(universal, VP_TOOL_NONE);
  EXPECT_EQ(universal.selected_tool(), 0);
  EXPECT_EQ(universal.simulation().instrument(0).description.kind, core::InstrumentKind::kForceps);
  EXPECT_TRUE(universal.simulation().instrument(0).input.present);
  EXPECT_EQ(forceps_cut, 0u) << "open forceps pushed across the retina cut nothing";
  EXPECT_NE(universal.state_hash(), blade.state_hash());
}

TEST(ToolType, ASidewaysBladeIsPickedTooAndAToolTheCaseLacksLeavesTheSwitch) {
  const rig::ModelConfig mc = blade_case();
  rig::SimulationModel model(mc);
  const rig::PreparedCase& c = model.current_case();
  const core::Vec3 tip = c.tracker_ports[rig::kToolTracker].position_mm +
                         4.0 * (c.focus_mm - c.tracker_ports[rig::kToolTracker].position_mm).normalized();
  ASSERT_TRUE(model.apply(test::tracker_sample(tip, VP_TOOL_SIDEWAYS_BLADE)));
  model.step();
  EXPECT_EQ(model.selected_tool(), 3);
  EXPECT_EQ(model.simulation().instrument(3).description.kind, core::InstrumentKind::kSidewaysBlade);
  EXPECT_TRUE(model.simulation().instrument(3).input.present);
  ASSERT_TRUE(model.apply(test::tracker_sample(tip, VP_TOOL_VITRECTOR)));  // not offered by this case
  model.step();
  EXPECT_EQ(model.selected_tool(), 0);
  EXPECT_TRUE(model.simulation().instrument(0).input.present);
  EXPECT_FALSE(model.simulation().instrument(3).input.present);
  // A recorded tool type that is no byte never reaches the model: the codec refuses it
  // (tests/rig/telemetry/input_codec_test.cpp).
}

}  // namespace
