// A technician's calibration script (rig/session/technician_script.hpp): the shipped one resolves
// into every step the simulated calibration rig needs, each window inside the hold the script
// wrote, with the tip at the fixture's landmark meanwhile (read back through the emulator's own
// parser and interpolation, not through the resolver); malformed or mismatched scripts are refused
// with FILE:LINE: KEY.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "drivers/sim/emulator.hpp"
#include "rig/session/technician_script.hpp"

namespace vitreo::rig {
namespace {

using calibration::ProcedureStep;
using calibration::StepKind;

const std::string kSource = VITREO_SOURCE_DIR;
const TechnicianDevices kRig{{{"tracker-0", 0}}, "pedals", "eyeball"};

std::vector<ProcedureStep> planned() { return calibration::plan_steps(calibration::default_fixture(), kRig.trackers, kRig.pedals, kRig.eyeball); }

calibration::Procedure resolve_text(const std::string& text, const TechnicianDevices& rig = kRig) {
  return resolve_technician_script(parse_surgical_script(text, "t.toml"), calibration::default_fixture(), rig,
                                   calibration::plan_steps(calibration::default_fixture(), rig.trackers, rig.pedals, rig.eyeball));
}

std::string technician_error_of(const std::string& text, const TechnicianDevices& rig = kRig) {
  try {
    (void)resolve_text(text, rig);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

// The emulator's keyframes, interpolated the way the emulator plays them (linear between keys).
std::vector<double> played_at(const drivers::sim::Script& s, double t_s) {
  const auto t = static_cast<std::uint64_t>(std::llround(t_s * 1e6));
  for (std::size_t i = 1; i < s.keys.size(); ++i) {
    if (s.keys[i].first < t) continue;
    const auto& [t0, a] = s.keys[i - 1];
    const auto& [t1, b] = s.keys[i];
    const double f = t1 > t0 ? static_cast<double>(t - t0) / static_cast<double>(t1 - t0) : 1.0;
    std::vector<double> v(a.size());
    for (std::size_t k = 0; k < a.size(); ++k) v[k] = a[k] + f * (b[k] - a[k]);
    return v;
  }
  return s.keys.back().second;
}

drivers::sim::Script emulator_script(const std::string& device_line, const std::string& keys) {
  drivers::sim::Script s;
  std::string error;
  EXPECT_TRUE(drivers::sim::parse_script(device_line + "loop 0\n" + keys, s, &error)) << error;
  return s;
}

TEST(TechnicianScript, TheShippedOneDoesEveryStepWithTheTipWhereTheFixtureSaysMeanwhile) {
  const calibration::Fixture f = calibration::default_fixture();
  const calibration::Procedure p = resolve_technician_script(read_surgical_script(kSource + "/rig/config/sim-calibration.technician.toml"), f, kRig, planned());
  EXPECT_TRUE(calibration::missing_steps(planned(), p.steps).empty());
  EXPECT_EQ(p.steps.size(), planned().size());
  const drivers::sim::Script tracker = emulator_script("device tracker\n", p.motion.at("tracker-0"));
  const drivers::sim::Script pedals = emulator_script("device pedals\n", p.motion.at("pedals"));
  ASSERT_TRUE(p.motion.count("eyeball"));
  double last_start = -1.0;
  for (const ProcedureStep& s : p.steps) {
    EXPECT_LT(s.start_s, s.end_s) << s.instruction;
    EXPECT_LE(s.end_s, p.duration_s) << s.instruction;
    if (s.kind == StepKind::clock) {
      EXPECT_EQ(s.start_s, 0.0);
      EXPECT_EQ(s.end_s, p.duration_s);
      continue;
    }
    EXPECT_GE(s.start_s, last_start) << "in the order they happen";
    last_start = s.start_s;
    // Sample the window: the tip stays on its landmark (and, pivoting, the shaft swings about it).
    auto tip_at = [&](double t) {
      const std::vector<double> v = played_at(tracker, t);
      return core::Vec3(v[0], v[1], v[2]);
    };
    const core::Vec3 landmark = s.kind == StepKind::fiducial ? f.fiducials_mm[static_cast<std::size_t>(s.index)]
                                : s.kind == StepKind::port   ? f.ports_mm[static_cast<std::size_t>(s.index)]
                                : s.kind == StepKind::pivot  ? f.divot_mm
                                                             : f.rest_mm;
    for (double t = s.start_s; t <= s.end_s; t += 0.01) EXPECT_LT((tip_at(t) - landmark).norm(), 1e-3) << s.instruction << " at " << t << " s";
    if (s.kind == StepKind::pivot) {
      double min_tilt = 1e9, max_tilt = 0;
      for (double t = s.start_s; t <= s.end_s; t += 0.01) {
        const std::vector<double> v = played_at(tracker, t);
        const double tilt = std::hypot(v[4], v[5]);
        min_tilt = std::min(min_tilt, tilt), max_tilt = std::max(max_tilt, tilt);
      }
      EXPECT_GT(max_tilt, 25.0) << "the handle swings out to nearly 28°";
      EXPECT_LT(min_tilt, 15.0);
    }
    if (s.kind == StepKind::pedal_travel) {
      double peak = 0.0, other = 0.0;
      for (double t = s.start_s; t <= s.end_s; t += 0.01) {
        const std::vector<double> v = played_at(pedals, t);
        peak = std::max(peak, v[static_cast<std::size_t>(s.index)]);
        other = std::max(other, v[static_cast<std::size_t>(1 - s.index)]);
      }
      EXPECT_DOUBLE_EQ(peak, 1.0) << "pressed all the way during the window";
      EXPECT_EQ(other, 0.0) << "and only that axis";
      EXPECT_EQ(played_at(pedals, s.start_s)[static_cast<std::size_t>(s.index)], 0.0) << "from rest";
      EXPECT_EQ(played_at(pedals, s.end_s)[static_cast<std::size_t>(s.index)], 0.0) << "back to rest";
    }
    if (s.kind == StepKind::pedal_rest || s.kind == StepKind::eye_zero) {
      for (double t = s.start_s; t <= s.end_s; t += 0.01) EXPECT_EQ(played_at(pedals, t)[0] + played_at(pedals, t)[1], 0.0);
    }
  }
}

const char* kTechnicianHead = "[script]\nversion = 1\nkind = \"calibration\"\n[[hand]]\ntracker = 0\n";

TEST(TechnicianScript, MismatchedOrMalformedScriptsAreRefusedWithFileLineAndKey) {
  // Surgeon's keys in a technician's script and the other way round; a case or a length.
  EXPECT_EQ(technician_error_of(std::string(kTechnicianHead) + "[[hand.waypoint]]\nto = \"divot\"\nabove_mm = 1.0\n"),
            "t.toml:8: hand[0].waypoint[0].above_mm: not in a calibration script (no case, no port, no tool; the pedals are pressed by "
            "`records = \"pedal_travel.AXIS\"`)");
  EXPECT_NE(technician_error_of("[script]\nversion = 1\ncase = \"x\"\nkind = \"calibration\"\n").find("t.toml:3: script.case: a calibration script has no case"),
            std::string::npos);
  EXPECT_NE(technician_error_of("[script]\nversion = 1\nkind = \"calibration\"\nduration_s = 3\n").find("t.toml:4: script.duration_s:"), std::string::npos);
  try {
    (void)parse_surgical_script("[script]\nversion = 1\ncase = \"c\"\n[[hand]]\n[[hand.waypoint]]\nto = \"fovea\"\nrecords = \"pivot\"\n", "s.toml");
    ADD_FAILURE() << "a surgeon's script took `records`";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "s.toml:7: hand[0].waypoint[0].records: only in calibration scripts (kind = \"calibration\")");
  }
  // Landmarks and steps the fixture or the rig lacks, or recorded where they cannot be.
  EXPECT_EQ(technician_error_of(std::string(kTechnicianHead) + "[[hand.waypoint]]\nto = \"fiducial.9\"\n"),
            "t.toml:7: hand[0].waypoint[0].to: the fixture's fiducials are fiducial.1 … fiducial.8");
  EXPECT_EQ(technician_error_of(std::string(kTechnicianHead) + "[[hand.waypoint]]\nto = \"fovea\"\n"),
            "t.toml:7: hand[0].waypoint[0].to: unknown landmark 'fovea' (rest, divot, fiducial.N, port.N: a calibration script's are the fixture's)");
  EXPECT_EQ(technician_error_of(std::string(kTechnicianHead) + "[[hand.waypoint]]\nto = \"port.1\"\nhold_s = 1\nrecords = \"fiducial\"\n"),
            "t.toml:9: hand[0].waypoint[0].records: a fiducial is recorded at fiducial.N, not at port.1");
  EXPECT_EQ(technician_error_of(std::string(kTechnicianHead) + "[[hand.waypoint]]\nto = \"divot\"\nhold_s = 1\nrecords = \"pivot\"\n"),
            "t.toml:9: hand[0].waypoint[0].records: a pivot needs swing_deg = [from, to]: the handle swung about the tip");
  EXPECT_EQ(technician_error_of(std::string(kTechnicianHead) + "[[hand.waypoint]]\nto = \"fiducial.2\"\nhold_s = 1\nrecords = \"fiducial\"\n"
                                          "[[hand.waypoint]]\nto = \"fiducial.2\"\nhold_s = 1\nrecords = \"fiducial\"\n"),
            "t.toml:13: hand[0].waypoint[1].records: recorded twice: touch fiducial 2 of 8 and hold still");
  EXPECT_EQ(technician_error_of(std::string(kTechnicianHead) + "[[hand.waypoint]]\nto = \"rest\"\nhold_s = 1\nrecords = \"pedal_rest\"\n", {{{"tracker-0", 0}}, "", ""}),
            "t.toml:9: hand[0].waypoint[0].records: the rig has no pedals");
  EXPECT_EQ(technician_error_of(std::string(kTechnicianHead) + "[[hand.waypoint]]\nto = \"rest\"\nhold_s = 1\nrecords = \"pedal_travel.2\"\n"),
            "t.toml:9: hand[0].waypoint[0].records: the pedal's axes are pedal_travel.0 (down) and pedal_travel.1 (sideways)");
  EXPECT_EQ(technician_error_of(std::string(kTechnicianHead) + "[[hand.waypoint]]\nto = \"fiducial.1\"\nhold_s = 0.2\nrecords = \"fiducial\"\n").substr(0, 45),
            "t.toml:9: hand[0].waypoint[0].records: a reco");
  EXPECT_EQ(technician_error_of("[script]\nversion = 1\nkind = \"calibration\"\n[[hand]]\ntracker = 1\n[[hand.waypoint]]\nto = \"rest\"\n"),
            "t.toml:4: hand[0].tracker: the rig has no tracker for instrument 1");
  // A surgeon's script is not a technician's, and the other way round.
  EXPECT_NE(technician_error_of("[script]\nversion = 1\ncase = \"c\"\nkind = \"expert\"\n").find("is a surgeon's script"), std::string::npos);
}

TEST(TechnicianScript, ATremblingTechnicianShakesTheTipOnlyWhileHolding) {
  const std::string text = std::string("[script]\nversion = 1\nkind = \"calibration\"\ntremor_mm = 0.2\nseed = 3\n[[hand]]\ntracker = 0\n") +
                           "[[hand.waypoint]]\nto = \"fiducial.3\"\nduration_s = 0.5\nhold_s = 1.0\nrecords = \"fiducial\"\n";
  const calibration::Procedure p = resolve_text(text);
  const drivers::sim::Script tracker = emulator_script("device tracker\n", p.motion.at("tracker-0"));
  const core::Vec3 target = calibration::default_fixture().fiducials_mm[2];
  double sq = 0.0;
  int n = 0;
  for (double t = 0.6; t < 1.4; t += 0.05, ++n) {
    const std::vector<double> v = tracker.keys.empty() ? std::vector<double>{} : played_at(tracker, t);
    sq += (core::Vec3(v[0], v[1], v[2]) - target).squaredNorm();
  }
  const double rms = std::sqrt(sq / n);
  EXPECT_GT(rms, 0.2) << "three axes of 0.2 mm";
  EXPECT_LT(rms, 0.6);
  // The same seed trembles the same way.
  EXPECT_EQ(resolve_text(text).motion.at("tracker-0"), p.motion.at("tracker-0"));
}

}  // namespace
}  // namespace vitreo::rig
