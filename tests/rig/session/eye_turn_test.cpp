// The surgeon turning the eye (issue 15: scripts turn the eyeball fixture). Two halves of one path:
// - a script's [[eye]] turns resolve into the eyeball fixture's keys, and the hands' tracker keys turn
//   with the eye, so a tip held over a landmark stays over it in the eye frame while the eye turns;
// - the rig maps a tracked tip through the port where the turned eye carries it, so the core gets the
//   tip where the tracker saw it and a shaft that passes through the eye's own cannula.
// The rotation is built here from the fixture's angles by the closed-form yaw–pitch quaternion
// (PROTOCOL.md's Z-then-Y order), not by the code under test.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "drivers/sim/emulator.hpp"
#include "rig/session/surgical_script.hpp"
#include "tests/rig/session/model_inputs.hpp"

using namespace vitreo;

namespace {

// The fixture's orientation for yaw (about z) then pitch (about y), roll 0.
core::Quat yaw_pitch(double yaw_deg, double pitch_deg) {
  const double y = 0.5 * yaw_deg * std::numbers::pi / 180.0, p = 0.5 * pitch_deg * std::numbers::pi / 180.0;
  return core::Quat(std::cos(y) * std::cos(p), -std::sin(y) * std::sin(p), std::cos(y) * std::sin(p), std::sin(y) * std::cos(p));
}

core::Vec3 key_tip(const std::pair<std::uint64_t, std::vector<double>>& k) { return {k.second[0], k.second[1], k.second[2]}; }

TEST(EyeTurn, TheHandsTurnWithTheEyeAndTheFixturePlaysTheTurn) {
  rig::SimulationModel model(test::light_case("exercise_pull_tissue.toml"));
  const rig::PreparedCase& c = model.current_case();
  const std::string text =
      "[script]\nversion = 1\ncase = \"exercise_pull_tissue\"\nduration_s = 5.0\n"
      "[[hand]]\nspeed_mm_s = 20.0\n[[hand.waypoint]]\nto = \"port\"\nabove_mm = 3.0\n"
      "[[hand.waypoint]]\nto = \"fovea\"\nabove_mm = 1.0\nhold_s = 3.0\n"
      "[[eye]]\nat_s = 2.0\nduration_s = 1.0\nyaw_deg = 10.0\npitch_deg = -5.0\n";
  const rig::ResolvedScript r = rig::resolve_script(rig::parse_surgical_script(text, "eye.toml"), c, rig::PedalMapping{});
  drivers::sim::Script eye, hand;
  std::string err;
  ASSERT_TRUE(drivers::sim::parse_script(r.device_scripts.at("eyeball"), eye, &err)) << err;
  ASSERT_TRUE(drivers::sim::parse_script(r.device_scripts.at("tracker-0"), hand, &err)) << err;
  // The fixture: at rest until 2 s, turned by 3 s, and held there to the end.
  auto eye_at = [&](double t_s) {
    for (std::size_t k = 1; k < eye.keys.size(); ++k) {
      const double t0 = eye.keys[k - 1].first * 1e-6, t1 = eye.keys[k].first * 1e-6;
      if (t_s <= t1) {
        const double f = t1 > t0 ? (t_s - t0) / (t1 - t0) : 1.0;
        return std::pair{eye.keys[k - 1].second[0] + f * (eye.keys[k].second[0] - eye.keys[k - 1].second[0]),
                         eye.keys[k - 1].second[1] + f * (eye.keys[k].second[1] - eye.keys[k - 1].second[1])};
      }
    }
    return std::pair{eye.keys.back().second[0], eye.keys.back().second[1]};
  };
  EXPECT_EQ(eye_at(1.9), (std::pair{0.0, 0.0}));
  EXPECT_NEAR(eye_at(2.5).first, 5.0, 1e-9);
  EXPECT_NEAR(eye_at(2.5).second, -2.5, 1e-9);
  EXPECT_NEAR(eye_at(4.9).first, 10.0, 1e-9);
  EXPECT_NEAR(eye_at(4.9).second, -5.0, 1e-9);
  EXPECT_GE(eye.keys.back().first * 1e-6, 5.0) << "the fixture plays to the end of the script";

  // Every hand key once the tip has arrived: turned back into the eye frame by the fixture's reading
  // at its time, it is 1 mm over the fovea — the tip stays on its landmark while the eye turns.
  const core::Scene& scene = *c.scene;
  const core::Vec3 over_fovea = scene.eye.fovea_mm + 1.0 * (scene.eye.wall.center() - scene.eye.fovea_mm).normalized();
  int held = 0, while_turning = 0;
  for (const auto& k : hand.keys) {
    const double t = k.first * 1e-6;
    if (t < 1.6) continue;  // still on its way in (the fovea is ~20 mm from the port at 20 mm/s)
    const auto [yaw, pitch] = eye_at(t);
    const core::Vec3 in_eye = yaw_pitch(yaw, pitch).conjugate() * key_tip(k);
    EXPECT_LT((in_eye - over_fovea).norm(), 1e-3) << "at " << t << " s";
    ++held;
    while_turning += t > 2.0 && t < 3.0;
  }
  EXPECT_GE(while_turning, 18) << "keys at 20 Hz through the turn, so the tracker's straight lines between keys stay on the turn";
  EXPECT_GT(held, while_turning);
  // In the rig frame the tip has moved: 10° of yaw carries a point ~10 mm from the axis ~1.7 mm.
  EXPECT_GT((key_tip(hand.keys.back()) - over_fovea).norm(), 0.5);
}

TEST(EyeTurn, MalformedTurnsAreRefusedWithFileLineAndKey) {
  const std::string head = "[script]\nversion = 1\ncase = \"exercise_pull_tissue\"\nduration_s = 5.0\n";
  auto error_of = [](const std::string& text) {
    try {
      (void)rig::parse_surgical_script(text, "s.toml");
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string overlap = head + "[[eye]]\nat_s = 1.0\nduration_s = 2.0\nyaw_deg = 5\n[[eye]]\nat_s = 2.0\nyaw_deg = 0\n";
  EXPECT_NE(error_of(overlap).find("s.toml:10: eye[1].at_s: the eye is still turning then (the turn before ends at 3.000 s)"), std::string::npos)
      << error_of(overlap);
  EXPECT_NE(error_of(head + "[[eye]]\nat_s = 1.0\nyaw_deg = 40\n").find("eye[0].yaw_deg: 40"), std::string::npos)
      << error_of(head + "[[eye]]\nat_s = 1.0\nyaw_deg = 40\n");
  EXPECT_NE(error_of(head + "[[eye]]\nyaw_deg = 4\n").find("eye[0].at_s: missing"), std::string::npos);
  EXPECT_NE(error_of(head + "[[eye]]\nat_s = 1\nroll_deg = 4\n").find("s.toml:7: eye[0].roll_deg: unknown key"), std::string::npos)
      << error_of(head + "[[eye]]\nat_s = 1\nroll_deg = 4\n");
  EXPECT_NE(error_of("eye = 3\n" + head).find("s.toml:1: eye: must be [[eye]] tables"), std::string::npos) << error_of("eye = 3\n" + head);
}

TEST(EyeTurn, TheRigMapsATrackedTipThroughThePortTheTurnedEyeCarries) {
  rig::SimulationModel model(test::light_case("exercise_pull_tissue.toml"));
  const rig::PreparedCase& c = model.current_case();
  const core::Vec3 port = c.tracker_ports[rig::kToolTracker].position_mm;
  const core::Vec3 tip_eye = port + 8.0 * (c.focus_mm - port).normalized();  // 8 mm in, aimed at the work
  const core::Quat turned = yaw_pitch(12.0, 6.0);
  telemetry::EyeFixtureSample fixture;
  fixture.q_wxyz = {turned.w(), turned.x(), turned.y(), turned.z()};
  fixture.port_count = 3;
  telemetry::RecordedInput f;
  f.what = fixture;
  ASSERT_TRUE(model.apply(f));
  ASSERT_TRUE(model.apply(test::tracker_sample(turned * tip_eye, 0)));  // where the tracker sees the tip
  model.step();
  const core::InstrumentState& st = model.simulation().instrument(static_cast<std::uint32_t>(model.selected_tool()));
  ASSERT_TRUE(st.inside);
  EXPECT_LT((st.frame.tip - tip_eye).norm(), 1e-6) << "the tip in the eye frame";
  // The shaft passes through the eye's own cannula: the port's distance from the shaft's line.
  const core::Vec3 axis = st.frame.u.normalized();
  const core::Vec3 off = port - st.frame.tip;
  EXPECT_LT((off - off.dot(axis) * axis).norm(), 1e-6) << "the shaft through the port";
  EXPECT_NEAR(st.frame.inserted_mm, 8.0, 1e-6);
}

}  // namespace
