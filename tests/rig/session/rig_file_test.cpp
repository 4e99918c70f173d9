// Rig files (rig/session/rig_file.hpp): every file in rig/config/ reads; a bad file is refused with
// its file, line and key; what the files say reaches the devices (identity, rate, scripts).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "drivers/device_uri.hpp"
#include "rig/session/rig_file.hpp"

using namespace vitreo;

namespace {

const std::string kConfig = std::string(VITREO_SOURCE_DIR) + "/rig/config";

std::string error_of(const std::string& text, const std::string& base = "/nonexistent") {
  try {
    rig::parse_rig_file(text, "t.toml", base);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  ADD_FAILURE() << "accepted:\n" << text;
  return {};
}

const char* kHead = "[rig]\nversion = 1\n";
const char* kTracker = "[[device]]\nname = \"tracker\"\nrole = \"tracker\"\nuri = \"usb:1209:7a11\"\nid = 1\n";

}  // namespace

TEST(RigFile, EveryShippedRigFileReads) {
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(kConfig)) {
    if (e.path().extension() != ".toml") continue;
    // A rig's scripted technician (RIG.technician.toml) is a surgical script, not a rig file: the
    // technician-script tests read it.
    if (e.path().filename().string().ends_with(".technician.toml")) continue;
    ++files;
    SCOPED_TRACE(e.path().string());
    const rig::RigFile f = rig::read_rig_file(e.path().string());
    EXPECT_FALSE(f.name.empty());
    ASSERT_EQ(f.devices.size(), 3u) << "tracker, pedals and eyeball";
    EXPECT_EQ(f.devices[0].role, rig::DeviceRole::tracker);
    EXPECT_EQ(f.devices[1].role, rig::DeviceRole::pedals);
    EXPECT_EQ(f.devices[2].role, rig::DeviceRole::eyeball);
    for (const auto& d : f.devices) {
      drivers::DeviceUri uri;
      std::string why;
      EXPECT_TRUE(drivers::parse_device_uri(d.uri, uri, &why)) << why;
    }
  }
  EXPECT_GE(files, 3);
}

TEST(RigFile, TheMixedRigUsesAllThreeTransports) {
  const rig::RigFile f = rig::read_rig_file(kConfig + "/sim-mixed.toml");
  std::vector<drivers::Transport> transports;
  for (const auto& d : f.devices) {
    drivers::DeviceUri uri;
    ASSERT_TRUE(drivers::parse_device_uri(d.uri, uri, nullptr));
    EXPECT_EQ(uri.scheme, drivers::DeviceUri::Scheme::sim);
    transports.push_back(uri.transport());
  }
  EXPECT_EQ(transports, (std::vector<drivers::Transport>{drivers::Transport::usb, drivers::Transport::serial, drivers::Transport::can}));
}

TEST(RigFile, TheBuiltRigNamesRealDevicesAndCarriesThePedalMapping) {
  const rig::RigFile f = rig::read_rig_file(kConfig + "/default-rig.toml");
  EXPECT_EQ(f.devices[0].uri, "usb:1209:7a11");
  EXPECT_EQ(f.devices[1].uri, "serial:/dev/vitreo/pedals");
  EXPECT_EQ(f.devices[2].uri, "can:can0?node=33");
  ASSERT_TRUE(f.pedals.has_value());
  EXPECT_EQ(f.pedals->vacuum_max_mmhg, 650.0);
  EXPECT_EQ(f.pedals->cut_rate_max_cpm, 10000.0);
  ASSERT_TRUE(f.laser.has_value());
  EXPECT_EQ(f.laser->power_mw, 200.0);
  EXPECT_EQ(f.laser->duration_ms, 100.0);
}

// The rig file the installed service reads (rig/system/): its serial devices by the names
// 70-vitreo.rules gives them (tests/install/udev_rules_test.sh checks udev makes them).
TEST(RigFile, TheInstalledRigNamesItsDevicesByTheirStableNames) {
  const rig::RigFile f = rig::read_rig_file(kConfig + "/installed-rig.toml");
  ASSERT_EQ(f.devices.size(), 3u);
  EXPECT_EQ(f.devices[0].uri, "serial:/dev/vitreo/tracker");
  EXPECT_EQ(f.devices[1].uri, "serial:/dev/vitreo/pedals");
  EXPECT_EQ(f.devices[2].uri, "can:can0?node=33");
  for (const auto& d : f.devices) {
    if (d.uri.rfind("serial:", 0) == 0) {
      EXPECT_EQ(d.uri, "serial:/dev/vitreo/" + d.name) << "a device is named as its /dev/vitreo link";
    }
  }
  EXPECT_FALSE(f.pedals.has_value()) << "the default mapping";
  EXPECT_TRUE(f.calibration_path.empty());
}

TEST(RigFile, FieldsReachTheSpec) {
  const auto dir = std::filesystem::temp_directory_path() / ("rig-file-test-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "hand.sim") << "device tracker\nkey 0 0 0 20 0 0 0 0\n";
  const rig::RigFile f = rig::parse_rig_file(std::string(kHead) + "name = \"bench\"\n" +
                                                 "[[device]]\nname = \"light\"\nrole = \"tracker\"\n"
                                                 "uri = \"sim:tracker?transport=pty\"\nid = 7\nserial = 4242\ninstrument = 1\n"
                                                 "rate_hz = 250\nscript = \"hand.sim\"\n",
                                             "t.toml", dir.string());
  std::filesystem::remove_all(dir);
  ASSERT_EQ(f.devices.size(), 1u);
  const rig::DeviceSpec& d = f.devices[0];
  EXPECT_EQ(f.name, "bench");
  EXPECT_EQ(d.name, "light");
  EXPECT_EQ(d.device_id, 7);
  EXPECT_EQ(d.expected_serial, 4242u);
  EXPECT_EQ(d.channel, 1);
  EXPECT_EQ(d.sample_rate_hz, 250);
  EXPECT_EQ(d.sim_script, "device tracker\nkey 0 0 0 20 0 0 0 0\n") << "read relative to the rig file";
  EXPECT_EQ(d.uri, "sim:tracker?transport=pty") << "canonical";
  EXPECT_FALSE(f.pedals.has_value());
}

TEST(RigFile, BadFilesAreRefusedWithFileLineAndKey) {
  EXPECT_NE(error_of("[rig]\nversion = 2\n").find("t.toml:2: rig.version: this is a version 2 rig file; this vitreo reads version 1"),
            std::string::npos);
  EXPECT_NE(error_of("[rig]\nname = \"x\"\n").find("rig.version missing"), std::string::npos);
  EXPECT_NE(error_of(kHead).find("no [[device]] entries"), std::string::npos);
  EXPECT_NE(error_of("devices = 1\n" + std::string(kHead)).find("t.toml:1: devices: unknown key"), std::string::npos);
  EXPECT_NE(error_of(std::string(kHead) + kTracker + "colour = \"red\"\n").find("t.toml:8: device[0].colour: unknown key"),
            std::string::npos);
  EXPECT_NE(error_of(std::string(kHead) + kTracker + "[[device]]\nname = \"tracker\"\n").find("device[1].name: 'tracker' names two devices"),
            std::string::npos);
  EXPECT_NE(error_of(std::string(kHead) + kTracker + kTracker).find("device[1].id: 1 is the id of two devices"), std::string::npos);
  EXPECT_NE(error_of(std::string(kHead) + "[[device]]\nname = \"a b\"\n").find("letters, digits"), std::string::npos);
  EXPECT_NE(error_of(std::string(kHead) + "[[device]]\nname = \"t\"\nrole = \"camera\"\n").find("t.toml:5: device[0].role: 'camera'"),
            std::string::npos);
  EXPECT_NE(error_of(std::string(kHead) + "[[device]]\nname = \"t\"\nrole = \"tracker\"\nuri = \"usb:7a11\"\n")
                .find("t.toml:6: device[0].uri: device URI 'usb:7a11'"),
            std::string::npos);
  EXPECT_NE(error_of(std::string(kHead) + "[[device]]\nname = \"t\"\nrole = \"tracker\"\nid = 1\n").find("no uri"), std::string::npos);
  EXPECT_NE(error_of(std::string(kHead) + "[[device]]\nname = \"t\"\nrole = \"tracker\"\nuri = \"can:can0?node=5\"\n")
                .find("no id"),
            std::string::npos);
  EXPECT_NE(error_of(std::string(kHead) + kTracker + "id = 0\n").find("id"), std::string::npos);
  EXPECT_NE(error_of(std::string(kHead) + "[[device]]\nname = \"p\"\nrole = \"pedals\"\nuri = \"serial:/dev/x\"\nid = 1\ninstrument = 0\n")
                .find("only trackers carry an instrument"),
            std::string::npos);
  EXPECT_NE(error_of(std::string(kHead) + "[[device]]\nname = \"p\"\nrole = \"pedals\"\nuri = \"sim:tracker?transport=pty\"\nid = 1\n")
                .find("simulates another kind of device than its role, pedals"),
            std::string::npos);
  EXPECT_NE(error_of(std::string(kHead) + kTracker + "script = \"x.sim\"\n").find("only simulated devices"), std::string::npos);
  EXPECT_NE(error_of(std::string(kHead) + "[[device]]\nname = \"t\"\nrole = \"tracker\"\nuri = \"sim:tracker\"\nid = 1\nscript = \"none.sim\"\n")
                .find("none.sim: cannot read the device's script"),
            std::string::npos);
  EXPECT_NE(error_of(std::string(kHead) + kTracker + "[[device]]\nname = \"u\"\nrole = \"tracker\"\nuri = \"usb:1209:7A11\"\nid = 2\n")
                .find("'usb:1209:7a11' is given for two devices"),
            std::string::npos);
  EXPECT_NE(error_of(std::string(kHead) + kTracker + "[pedals]\nvacuum_axis = 9\n").find("pedals.vacuum_axis"), std::string::npos);
}

// The [laser] table: the endolaser's start settings, held to the operator commands' ranges.
TEST(RigFile, TheLaserTableSetsPowerAndPulseDuration) {
  const rig::RigFile f = rig::parse_rig_file(std::string(kHead) + kTracker + "[laser]\npower_mw = 350\nduration_ms = 150.5\n",
                                             "t.toml", "/nonexistent");
  ASSERT_TRUE(f.laser.has_value());
  EXPECT_EQ(f.laser->power_mw, 350.0);
  EXPECT_EQ(f.laser->duration_ms, 150.5);
  const rig::RigFile half = rig::parse_rig_file(std::string(kHead) + kTracker + "[laser]\nduration_ms = 50\n", "t.toml", "/nonexistent");
  ASSERT_TRUE(half.laser.has_value());
  EXPECT_EQ(half.laser->power_mw, 200.0) << "the console's default";
  EXPECT_EQ(half.laser->duration_ms, 50.0);
  EXPECT_FALSE(rig::parse_rig_file(std::string(kHead) + kTracker, "t.toml", "/nonexistent").laser.has_value());
  // The ends of the ranges are settings; past them, a non-number, an unknown key and a non-table are refused.
  EXPECT_NO_THROW(rig::parse_rig_file(std::string(kHead) + kTracker + "[laser]\npower_mw = 50\nduration_ms = 2000\n", "t.toml", "/x"));
  EXPECT_NO_THROW(rig::parse_rig_file(std::string(kHead) + kTracker + "[laser]\npower_mw = 2000.0\nduration_ms = 10\n", "t.toml", "/x"));
  EXPECT_NE(error_of(std::string(kHead) + kTracker + "[laser]\npower_mw = 2500\n").find("t.toml:9: laser.power_mw: must be a power in [50, 2000] mW"),
            std::string::npos);
  EXPECT_NE(error_of(std::string(kHead) + kTracker + "[laser]\npower_mw = 49.9\n").find("t.toml:9: laser.power_mw"), std::string::npos);
  EXPECT_NE(error_of(std::string(kHead) + kTracker + "[laser]\npower_mw = 200\nduration_ms = 0\n")
                .find("t.toml:10: laser.duration_ms: must be a pulse duration in [10, 2000] ms"),
            std::string::npos)
      << "no continuous mode";
  EXPECT_NE(error_of(std::string(kHead) + kTracker + "[laser]\nduration_ms = nan\n").find("t.toml:9: laser.duration_ms"), std::string::npos);
  EXPECT_NE(error_of(std::string(kHead) + kTracker + "[laser]\npower_mw = \"high\"\n").find("t.toml:9: laser.power_mw"), std::string::npos);
  EXPECT_NE(error_of(std::string(kHead) + kTracker + "[laser]\nwavelength_nm = 532\n").find("t.toml:9: laser.wavelength_nm: unknown key"),
            std::string::npos);
  EXPECT_NE(error_of(std::string(kHead) + kTracker + "laser = 200\n").find("device[0].laser: unknown key"), std::string::npos);
  EXPECT_NE(error_of("laser = 200\n" + std::string(kHead) + kTracker).find("t.toml:1: laser: must be a table"), std::string::npos);
}
