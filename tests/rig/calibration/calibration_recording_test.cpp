// A recorded calibration session (rig/calibration/calibration_recording.hpp): what is written reads
// back bit for bit, so the analysis of the file is the analysis of the run; a file of another
// version, a malformed line, a device name with a space are refused with the reason, and a write
// that fails leaves the file already there untouched.
#include "rig/calibration/calibration_recording.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

namespace vitreo::rig::calibration {
namespace {

namespace fs = std::filesystem;

CalibrationSession a_session() {
  CalibrationSession s;
  s.rig = "bench 2 (left)";
  s.procedure.duration_s = 3.25;
  s.procedure.steps = plan_steps(default_fixture(), {{"tracker-0", 0}}, "pedals", "eyeball");
  for (std::size_t i = 0; i < s.procedure.steps.size(); ++i) {
    s.procedure.steps[i].start_s = 0.1 * static_cast<double>(i) + 1.0 / 3.0;
    s.procedure.steps[i].end_s = s.procedure.steps[i].start_s + 0.4;
  }
  s.recording.serials = {{"tracker-0", 1001}, {"pedals", 4000000000u}};
  for (int k = 0; k < 50; ++k) {
    const double t = 0.001 * k + 1e-9;
    s.recording.poses["tracker-0"].push_back(
        {t, core::Vec3(22.0 + std::sin(k) / 3.0, -1.0 / 7.0, 1e-17 * k), core::Quat(Eigen::AngleAxisd(0.01 * k, core::Vec3(1, 2, 3).normalized()))});
    s.recording.pedals["pedals"].push_back({t, 0, {0.07 + k / 9e3, 0.12}});
    s.recording.eyeball["eyeball"].push_back({t, core::Quat(Eigen::AngleAxisd(0.1, core::Vec3::UnitZ()))});
  }
  s.recording.clocks["tracker-0"].push_back({1000, 4127000, 4127001, 1999});
  s.events.push_back("tracker-0: link lost at 2.000 s");
  return s;
}

fs::path temp(const std::string& name) { return fs::temp_directory_path() / ("vitreo-calrec-" + std::to_string(::getpid()) + "-" + name); }

std::string read_error(const std::string& text) {
  try {
    (void)parse_calibration_recording(text, "r.rec");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(CalibrationRecording, ReadsBackBitForBitAndAnalysesTheSame) {
  const CalibrationSession s = a_session();
  const fs::path p = temp("roundtrip");
  write_calibration_recording(p.string(), s);
  const CalibrationSession r = read_calibration_recording(p.string());
  fs::remove(p);
  EXPECT_EQ(r.rig, s.rig);
  EXPECT_EQ(r.procedure.duration_s, s.procedure.duration_s);
  ASSERT_EQ(r.procedure.steps.size(), s.procedure.steps.size());
  for (std::size_t i = 0; i < s.procedure.steps.size(); ++i) {
    EXPECT_TRUE(same_step(r.procedure.steps[i], s.procedure.steps[i]));
    EXPECT_EQ(r.procedure.steps[i].start_s, s.procedure.steps[i].start_s);
    EXPECT_EQ(r.procedure.steps[i].end_s, s.procedure.steps[i].end_s);
    EXPECT_EQ(r.procedure.steps[i].instruction, s.procedure.steps[i].instruction);
  }
  EXPECT_EQ(r.recording.serials, s.recording.serials);
  const auto& a = s.recording.poses.at("tracker-0");
  const auto& b = r.recording.poses.at("tracker-0");
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].t_s, b[i].t_s);
    EXPECT_EQ(a[i].position_mm, b[i].position_mm);
    EXPECT_EQ(a[i].orientation.coeffs(), b[i].orientation.coeffs());
  }
  for (std::size_t i = 0; i < 50; ++i) {
    EXPECT_EQ(r.recording.pedals.at("pedals")[i].axes[0], s.recording.pedals.at("pedals")[i].axes[0]);
    EXPECT_EQ(r.recording.eyeball.at("eyeball")[i].orientation.coeffs(), s.recording.eyeball.at("eyeball")[i].orientation.coeffs());
  }
  ASSERT_EQ(r.recording.clocks.at("tracker-0").size(), 1u);
  EXPECT_EQ(r.recording.clocks.at("tracker-0")[0].device_rx_us, 4127000u);
  EXPECT_EQ(r.events, s.events);
  // The analysis cannot tell them apart.
  EXPECT_EQ(summary_text(analyse(r.procedure, default_fixture(), r.recording)),
            summary_text(analyse(s.procedure, default_fixture(), s.recording)));
}

TEST(CalibrationRecording, OtherVersionsAndMalformedLinesAreRefusedWithTheLine) {
  const std::string head = "vitreo-calibration-recording 1\nduration 2\nstep pivot tracker-0 0 0.1 1 rest the tip\n";
  EXPECT_EQ(read_error("vitreo-calibration-recording 2\n"),
            "r.rec:1: this is a version 2 calibration recording; this vitreo-calibrate reads version 1");
  EXPECT_EQ(read_error("vitreo session 1\n"), "r.rec:1: not a vitreo calibration recording (it starts 'vitreo-calibration-recording VERSION')");
  EXPECT_EQ(read_error(head + "pose tracker-0 0.5 1 2 3 1 0 0\n"), "r.rec:4: 'pose' takes 9 fields, this line has 8");
  EXPECT_EQ(read_error(head + "pose tracker-0 0.5 1 2 nan 1 0 0 0\n"), "r.rec:4: 'nan' is not a finite number");
  EXPECT_EQ(read_error(head + "pose tracker-0 0.5 1 2 3 2 0 0 0\n"), "r.rec:4: the orientation is not a unit quaternion");
  EXPECT_EQ(read_error(head + "pose tracker-0 0.5 1 2 3 1 0 0 0\npose tracker-0 0.4 1 2 3 1 0 0 0\n"),
            "r.rec:5: time 0.400000 s goes back (the previous was 0.500000 s)");
  EXPECT_EQ(read_error(head + "step sideways tracker-0 0 0 1 x\n"), "r.rec:4: unknown step 'sideways'");
  EXPECT_EQ(read_error(head + "sync tracker-0 1 2 -3 4\n"), "r.rec:4: '-3' is not a whole number ≥ 0");
  EXPECT_EQ(read_error(head + "frobnicate 1\n"),
            "r.rec:4: unknown line 'frobnicate' (rig, fixture, duration, serial, step, pose, eye, pedal, sync, event)");
  EXPECT_EQ(read_error("vitreo-calibration-recording 1\nduration 2\n"), "r.rec:2: no 'step' line: nothing to analyse");
  // A recording cut short by a crash while writing cannot happen (atomic write), but a file cut
  // mid-line by other means is still refused at that line.
  EXPECT_EQ(read_error(head + "pose tracker-0 0.5 1 2"), "r.rec:4: 'pose' takes 9 fields, this line has 4");
  EXPECT_EQ(read_error(""), "r.rec:1: empty: not a vitreo calibration recording");
}

TEST(CalibrationRecording, AFailedWriteLeavesThePreviousFile) {
  const fs::path p = temp("keep");
  std::ofstream(p) << "the previous recording\n";
  CalibrationSession s = a_session();
  s.recording.poses["tracker 0"] = s.recording.poses.at("tracker-0");  // a name the format cannot carry
  EXPECT_THROW(write_calibration_recording(p.string(), s), std::runtime_error);
  std::ifstream f(p);
  std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text, "the previous recording\n");
  fs::remove(p);
}

}  // namespace
}  // namespace vitreo::rig::calibration
