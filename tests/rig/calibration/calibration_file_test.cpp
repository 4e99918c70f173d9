#include "rig/calibration/calibration_file.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <random>
#include <thread>

namespace vitreo::rig::calibration {
namespace {

// A file as a technician would find it on disk, written out by hand (not by format_calibration),
// so the reader is checked against the documented format rather than against the writer.
const char* const kExample = R"(# a calibration
[calibration]
version = 1
created = 2026-11-26T07:30:00+01:00
tool = "vitreo-calibrate 0.1.0"
rig = "bench 2"

[[device]]
name = "tracker"
serial = 1001

[[device]]
name = "pedals"
serial = 2002

[registration]
rig_to_eye_wxyz = [0.0, 0.0, 0.0, 1.0]
eye_center_in_rig_mm = [10, -20.5, 300]
fiducials = 8
fre_mm = 0.04
tre_mm = 0.06
tre_measured = false

[[instrument]]
instrument = 1
tip_offset_mm = [0.5, -0.25, 14.0]
poses = 412
spread_deg = 38.0
rms_mm = 0.041

[[port]]
port = 0
position_mm = [-9.6, 5.5, 4.6]
outward = [0.0, 0.6, 0.8]
samples = 200
spread_mm = 0.03

[[pedal]]
pedal = 0
axis = 1
lo = 0.07
hi = 0.91
dead_zone = 0.02

[[clock]]
device = "tracker"
offset_ms = -2999987.655
drift_ppm = 80.0
latency_ms = 0.13
rms_ms = 0.004

[eyeball]
zero_wxyz = [0.6, 0.8, 0.0, 0.0]
samples = 1100
spread_deg = 0.04

[eyepieces]
left_offset_px = [0, 0]
right_offset_px = [3.5, -2]
stereo_base_mm = 24
convergence_mm = 0
)";

TEST(CalibrationFile, ReadsTheDocumentedFormat) {
  const CalibrationFile c = parse_calibration(kExample, "x.toml");
  EXPECT_EQ(c.created_unix_s, 1795674600);  // 2026-11-26T06:30:00Z: `date -u -d 2026-11-26T06:30:00Z +%s`
  EXPECT_EQ(c.tool, "vitreo-calibrate 0.1.0");
  EXPECT_EQ(c.rig, "bench 2");
  ASSERT_EQ(c.devices.size(), 2u);
  EXPECT_EQ(c.devices[1].name, "pedals");
  EXPECT_EQ(c.devices[1].serial, 2002u);
  ASSERT_TRUE(c.registration);
  EXPECT_NEAR(c.registration->rig_to_eye.angularDistance(core::Quat(0, 0, 0, 1)), 0.0, 1e-12);
  EXPECT_EQ(c.registration->eye_center_in_rig_mm, core::Vec3(10, -20.5, 300));
  ASSERT_NE(c.instrument(1), nullptr);
  EXPECT_EQ(c.instrument(0), nullptr);
  EXPECT_EQ(c.instrument(1)->tip_offset_mm, core::Vec3(0.5, -0.25, 14.0));
  ASSERT_NE(c.port(0), nullptr);
  EXPECT_EQ(c.port(0)->position_mm, core::Vec3(-9.6, 5.5, 4.6));
  ASSERT_NE(c.pedal(0, 1), nullptr);
  EXPECT_DOUBLE_EQ(c.pedal(0, 1)->range.hi, 0.91);
  ASSERT_EQ(c.clocks.size(), 1u);
  EXPECT_DOUBLE_EQ(c.clocks[0].offset_ms, -2999987.655);
  ASSERT_TRUE(c.eye_zero);
  EXPECT_NEAR(c.eye_zero->zero.angularDistance(core::Quat(0.6, 0.8, 0.0, 0.0)), 0.0, 1e-12);
  EXPECT_EQ(c.eye_zero->samples, 1100u);
}

TEST(CalibrationFile, UtcTimestampsMatchTheCivilCalendar) {
  EXPECT_EQ(utc_timestamp(0), "1970-01-01T00:00:00Z");
  EXPECT_EQ(utc_timestamp(951782400), "2000-02-29T00:00:00Z");  // a leap day of a century leap year
  EXPECT_EQ(utc_timestamp(1795678200), "2026-11-26T07:30:00Z");
}

TEST(CalibrationFile, WritesWhatItReads) {
  CalibrationFile c = parse_calibration(kExample, "x.toml");
  c.registration->rig_to_eye = core::Quat(Eigen::AngleAxisd(0.7, core::Vec3(1, 2, 3).normalized()));
  const CalibrationFile back = parse_calibration(format_calibration(c), "y.toml");
  EXPECT_EQ(back.created_unix_s, c.created_unix_s);
  EXPECT_LT(back.registration->rig_to_eye.angularDistance(c.registration->rig_to_eye), 1e-9);
  EXPECT_LT((back.instrument(1)->tip_offset_mm - c.instrument(1)->tip_offset_mm).norm(), 1e-6);
  EXPECT_LT((back.port(0)->outward - c.port(0)->outward).norm(), 1e-8);
  ASSERT_TRUE(c.eyepieces && back.eyepieces);
  EXPECT_EQ(c.eyepieces->offset_px[1][0], 3.5);
  EXPECT_EQ(c.eyepieces->offset_px[1][1], -2.0);
  EXPECT_EQ(c.eyepieces->stereo_base_mm, 24.0);
  EXPECT_EQ(back.eyepieces->offset_px[1][0], 3.5);
  EXPECT_EQ(back.eyepieces->stereo_base_mm, 24.0);
  EXPECT_EQ(format_calibration(back), format_calibration(c));
}

// Each malformed file names its file, line and key.
struct Bad {
  const char* find;
  const char* replace;
  const char* expect;
};
class Malformed : public ::testing::TestWithParam<Bad> {};
TEST_P(Malformed, IsRejectedWithFileLineAndKey) {
  std::string text = kExample;
  const std::size_t at = text.find(GetParam().find);
  ASSERT_NE(at, std::string::npos);
  text.replace(at, std::strlen(GetParam().find), GetParam().replace);
  try {
    parse_calibration(text, "cal.toml");
    FAIL() << "accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(GetParam().expect), std::string::npos) << e.what();
  }
}
INSTANTIATE_TEST_SUITE_P(
    CalibrationFile, Malformed,
    ::testing::Values(Bad{"version = 1", "version = 2", "cal.toml:3: calibration.version"},
                      Bad{"created = 2026-11-26T07:30:00+01:00", "created = 2026-11-26T07:30:00",
                          "cal.toml:4: calibration.created: must be a date and time with its UTC offset"},
                      Bad{"serial = 2002", "serial = -1", "cal.toml:14: device[1].serial"},
                      Bad{"serial = 2002", "serial = 2002\ncolour = 1", "cal.toml:15: device[1].colour: unknown key"},
                      Bad{"[0.0, 0.0, 0.0, 1.0]", "[0.0, 0.0, 0.5, 1.0]", "cal.toml:17: registration.rig_to_eye_wxyz: must be a unit"},
                      Bad{"fre_mm = 0.04", "fre_mm = \"small\"", "cal.toml:20: registration.fre_mm: must be a number"},
                      Bad{"tip_offset_mm = [0.5, -0.25, 14.0]", "tip_offset_mm = [0.5, 14.0]",
                          "cal.toml:26: instrument[0].tip_offset_mm: must be an array of 3"},
                      Bad{"outward = [0.0, 0.6, 0.8]", "outward = [0.0, 0.6, 0.9]", "cal.toml:34: port[0].outward: must be a unit"},
                      Bad{"hi = 0.91", "hi = 0.05", "cal.toml:42: pedal[0].hi: must be above lo"},
                      Bad{"rms_ms = 0.004", "rms_ms = 0.004\n[extra]", "cal.toml:51: extra: unknown table"},
                      Bad{"rig = \"bench 2\"", "rig = \"bench 2", "cal.toml:6:"},
                      Bad{"name = \"pedals\"", "name = \"tracker\"", "cal.toml:13: device[1].name: 'tracker' is listed twice"},
                      Bad{"[calibration]", "[calibrat]", "cal.toml:1: calibration: no [calibration] table"},
                      Bad{"zero_wxyz = [0.6, 0.8, 0.0, 0.0]", "zero_wxyz = [0.6, 0.6, 0.0, 0.0]", "cal.toml:53: eyeball.zero_wxyz: must be a unit"},
                      Bad{"right_offset_px = [3.5, -2]", "right_offset_px = [3.5, -2, 0]", "cal.toml:59: eyepieces.right_offset_px: must be an array of 2"},
                      Bad{"stereo_base_mm = 24", "stereo_base_mm = 0", "cal.toml:60: eyepieces.stereo_base_mm"},
                      Bad{"convergence_mm = 0", "convergence = 0", "cal.toml:57: eyepieces.convergence_mm: missing"},
                      Bad{"convergence_mm = 0", "convergence_mm = 0\ncolour = 1", "cal.toml:62: eyepieces.colour: unknown key"}));

TEST(CalibrationFile, RefusesOtherDevicesSerials) {
  const CalibrationFile c = parse_calibration(kExample, "x.toml");
  EXPECT_EQ(check_devices(c, {{"tracker", 1001}, {"pedals", 2002}, {"eyeball", 7}}), "");
  const std::string other = check_devices(c, {{"tracker", 1001}, {"pedals", 2003}});
  EXPECT_NE(other.find("made for pedals serial 2002, this rig's pedals is serial 2003"), std::string::npos) << other;
  EXPECT_NE(check_devices(c, {{"tracker", 1001}}).find("'pedals' this rig does not have"), std::string::npos);
}

TEST(CalibrationFile, WarnsWhenOlderThanTheConfiguredAge) {
  const CalibrationFile c = parse_calibration(kExample, "x.toml");
  EXPECT_FALSE(age_warning(c, c.created_unix_s + 29 * 86400, 30.0));
  const auto old = age_warning(c, c.created_unix_s + 31 * 86400, 30.0);
  ASSERT_TRUE(old);
  EXPECT_NE(old->find("31.0 days old (more than 30)"), std::string::npos) << *old;
  EXPECT_TRUE(age_warning(c, c.created_unix_s - 86400, 30.0));  // from the future
}

std::filesystem::path scratch_dir(const std::string& name) {
  const auto d = std::filesystem::temp_directory_path() / ("vitreo-calib-" + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

TEST(CalibrationFile, AKilledWriterNeverLeavesACorruptFile) {
  // A child rewrites the file as fast as it can, alternating two large, different calibrations; we
  // SIGKILL it at random moments. Whatever is left under the name must be one of them, whole.
  const auto dir = scratch_dir("kill");
  const std::string path = (dir / "rig.calibration.toml").string();
  CalibrationFile a = parse_calibration(kExample, "x.toml"), b = a;
  for (int i = 0; i < 2000; ++i) a.ports.push_back({i % 16 == 0 ? 1 : 2, core::Vec3(i * 1e-3, 1, 2), core::Vec3::UnitZ(), 1, 0});
  a.ports.resize(16);
  for (int i = 0; i < 16; ++i) a.ports[static_cast<std::size_t>(i)].port = i;
  b.rig = std::string(40000, 'b');  // a long name: a writer cut short would truncate it
  const std::string text_a = format_calibration(a), text_b = format_calibration(b);
  write_calibration_file(path, a);
  std::mt19937 rng(7);
  int seen_a = 0, seen_b = 0;
  for (int round = 0; round < 25; ++round) {
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      for (int i = 0;; ++i) {
        try {
          write_calibration_file(path, i % 2 ? a : b);
        } catch (...) {
          ::_exit(3);
        }
      }
    }
    std::this_thread::sleep_for(std::chrono::microseconds(std::uniform_int_distribution<int>(200, 5000)(rng)));
    ::kill(child, SIGKILL);
    int status = 0;
    ::waitpid(child, &status, 0);
    ASSERT_TRUE(WIFSIGNALED(status)) << "the writer failed on its own";
    std::ifstream f(path, std::ios::binary);
    const std::string got((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    ASSERT_TRUE(got == text_a || got == text_b) << "round " << round << ": " << got.size() << " bytes";
    (got == text_a ? seen_a : seen_b)++;
    EXPECT_NO_THROW(read_calibration_file(path));
    for (const auto& e : std::filesystem::directory_iterator(dir))  // the killed child's temporary
      if (e.path().string() != path) std::filesystem::remove(e.path());
  }
  EXPECT_GT(seen_a + seen_b, 0);
  std::filesystem::remove_all(dir);
}

TEST(CalibrationFile, AFailedWriteKeepsThePreviousFile) {
  const auto dir = scratch_dir("keep");
  const std::string path = (dir / "cal.toml").string();
  const CalibrationFile c = parse_calibration(kExample, "x.toml");
  write_calibration_file(path, c);
  // A directory where the temporary file must go makes the write fail before anything is renamed.
  std::filesystem::create_directory(path + ".tmp." + std::to_string(::getpid()));
  CalibrationFile other = c;
  other.rig = "another";
  EXPECT_THROW(write_calibration_file(path, other), std::runtime_error);
  EXPECT_EQ(read_calibration_file(path).rig, "bench 2");
  EXPECT_THROW(write_calibration_file((dir / "missing" / "cal.toml").string(), c), std::runtime_error);
  EXPECT_THROW(read_calibration_file((dir / "missing.toml").string()), std::runtime_error);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace vitreo::rig::calibration
