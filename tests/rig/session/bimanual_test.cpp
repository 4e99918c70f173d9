// Bimanual work (issue 15): a case whose other hand holds forceps (instruments.second_hand, lit by a
// chandelier) gives tracker 1 its own forceps through the other working port, and a scripted second
// hand grasps and peels a membrane with them through the whole stack — emulator → pty → driver →
// rig → core — while the working hand holds a tool of its own. A second hand in a case with nothing
// for it is refused when the script is resolved.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "rig/scene_io/case_loader.hpp"
#include "rig/session/rig_session.hpp"
#include "rig/session/scripted_session.hpp"

namespace vitreo::rig {
namespace {

namespace fs = std::filesystem;

const fs::path kScenes = fs::path(VITREO_SOURCE_DIR) / "scenes";

// low_membrane_macula with the light pipe's hand given forceps, under a chandelier.
scene_io::CaseText bimanual_membrane_case() {
  scene_io::CaseText c = scene_io::read_case_text((kScenes / "low_membrane_macula.toml").string());
  const std::string tools = R"(available = ["forceps", "pick", "scissors", "vitrector", "light_pipe", "infusion"])";
  const auto at = c.text.find(tools);
  EXPECT_NE(at, std::string::npos) << "the case's instrument list changed: update this test";
  if (at != std::string::npos)
    c.text.replace(at, tools.size(), R"(available = ["vitrector", "scissors", "infusion"])" "\nsecond_hand = \"forceps\"");
  c.text += "\n[view]\nchandelier = true\n";
  return c;
}

fs::path write_script(const std::string& name, const std::string& case_name, const std::string& hands) {
  const fs::path p = fs::path(::testing::TempDir()) / name;
  std::ofstream(p) << "[script]\nversion = 1\ncase = \"" << case_name << "\"\nkind = \"expert\"\nsummary = \"bimanual test\"\nduration_s = 5.0\n"
                   << hands;
  return p;
}

SessionSummary play(const scene_io::CaseText& c, const SurgicalScript& script, const std::string& tag) {
  const fs::path dir = fs::path(::testing::TempDir()) / ("bimanual-" + tag);
  fs::remove_all(dir);
  fs::create_directories(dir);
  SessionConfig config;
  config.model.cases.push_back(c);
  config.model.load.retina_vertices = 1500;
  config.model.load.texture_size_px = 128;
  config.model.load.cache_dir = (fs::path(::testing::TempDir()) / "bimanual-cache").string();
  config.devices = simulated_devices(script);
  config.adapt_devices = play_script(script, config.model.pedals, config.model.microscope);
  config.device_mode = HubMode::lockstep;
  config.unpaced = true;
  config.steps = static_cast<std::uint64_t>(std::llround(script.duration_s / config.model.dt_s));
  config.lcm_url = "file://" + (dir / "telemetry.lcmlog").string() + "?mode=w";
  config.command_echo = nullptr;
  return run_session(config);
}

// The other hand: in through its own port, down onto the membrane's edge toward it, jaws closed,
// lifted 1.5 mm toward the disc (the weak attachments under the flap let go).
const char* kSecondHandPeel = R"(
[[hand]]
tracker = 1
speed_mm_s = 8.0
[[hand.waypoint]]
to = "port"
above_mm = 3.0
duration_s = 0.001
[[hand.waypoint]]
to = "membrane.erm.edge"
above_mm = 1.0
toward_port_mm = -0.3
[[hand.waypoint]]
to = "membrane.erm.edge"
above_mm = 0.1
toward_port_mm = -0.3
speed_mm_s = 2.0
[[hand.waypoint]]
to = "membrane.erm.edge"
above_mm = 0.1
toward_port_mm = -0.3
duration_s = 0.2
jaws = 1.0
[[hand.waypoint]]
to = "membrane.erm.centre"
above_mm = 1.5
speed_mm_s = 2.0
)";

// The working hand meanwhile: the scissors just inside their port, clear of the forceps (both shafts
// reach the posterior pole from opposite sides: held over the disc, they crossed the forceps').
const char* kWorkingHandWaits = R"(
[[hand]]
tracker = 0
speed_mm_s = 8.0
[[hand.waypoint]]
to = "port"
above_mm = 3.0
duration_s = 0.001
tool = "scissors"
)";

TEST(Bimanual, TheOtherHandsForcepsGraspAndPeelAMembraneThroughTheWholeStack) {
  const scene_io::CaseText c = bimanual_membrane_case();
  const SurgicalScript script = read_surgical_script(
      write_script("bimanual-peel.toml", "low_membrane_macula", std::string(kSecondHandPeel) + kWorkingHandWaits).string());
  const SessionSummary s = play(c, script, "peel");
  EXPECT_NE(s.instruments.find("tracker 1 (working_2): forceps (lit by the chandelier)"), std::string::npos) << s.instruments;
  // Only the forceps close on tissue here: the working hand's scissors stay by their port.
  EXPECT_EQ(s.grasps, 1u) << "the second hand's forceps closed on the membrane";
  EXPECT_GE(s.attachments_broken, 3u) << "and peeled it: the weak attachments under the lifted flap let go";
  EXPECT_EQ(s.totals.iatrogenic_events(), 0u);
}

TEST(Bimanual, TheSameSecondHandWithoutItsForcepsGraspsNothing) {
  // Control: the shipped case's other hand is the light pipe, so the same motion closes nothing.
  const scene_io::CaseText c = scene_io::read_case_text((kScenes / "low_membrane_macula.toml").string());
  const SurgicalScript script = read_surgical_script(
      write_script("light-pipe-peel.toml", "low_membrane_macula", std::string(kSecondHandPeel) + kWorkingHandWaits).string());
  const SessionSummary s = play(c, script, "light-pipe");
  EXPECT_NE(s.instruments.find("tracker 1 (working_2): light pipe"), std::string::npos) << s.instruments;
  EXPECT_EQ(s.grasps, 0u) << "a light pipe has no jaws (its tip, pushed along the membrane, may still tear some attachments off)";
}

TEST(Bimanual, ASecondHandInACaseWithNothingForItIsRefusedWhenResolved) {
  scene_io::CaseText c = scene_io::read_case_text((kScenes / "low_membrane_macula.toml").string());
  const std::string light = R"("light_pipe", )";
  const auto at = c.text.find(light);
  ASSERT_NE(at, std::string::npos);
  c.text.erase(at, light.size());  // no light pipe, no second_hand: the other hand holds nothing
  scene_io::CaseLoadOptions o;
  o.retina_vertices = 1500;
  o.texture_size_px = 128;
  o.cache_dir = (fs::path(::testing::TempDir()) / "bimanual-cache").string();
  const auto prepared = prepare_case({c}, 0, o);
  EXPECT_EQ(prepared->second_hand, -1);
  const fs::path file = write_script("nothing-for-it.toml", "low_membrane_macula", kSecondHandPeel);
  try {
    (void)resolve_script(read_surgical_script(file.string()), *prepared, PedalMapping{});
    FAIL() << "resolved";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(file.string() + ":8: hand[0].tracker: the case has nothing for the second hand"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace vitreo::rig
