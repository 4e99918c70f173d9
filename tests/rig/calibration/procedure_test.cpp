// The procedure's analysis on what a run recorded: nothing, or a recording cut short, fails every
// step that lacks its samples by name and fills in nothing it could not measure.
#include "rig/calibration/procedure.hpp"

#include <gtest/gtest.h>

namespace vitreo::rig::calibration {
namespace {

TEST(Procedure, PlansEveryStepTheRigsDevicesNeed) {
  const std::vector<ProcedureStep> p = plan_steps(default_fixture(), {{"tracker-0", 0}}, "pedals", "eyeball");
  int pivots = 0, fiducials = 0, ports = 0, travels = 0, rests = 0, eyes = 0, clocks = 0;
  for (const ProcedureStep& s : p) {
    pivots += s.kind == StepKind::pivot;
    fiducials += s.kind == StepKind::fiducial;
    ports += s.kind == StepKind::port;
    travels += s.kind == StepKind::pedal_travel;
    rests += s.kind == StepKind::pedal_rest;
    eyes += s.kind == StepKind::eye_zero;
    clocks += s.kind == StepKind::clock;
    EXPECT_FALSE(s.instruction.empty());
  }
  EXPECT_EQ(pivots, 1);
  EXPECT_EQ(fiducials, 8);
  EXPECT_EQ(ports, 2);
  EXPECT_EQ(travels, 2);
  EXPECT_EQ(rests, 1);
  EXPECT_EQ(eyes, 1);
  EXPECT_EQ(clocks, 3);
  // A second tracker pivots too, but only the first touches the fiducials and ports.
  const std::vector<ProcedureStep> two = plan_steps(default_fixture(), {{"tracker-0", 0}, {"tracker-1", 1}}, "", "");
  int pivots2 = 0, touches_by_second = 0;
  for (const ProcedureStep& s : two) {
    pivots2 += s.kind == StepKind::pivot;
    touches_by_second += s.device == "tracker-1" && (s.kind == StepKind::fiducial || s.kind == StepKind::port);
  }
  EXPECT_EQ(pivots2, 2);
  EXPECT_EQ(touches_by_second, 0);
  // What a run lacks is named by device and instruction.
  std::vector<ProcedureStep> done(p.begin(), p.end());
  done.erase(done.begin() + 2);
  const std::vector<std::string> missing = missing_steps(p, done);
  ASSERT_EQ(missing.size(), 1u);
  EXPECT_EQ(missing[0], p[2].device + ": " + p[2].instruction);
}

TEST(Procedure, AnEmptyRecordingFailsEveryStepAndCalibratesNothing) {
  const Fixture f = default_fixture();
  Procedure p;
  p.steps = plan_steps(f, {{"tracker-0", 0}}, "pedals", "eyeball");
  for (ProcedureStep& s : p.steps) s.end_s = 10.0;
  p.duration_s = 10.0;
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
