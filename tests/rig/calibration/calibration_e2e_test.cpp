// End to end (label calibration): a simulated rig with known injected imperfections
// (rig/config/sim-calibration.toml and its sim/calibration-*.sim scripts) → vitreo-calibrate over
// ptys → the calibration file → the rig's input mapping puts the instruments and pedals where the
// truth says, where the uncalibrated mapping is off by the injected transform.
//
// The truth below is written from the scripts' directives, independently of the calibration code.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "rig/calibration/calibration_file.hpp"
#include "rig/session/calibration_in_force.hpp"
#include "rig/session/device_hub.hpp"
#include "rig/session/device_inputs.hpp"
#include "rig/session/rig_session.hpp"
#include "rig/scene_io/case_loader.hpp"
#include "rig/telemetry/channels.hpp"
#include "rig/telemetry/recording.hpp"
#include "vitreo_lcm/device_status_t.hpp"

#include <lcm/lcm-cpp.hpp>
#include <map>

namespace vitreo::rig {
namespace {

namespace fs = std::filesystem;
const std::string kSource = VITREO_SOURCE_DIR;

// From rig/config/sim/calibration-tracker.sim and calibration-pedals.sim.
const core::Vec3 kTipOffset(0.8, -0.5, 14.0);
core::Quat tracker_rotation() {
  const double d = std::numbers::pi / 180.0;
  return core::Quat(Eigen::AngleAxisd(25 * d, core::Vec3::UnitZ()) * Eigen::AngleAxisd(-12 * d, core::Vec3::UnitY()) *
                    Eigen::AngleAxisd(8 * d, core::Vec3::UnitX()));
}
const core::Vec3 kTrackerOrigin(40.0, -25.0, 180.0);
core::Vec3 eye_to_tracker(const core::Vec3& eye) { return tracker_rotation() * eye + kTrackerOrigin; }
// The fixture's two working ports: 4.6 mm anterior on the 12 mm globe, at 10 and 2 o'clock.
core::Vec3 true_port(int i) {
  const double rho = std::sqrt(144.0 - 4.6 * 4.6);
  return {(i == 0 ? -1 : 1) * rho * std::cos(std::numbers::pi / 6), rho * 0.5, 4.6};
}

struct ToolRun {
  int status = -1;
  std::string output;
};
ToolRun run_calibrate(const std::string& rig, const std::string& out) {
  ToolRun r;
  const std::string cmd = std::string(VITREO_CALIBRATE) + " --rig " + rig + " --out " + out + " --non-interactive 2>&1";
  FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) return r;
  char buf[4096];
  for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, p)) > 0;) r.output.append(buf, n);
  const int st = ::pclose(p);
  r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return r;
}

class CalibrationEndToEnd : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("vitreo-calib-e2e-" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    file_ = (dir_ / "rig.calibration.toml").string();
    run_ = run_calibrate(kSource + "/rig/config/sim-calibration.toml", file_);
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static inline fs::path dir_;
  static inline std::string file_;
  static inline ToolRun run_;
};

TEST_F(CalibrationEndToEnd, RecoversEveryInjectedImperfectionWithinTheIssuesTolerances) {
  ASSERT_EQ(run_.status, 0) << run_.output;
  EXPECT_NE(run_.output.find("result: PASS"), std::string::npos) << run_.output;
  EXPECT_NE(run_.output.find("touch fiducial 8 of 8"), std::string::npos) << run_.output;  // step-by-step feedback
  const calibration::CalibrationFile c = calibration::read_calibration_file(file_);
  // Tip offset within 0.1 mm.
  ASSERT_NE(c.instrument(0), nullptr);
  const double tip_error = (c.instrument(0)->tip_offset_mm - kTipOffset).norm();
  EXPECT_LT(tip_error, 0.1);
  // Registration: the target error at points a surgeon works at (never touched) within 0.2 mm.
  ASSERT_TRUE(c.registration);
  double tre_sq = 0;
  const std::vector<core::Vec3> targets = {{0, 0, -12}, {3, -1, -11.5}, {0, 11, -4}, {-8, 0, -8}, {0, 0, 0}};
  for (const core::Vec3& t : targets) {
    const core::Vec3 mapped = c.registration->rig_to_eye * (eye_to_tracker(t) - c.registration->eye_center_in_rig_mm);
    tre_sq += (mapped - t).squaredNorm();
  }
  const double tre = std::sqrt(tre_sq / static_cast<double>(targets.size()));
  EXPECT_LT(tre, 0.2);
  // Ports within 0.2 mm.
  double port_error = 0;
  for (int i = 0; i < 2; ++i) {
    ASSERT_NE(c.port(i), nullptr);
    port_error = std::max(port_error, (c.port(i)->position_mm - true_port(i)).norm());
  }
  EXPECT_LT(port_error, 0.2);
  // Pedal ranges within 2 % of the travel.
  const double pedal_truth[2][2] = {{0.07, 0.91}, {0.12, 0.86}};
  double pedal_error = 0;
  for (int axis = 0; axis < 2; ++axis) {
    ASSERT_NE(c.pedal(0, axis), nullptr);
    const double span = pedal_truth[axis][1] - pedal_truth[axis][0];
    pedal_error = std::max({pedal_error, std::abs(c.pedal(0, axis)->range.lo - pedal_truth[axis][0]) / span,
                            std::abs(c.pedal(0, axis)->range.hi - pedal_truth[axis][1]) / span});
  }
  EXPECT_LT(pedal_error, 0.02);
  // Clocks: both devices share the emulators' start and boot time, so their offsets differ by the
  // injected offsets plus the injected drifts accumulated by the fit's reference time (near the
  // run's end: the procedure's length less 0.5 ± 0.5 s, so ±0.1 ms of uncertainty from the 210 ppm
  // difference). The tool prints the procedure's length: "(27.5 s of procedure)".
  const std::size_t at = run_.output.find(" s of procedure)");
  ASSERT_NE(at, std::string::npos) << run_.output;
  const double procedure_s = std::stod(run_.output.substr(run_.output.rfind('(', at) + 1));
  EXPECT_GT(procedure_s, 10.0);
  ASSERT_EQ(c.clocks.size(), 3u);  // tracker, pedals, eyeball
  auto clock_of = [&](const std::string& name) {
    for (const calibration::ClockRecord& r : c.clocks)
      if (r.device == name) return r;
    ADD_FAILURE() << "no clock for " << name;
    return calibration::ClockRecord{};
  };
  const calibration::ClockRecord tracker = clock_of("tracker-0"), pedals = clock_of("pedals");
  const double expected_difference_ms = (123.4 - -40.0) + (150.0 - -60.0) * 1e-6 * (procedure_s - 0.5) * 1e3;
  const double clock_error = std::abs((tracker.offset_ms - pedals.offset_ms) - expected_difference_ms);
  EXPECT_LT(clock_error, 0.5);
  EXPECT_NEAR(tracker.drift_ppm - pedals.drift_ppm, 210.0, 10.0);
  // The eyeball fixture's rest reading (calibration-eyeball.sim: yaw 6°, pitch −4°) within 0.1°.
  ASSERT_TRUE(c.eye_zero);
  const double d = std::numbers::pi / 180.0;
  const core::Quat eye_zero_truth(Eigen::AngleAxisd(6 * d, core::Vec3::UnitZ()) * Eigen::AngleAxisd(-4 * d, core::Vec3::UnitY()));
  const double eye_zero_error_deg = c.eye_zero->zero.angularDistance(eye_zero_truth) / d;
  EXPECT_LT(eye_zero_error_deg, 0.1);
  std::printf("recovered: tip %.4f mm (0.1), TRE %.4f mm (0.2), ports %.4f mm (0.2), pedals %.2f %% (2), "
              "clock %.3f ms (0.5); drift %.1f and %.1f ppm (150, -60 injected); eye zero %.4f deg\n",
              tip_error, tre, port_error, 100 * pedal_error, clock_error, tracker.drift_ppm, pedals.drift_ppm, eye_zero_error_deg);
}

// Plays a tracker with the injected imperfections through a pty in lockstep, holding its tip at
// `tip_eye` (eye frame), and returns the samples the driver decoded after the first 10 ms.
std::vector<TrackedPose> tracked_through_the_rig(const core::Vec3& tip_eye) {
  std::ifstream f(kSource + "/rig/config/sim/calibration-tracker.sim");
  std::string script((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  script.erase(script.find("key "));
  char key[128];
  std::snprintf(key, sizeof key, "loop 0\nkey 0 %.4f %.4f %.4f 10 35 -20 0\n", tip_eye.x(), tip_eye.y(), tip_eye.z());
  DeviceSpec d;
  d.name = "tracker-0";
  d.role = DeviceRole::tracker;
  d.uri = "sim:tracker?transport=pty";
  d.device_id = 1;
  d.sim_script = script + key;
  DeviceHub hub({d}, nullptr, HubMode::lockstep);
  hub.start();
  hub.lockstep_connect();
  std::vector<TrackedPose> samples;
  for (std::uint64_t k = 0; k < 110; ++k) {
    hub.lockstep_deliver(k, 1000);
    hub.take_new([&](const telemetry::RecordedInput& in) {
      if (const auto* t = std::get_if<telemetry::TrackerSample>(&in.what); t && k >= 10) samples.push_back(tracked_pose(*t));
    });
  }
  hub.stop();
  EXPECT_GE(samples.size(), 90u);
  return samples;
}

TEST_F(CalibrationEndToEnd, TheCalibratedRigMapsTheInstrumentWhereItIs) {
  ASSERT_EQ(run_.status, 0) << run_.output;
  ModelConfig calibrated, plain;
  std::vector<DeviceSpec> devices = {{"tracker-0", DeviceRole::tracker, "sim:tracker?transport=pty", 1, 0, 0, 0, {}},
                                     {"pedals", DeviceRole::pedals, "sim:pedals?transport=pty", 2, 0, 0, 0, {}},
                                     {"eyeball", DeviceRole::eyeball, "sim:eyeball?transport=pty", 3, 0, 0, 0, {}}};
  const CalibrationLoad load = load_calibration(file_, devices, calibrated, 30.0, ::time(nullptr));
  EXPECT_TRUE(load.warnings.empty());
  EXPECT_EQ(devices[0].expected_serial, 1001u);  // pinned to the calibrated unit
  EXPECT_GT(calibrated.eye_zero.angularDistance(core::Quat::Identity()), 0.1);  // the fixture's 7° rest reading
  // A tip 3 mm inside port 0, tilted: where the rig puts it with and without the calibration.
  const core::Vec3 truth = true_port(0) - 3.0 * true_port(0).normalized();
  // Averaged over 100 samples (0.1 s), so the check is of the mapping, not of one sample's noise.
  InstrumentPose with, without;
  core::Vec3 with_sum = core::Vec3::Zero(), without_sum = core::Vec3::Zero();
  const std::vector<TrackedPose> samples = tracked_through_the_rig(truth);
  for (const TrackedPose& pose : samples) {
    ASSERT_TRUE(map_through_port(pose, *calibrated.measured_ports[0], core::Quat::Identity(), calibrated.calibration[0], with));
    ASSERT_TRUE(map_through_port(pose, Port{true_port(0), true_port(0).normalized()}, core::Quat::Identity(),
                                 plain.calibration[0], without));
    with_sum += with.tip_mm, without_sum += without.tip_mm;
  }
  with.tip_mm = with_sum / static_cast<double>(samples.size());
  without.tip_mm = without_sum / static_cast<double>(samples.size());
  EXPECT_LT((with.tip_mm - truth).norm(), 0.2) << "calibrated tip " << with.tip_mm.transpose();
  EXPECT_TRUE(with.inserted);
  EXPECT_NEAR(with.insertion_mm, 3.0, 0.2);
  EXPECT_GT((without.tip_mm - truth).norm(), 100.0) << "the uncalibrated rig is off by the injected transform";
  std::printf("instrument tip: %.4f mm from the truth calibrated, %.1f mm uncalibrated\n", (with.tip_mm - truth).norm(),
              (without.tip_mm - truth).norm());
  // Pedals: the potentiometer's 0.07 at rest and 0.91 fully down read as no and full vacuum.
  PedalMapper mapped(calibrated.pedals), raw(plain.pedals);
  PedalReading full;
  full.pedal_id = 0, full.axis_count = 2, full.axes[0] = 0.91, full.axes[1] = 0.12;
  ASSERT_TRUE(mapped.apply(full) && raw.apply(full));
  EXPECT_NEAR(mapped.controls().vacuum_mmhg, calibrated.pedals.vacuum_max_mmhg, 0.02 * calibrated.pedals.vacuum_max_mmhg);
  EXPECT_LT(raw.controls().vacuum_mmhg, 0.92 * plain.pedals.vacuum_max_mmhg);
  PedalReading rest = full;
  rest.axes[0] = 0.0705;
  ASSERT_TRUE(mapped.apply(rest));
  EXPECT_EQ(mapped.controls().vacuum_mmhg, 0.0);
}

TEST_F(CalibrationEndToEnd, IsRefusedForOtherSerialsAndItsRecordingCarriesIt) {
  ASSERT_EQ(run_.status, 0) << run_.output;
  ModelConfig model;
  std::vector<DeviceSpec> devices = {{"tracker-0", DeviceRole::tracker, "sim:tracker?transport=pty", 1, 0, 4242, 0, {}}};
  try {
    load_calibration(file_, devices, model, 30.0, ::time(nullptr));
    FAIL() << "accepted for another tracker";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("made for tracker-0 serial 1001, this rig's tracker-0 is serial 4242"), std::string::npos)
        << e.what();
  }
  EXPECT_TRUE(model.calibration_text.empty());  // nothing applied
  EXPECT_EQ(devices[0].expected_serial, 4242u);
  // A stale one is applied with a warning.
  devices[0].expected_serial = 0;
  devices.push_back({"pedals", DeviceRole::pedals, "sim:pedals?transport=pty", 2, 0, 0, 0, {}});
  devices.push_back({"eyeball", DeviceRole::eyeball, "sim:eyeball?transport=pty", 3, 0, 0, 0, {}});
  const CalibrationLoad old = load_calibration(file_, devices, model, 30.0, ::time(nullptr) + 40 * 86400);
  ASSERT_EQ(old.warnings.size(), 1u);
  EXPECT_NE(old.warnings[0].find("days old"), std::string::npos);
  // The recording's case list carries it; decoding restores the same mapping.
  model.cases.push_back({"x.toml", "x", ""});
  ModelConfig replayed;
  decode_case_list(encode_case_list(model), replayed);
  EXPECT_EQ(replayed.calibration_text, model.calibration_text);
  EXPECT_EQ(replayed.calibration[0].tip_offset_mm, model.calibration[0].tip_offset_mm);
  EXPECT_EQ(replayed.pedals.axis_ranges.size(), 2u);
}

TEST_F(CalibrationEndToEnd, ADeviceThatStopsMidwayFailsAndKeepsThePreviousCalibration) {
  ASSERT_EQ(run_.status, 0) << run_.output;
  // The same rig (and its technician), but the tracker's cable is pulled 16 s in (while touching
  // the fiducials: rig/config/sim-calibration.technician.toml, beside the copy as stops.technician.toml).
  const fs::path rig = dir_ / "stops.toml";
  fs::copy(kSource + "/rig/config/sim", dir_ / "sim", fs::copy_options::recursive | fs::copy_options::overwrite_existing);
  fs::copy_file(kSource + "/rig/config/sim-calibration.technician.toml", dir_ / "stops.technician.toml", fs::copy_options::overwrite_existing);
  std::ofstream(dir_ / "sim/calibration-tracker.sim", std::ios::app) << "fault 16000 60000 disconnect\n";
  std::ifstream r(kSource + "/rig/config/sim-calibration.toml");
  std::ofstream(rig) << r.rdbuf();
  const std::string previous = (dir_ / "previous.toml").string();
  fs::copy_file(file_, previous);
  std::ifstream before_f(previous);
  const std::string before((std::istreambuf_iterator<char>(before_f)), std::istreambuf_iterator<char>());
  const ToolRun failed = run_calibrate(rig.string(), previous);
  EXPECT_EQ(failed.status, 1) << failed.output;
  EXPECT_NE(failed.output.find("tracker-0: link lost"), std::string::npos) << failed.output;
  EXPECT_NE(failed.output.find("was not written"), std::string::npos) << failed.output;
  std::ifstream after_f(previous);
  const std::string after((std::istreambuf_iterator<char>(after_f)), std::istreambuf_iterator<char>());
  EXPECT_EQ(after, before);
}

// Telemetry says which calibration is in force: a short session of the calibrated simulated rig
// (its rig file's devices, the file vitreo-calibrate just wrote) publishes, in every device's
// status, the id of that file; the same session's recording carries the file itself.
TEST_F(CalibrationEndToEnd, TheSessionsTelemetrySaysWhichCalibrationIsInForce) {
  ASSERT_EQ(run_.status, 0) << run_.output;
  RigFile rig = read_rig_file(kSource + "/rig/config/sim-calibration.toml");
  SessionConfig config;
  config.model.cases.push_back(scene_io::read_case_text(kSource + "/scenes/exercise_pull_tissue.toml"));
  config.model.load.retina_vertices = 1500;
  config.model.load.textures = false;
  config.model.load.cache_dir = (dir_ / "case-cache").string();
  const CalibrationLoad load = load_calibration(file_, rig.devices, config.model, 30.0, ::time(nullptr));
  config.devices = rig.devices;
  config.device_mode = HubMode::lockstep;
  config.unpaced = true;
  config.steps = 600;
  const std::string log_path = (dir_ / "calibrated-telemetry.lcmlog").string();
  config.lcm_url = "file://" + log_path + "?mode=w";
  config.record_path = (dir_ / "calibrated-session.lcmlog").string();
  config.command_echo = nullptr;
  const SessionSummary summary = run_session(config);
  ASSERT_EQ(summary.steps, 600u);

  const std::string id = calibration_id(load.file);
  ASSERT_NE(id, "");
  std::map<std::string, std::string> last;  // device → the calibration its last status named
  int statuses = 0;
  lcm::LogFile log(log_path, "r");
  ASSERT_TRUE(log.good());
  for (const lcm::LogEvent* ev = log.readNextEvent(); ev != nullptr; ev = log.readNextEvent()) {
    if (ev->channel != telemetry::kChanDeviceStatus) continue;
    vitreo_lcm::device_status_t m;
    ASSERT_EQ(m.decode(ev->data, 0, ev->datalen), ev->datalen);
    last[m.name] = m.calibration;
    ++statuses;
    EXPECT_EQ(m.calibration, id) << m.name << ": every status names the calibration in force";
  }
  EXPECT_GE(statuses, 3);
  for (const auto& d : rig.devices) EXPECT_EQ(last[d.name], id) << d.name;
  // The recording's case list holds the calibration file's text (a replay maps as the session did).
  const telemetry::Recording rec = telemetry::read_recording(config.record_path);
  ModelConfig replayed;
  decode_case_list(rec.header.config_text, replayed);
  EXPECT_EQ(replayed.calibration_text, config.model.calibration_text);
  std::printf("calibration in force, as telemetry names it: %s (%d statuses)\n", id.c_str(), statuses);
}

}  // namespace
}  // namespace vitreo::rig

namespace vitreo::rig {
namespace {

TEST(RigFileCalibration, NamesTheFileRelativeToTheRigFileAndItsMaxAge) {
  const std::string head = "[rig]\nversion = 1\n[[device]]\nname = \"t\"\nrole = \"tracker\"\nuri = \"sim:tracker?transport=pty\"\nid = 1\n";
  const RigFile r = parse_rig_file(head + "[calibration]\nfile = \"cal/bench.toml\"\nmax_age_days = 14\n", "rig.toml", "/rigs");
  EXPECT_EQ(r.calibration_path, "/rigs/cal/bench.toml");
  ASSERT_TRUE(r.calibration_max_age_days);
  EXPECT_EQ(*r.calibration_max_age_days, 14.0);
  EXPECT_TRUE(parse_rig_file(head, "rig.toml", "/rigs").calibration_path.empty());
  try {
    parse_rig_file(head + "[calibration]\nfile = \"x.toml\"\nmax_age_days = -3\n", "rig.toml", "/rigs");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("rig.toml:10: calibration.max_age_days"), std::string::npos) << e.what();
  }
  EXPECT_THROW(parse_rig_file(head + "[calibration]\nmax_age_days = 3\n", "rig.toml", "/rigs"), std::runtime_error);
}

}  // namespace
}  // namespace vitreo::rig
