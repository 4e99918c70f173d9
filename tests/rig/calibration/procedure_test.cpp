// The procedure's analysis on what a run recorded: nothing, or a recording cut short, fails every
// step that lacks its samples by name and fills in nothing it could not measure.
#include "rig/calibration/procedure.hpp"

#include <gtest/gtest.h>

namespace vitreo::rig::calibration {
namespace {

TEST(Procedure, PlansEveryStepOnOneTimeline) {
  const Procedure p = plan_procedure(default_fixture(), {{"tracker-0", 0}}, "pedals", "eyeball");
  int fiducials = 0, ports = 0, clocks = 0;
  for (const ProcedureStep& s : p.steps) {
    fiducials += s.kind == StepKind::fiducial;
    ports += s.kind == StepKind::port;
    clocks += s.kind == StepKind::clock;
    EXPECT_LT(s.start_s, s.end_s);
    EXPECT_LE(s.end_s, p.duration_s);
  }
  EXPECT_EQ(fiducials, 8);
  EXPECT_EQ(ports, 2);
  EXPECT_EQ(clocks, 3);
  EXPECT_EQ(p.motion.size(), 3u);
  EXPECT_NE(p.motion.at("tracker-0").find("key "), std::string::npos);
}

TEST(Procedure, AnEmptyRecordingFailsEveryStepAndCalibratesNothing) {
  const Fixture f = default_fixture();
  const Procedure p = plan_procedure(f, {{"tracker-0", 0}}, "pedals", "eyeball");
  const Analysis a = analyse(p, f, Recording{});
  EXPECT_FALSE(a.ok);
  EXPECT_EQ(a.steps.size(), p.steps.size());
  for (const StepOutcome& o : a.steps) EXPECT_FALSE(o.ok) << o.step->instruction;
  EXPECT_TRUE(a.file.instruments.empty());
  EXPECT_FALSE(a.file.registration);
  EXPECT_TRUE(a.file.pedals.empty());
  EXPECT_FALSE(a.file.eye_zero);
  bool names_pivot = false;
  for (const std::string& e : a.errors) names_pivot = names_pivot || e.find("tracker-0: rest the tip") != std::string::npos;
  EXPECT_TRUE(names_pivot);
  EXPECT_NE(summary_text(a).find("result: FAIL"), std::string::npos);
}

}  // namespace
}  // namespace vitreo::rig::calibration
