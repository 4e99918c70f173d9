// Surgical scripts (rig/session/surgical_script.hpp): every shipped script parses; malformed ones are
// refused with FILE:LINE: KEY; resolving against a case refuses what the case lacks and what no
// instrument can reach; the emulator keyframes land where the landmarks are, at the scripted speeds.
#include <gtest/gtest.h>

#include <filesystem>
#include <sstream>
#include <string>

#include "drivers/sim/emulator.hpp"
#include "rig/scene_io/case_loader.hpp"
#include "core/scene/microscope.hpp"
#include "rig/input/controls.hpp"
#include "rig/session/surgical_script.hpp"

namespace vitreo::rig {
namespace {

namespace fs = std::filesystem;
const fs::path kScenes = fs::path(VITREO_SOURCE_DIR) / "scenes";

std::string error_of(const std::string& text) {
  try {
    (void)parse_surgical_script(text, "s.toml");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

const char* kHead = "[script]\nversion = 1\ncase = \"exercise_pull_tissue\"\nduration_s = 4.0\n";

TEST(SurgicalScript, EveryShippedScriptParsesAndNamesAShippedCase) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(kScenes / "scripts")) {
    if (e.path().extension() != ".toml") continue;
    const SurgicalScript s = read_surgical_script(e.path().string());
    EXPECT_TRUE(fs::exists(kScenes / (s.case_name + ".toml"))) << e.path();
    EXPECT_EQ(e.path().filename().string().rfind(s.case_name + "." + s.kind + ".", 0), 0u) << e.path() << ": named CASE.KIND.toml";
    if (s.kind == "idle") {
      EXPECT_TRUE(s.hands.empty()) << e.path();
    }
    ++n;
  }
  EXPECT_GT(n, 0);
}

TEST(SurgicalScript, MalformedScriptsAreRefusedWithFileLineAndKey) {
  EXPECT_NE(error_of("").find("s.toml:1: script: no [script] table"), std::string::npos) << error_of("");
  EXPECT_NE(error_of("[script]\nversion = 2\ncase = \"x\"\n").find("s.toml:2: script.version: this is a version 2 script"), std::string::npos);
  EXPECT_NE(error_of("[script]\nversion = 1\n").find("script.case: missing"), std::string::npos);
  EXPECT_NE(error_of(std::string(kHead) + "speed = 3\n").find("s.toml:5: script.speed: unknown key"), std::string::npos)
      << error_of(std::string(kHead) + "speed = 3\n");
  const std::string bad_key = std::string(kHead) + "[[hand]]\n[[hand.waypoint]]\nto = \"port\"\n[[hand.waypoint]]\nto = \"fovea\"\nspeeed_mm_s = 2\n";
  EXPECT_NE(error_of(bad_key).find("s.toml:10: hand[0].waypoint[1].speeed_mm_s: unknown key"), std::string::npos) << error_of(bad_key);
  const std::string bad_value = std::string(kHead) + "[[hand]]\n[[hand.waypoint]]\nto = \"port\"\njaws = 1.5\n";
  EXPECT_NE(error_of(bad_value).find("s.toml:8: hand[0].waypoint[0].jaws: 1.5"), std::string::npos) << error_of(bad_value);
  const std::string wrong_type = std::string(kHead) + "[[hand]]\n[[hand.waypoint]]\nto = 3\n";
  EXPECT_NE(error_of(wrong_type).find("hand[0].waypoint[0].to: must be a non-empty string"), std::string::npos) << error_of(wrong_type);
  const std::string light_tool = std::string(kHead) + "[[hand]]\ntracker = 1\n[[hand.waypoint]]\nto = \"port\"\ntool = \"forceps\"\n";
  EXPECT_NE(error_of(light_tool).find("only the working hand"), std::string::npos) << error_of(light_tool);
  const std::string two = std::string(kHead) + "[[hand]]\n[[hand.waypoint]]\nto = \"port\"\n[[hand]]\n[[hand.waypoint]]\nto = \"port\"\n";
  EXPECT_NE(error_of(two).find("a second hand on tracker 0"), std::string::npos) << error_of(two);
  const std::string fault = std::string(kHead) + "[[fault]]\ndevice = \"tracker-0\"\nkind = \"melt\"\nat_s = 1\n";
  EXPECT_NE(error_of(fault).find("fault[0].kind: must be"), std::string::npos) << error_of(fault);
  EXPECT_NE(error_of("[script\n").find("s.toml:1"), std::string::npos) << error_of("[script\n");
}

class Resolving : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    cases_.push_back(scene_io::read_case_text((kScenes / "exercise_pull_tissue.toml").string()));
    scene_io::CaseLoadOptions o;
    o.retina_vertices = 5000;
    o.cache_dir = std::string(VITREO_CASE_CACHE_DIR);
    case_ = prepare_case(cases_, 0, o).release();
  }
  static void TearDownTestSuite() { delete case_; }
  static std::string resolve_error(const std::string& text) {
    try {
      (void)resolve_script(parse_surgical_script(text, "r.toml"), *case_, PedalMapping{});
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "";
  }
  static std::vector<scene_io::CaseText> cases_;
  static PreparedCase* case_;
};
std::vector<scene_io::CaseText> Resolving::cases_;
PreparedCase* Resolving::case_ = nullptr;

TEST_F(Resolving, WhatTheCaseLacksOrNoInstrumentReachesIsRefusedAtLoad) {
  const std::string tool = std::string(kHead) + "[[hand]]\n[[hand.waypoint]]\nto = \"port\"\ntool = \"vitrector\"\n";
  EXPECT_NE(resolve_error(tool).find("r.toml:8: hand[0].waypoint[0].tool: the case offers no vitrector"), std::string::npos) << resolve_error(tool);
  const std::string membrane = std::string(kHead) + "[[hand]]\n[[hand.waypoint]]\nto = \"membrane.erm.edge\"\n";
  EXPECT_NE(resolve_error(membrane).find("the case has no membrane 'erm'"), std::string::npos) << resolve_error(membrane);
  const std::string landmark = std::string(kHead) + "[[hand]]\n[[hand.waypoint]]\nto = \"macula_hole\"\n";
  EXPECT_NE(resolve_error(landmark).find("unknown landmark 'macula_hole'"), std::string::npos) << resolve_error(landmark);
  const std::string beyond = std::string(kHead) + "[[hand]]\n[[hand.waypoint]]\nto = \"fovea\"\nabove_mm = -2.0\n";
  EXPECT_NE(resolve_error(beyond).find("r.toml:7: hand[0].waypoint[0]: unreachable"), std::string::npos) << resolve_error(beyond);
  const std::string other = "[script]\nversion = 1\ncase = \"low_membrane_macula\"\n";
  EXPECT_NE(resolve_error(other).find("not for 'exercise_pull_tissue'"), std::string::npos) << resolve_error(other);
  EXPECT_EQ(resolve_error(std::string(kHead) + "[[hand]]\n[[hand.waypoint]]\nto = \"membrane.patch.mid\"\nabove_mm = 1.0\n"), "");
  // A membrane's attachment sites: numbered from the case, so site 999 is refused with the range.
  const std::string site = std::string(kHead) + "[[hand]]\n[[hand.waypoint]]\nto = \"membrane.patch.site.999\"\nabove_mm = 1.0\n";
  EXPECT_NE(resolve_error(site).find("r.toml:7: hand[0].waypoint[0].to: membrane.patch.site.999: no such site (0.."), std::string::npos)
      << resolve_error(site);
  const std::string bad_site = std::string(kHead) + "[[hand]]\n[[hand.waypoint]]\nto = \"membrane.patch.site.x\"\nabove_mm = 1.0\n";
  EXPECT_NE(resolve_error(bad_site).find("membrane.patch.site.x: no such site"), std::string::npos) << resolve_error(bad_site);
  EXPECT_EQ(resolve_error(std::string(kHead) + "[[hand]]\n[[hand.waypoint]]\nto = \"membrane.patch.site.0\"\nabove_mm = 1.0\n"), "");
}

TEST_F(Resolving, AStandoffPutsTheTipOnThePortLineShortOfItsPoint) {
  // An endolaser aims along its shaft: 2 mm short of the fovea on the line from the port through it.
  const std::string text = std::string(kHead) + "[[hand]]\n[[hand.waypoint]]\nto = \"fovea\"\nstandoff_mm = 2.0\n";
  const ResolvedScript r = resolve_script(parse_surgical_script(text, "s.toml"), *case_, PedalMapping{});
  drivers::sim::Script tracker;
  std::string err;
  ASSERT_TRUE(drivers::sim::parse_script(r.device_scripts.at("tracker-0"), tracker, &err)) << err;
  const core::Vec3 port = case_->tracker_ports[kToolTracker].position_mm;
  const core::Vec3 fovea = case_->scene->eye.fovea_mm;
  const core::Vec3 got(tracker.keys.back().second[0], tracker.keys.back().second[1], tracker.keys.back().second[2]);
  EXPECT_NEAR((fovea - got).norm(), 2.0, 1e-3);
  EXPECT_NEAR((got - port).norm() + 2.0, (fovea - port).norm(), 1e-3) << "on the segment from the port to the fovea";
  EXPECT_NE(error_of(std::string(kHead) + "[[hand]]\n[[hand.waypoint]]\nto = \"fovea\"\nstandoff_mm = -1.0\n").find("standoff_mm"), std::string::npos);
}

// Every fault kind a script names reaches its device's emulator as a line the emulator accepts,
// with its time, duration and (a clock jump only) size. Before, every kind but `jump` was written
// with a value the emulator refuses, and the device never started.
TEST_F(Resolving, EveryFaultKindReachesItsEmulator) {
  const char* kinds[] = {"nan", "range", "stuck", "jump", "version", "unknown", "drop", "disconnect"};
  std::string text = std::string(kHead) + "[[hand]]\n[[hand.waypoint]]\nto = \"port\"\nabove_mm = 3.0\n";
  for (int i = 0; i < 8; ++i) {
    text += "[[fault]]\ndevice = \"" + std::string(i % 2 ? "pedals" : "tracker-0") + "\"\nkind = \"" + kinds[i] + "\"\nat_s = " +
            std::to_string(1 + i) + "\nduration_s = 0.25\n" + (std::string(kinds[i]) == "jump" ? "value = 40.0\n" : "");
  }
  const ResolvedScript r = resolve_script(parse_surgical_script(text, "f.toml"), *case_, PedalMapping{});
  for (const char* device : {"tracker-0", "pedals"}) {
    drivers::sim::Script s;
    std::string err;
    ASSERT_TRUE(drivers::sim::parse_script(r.device_scripts.at(device), s, &err)) << device << ": " << err;
    ASSERT_EQ(s.faults.size(), 4u) << device;
    for (const auto& f : s.faults) {
      const int i = static_cast<int>(f.at_us / 1'000'000) - 1;
      EXPECT_EQ(f.at_us, static_cast<std::uint64_t>(1 + i) * 1'000'000u);
      EXPECT_EQ(f.duration_us, 250'000u);
      EXPECT_EQ(f.value, std::string(kinds[i]) == "jump" ? 40.0 : 0.0);
    }
  }
}

TEST_F(Resolving, ACaseCanPutTheWorkingHandThroughTheOtherPort) {
  // instruments.working_port = "working_2": the tool's tracker pivots about the port the light pipe
  // used, the light pipe's about the other, telemetry names the eye's ports, and a script's "port"
  // landmark follows.
  std::vector<scene_io::CaseText> swapped = cases_;
  const auto at = swapped[0].text.find("[instruments]\n");
  ASSERT_NE(at, std::string::npos);
  swapped[0].text.insert(at + 14, "working_port = \"working_2\"\n");
  scene_io::CaseLoadOptions o;
  o.retina_vertices = 5000;
  o.cache_dir = std::string(VITREO_CASE_CACHE_DIR);
  const auto c = prepare_case(swapped, 0, o);
  EXPECT_NEAR((c->tracker_ports[kToolTracker].position_mm - case_->tracker_ports[kSecondHandTracker].position_mm).norm(), 0.0, 1e-12);
  EXPECT_NEAR((c->tracker_ports[kSecondHandTracker].position_mm - case_->tracker_ports[kToolTracker].position_mm).norm(), 0.0, 1e-12);
  EXPECT_EQ(c->tracker_port_ids[kToolTracker], 2);
  EXPECT_EQ(case_->tracker_port_ids[kToolTracker], 1);
  EXPECT_NE(describe_instruments(*c).find("tracker 0 (working_2)"), std::string::npos) << describe_instruments(*c);
  const std::string text = std::string(kHead) + "[[hand]]\n[[hand.waypoint]]\nto = \"port\"\nabove_mm = 3.0\n";
  const ResolvedScript r = resolve_script(parse_surgical_script(text, "w.toml"), *c, PedalMapping{});
  drivers::sim::Script tracker;
  std::string err;
  ASSERT_TRUE(drivers::sim::parse_script(r.device_scripts.at("tracker-0"), tracker, &err)) << err;
  const Port& p = c->tracker_ports[kToolTracker];
  const core::Vec3 inside = p.position_mm - 3.0 * p.outward;
  const core::Vec3 got(tracker.keys.back().second[0], tracker.keys.back().second[1], tracker.keys.back().second[2]);
  EXPECT_NEAR((got - inside).norm(), 0.0, 1e-3);
}

TEST_F(Resolving, KeyframesLandOnTheLandmarksAtTheScriptedSpeeds) {
  // In through the port to 3 mm deep at 10 mm/s, then to 1 mm above the fovea at 4 mm/s, closing the jaws.
  const std::string text = std::string(kHead) +
                           "[[hand]]\nspeed_mm_s = 10.0\n[[hand.waypoint]]\nto = \"port\"\nabove_mm = 3.0\n"
                           "[[hand.waypoint]]\nto = \"fovea\"\nabove_mm = 1.0\nspeed_mm_s = 4.0\njaws = 1.0\n";
  const ResolvedScript r = resolve_script(parse_surgical_script(text, "k.toml"), *case_, PedalMapping{});
  drivers::sim::Script tracker;
  std::string err;
  ASSERT_TRUE(drivers::sim::parse_script(r.device_scripts.at("tracker-0"), tracker, &err)) << err;
  ASSERT_EQ(tracker.keys.size(), 3u);
  const Port& port = case_->tracker_ports[kToolTracker];
  const core::Vec3 start = port.position_mm + 2.0 * port.outward;  // outside the cannula
  const core::Vec3 inside = port.position_mm - 3.0 * port.outward;
  const core::Scene& scene = *case_->scene;
  const core::Vec3 inward = (scene.eye.wall.center() - scene.eye.fovea_mm).normalized();
  const core::Vec3 over_fovea = scene.eye.fovea_mm + 1.0 * inward;
  auto at = [&](std::size_t k) { return core::Vec3(tracker.keys[k].second[0], tracker.keys[k].second[1], tracker.keys[k].second[2]); };
  EXPECT_NEAR((at(0) - start).norm(), 0.0, 1e-3);
  EXPECT_NEAR((at(1) - inside).norm(), 0.0, 1e-3);
  EXPECT_NEAR((at(2) - over_fovea).norm(), 0.0, 1e-3);
  const double t1 = (inside - start).norm() / 10.0, t2 = t1 + (over_fovea - inside).norm() / 4.0;
  EXPECT_NEAR(static_cast<double>(tracker.keys[1].first) * 1e-6, t1, 1e-3);
  EXPECT_NEAR(static_cast<double>(tracker.keys[2].first) * 1e-6, t2, 1e-3);
  EXPECT_DOUBLE_EQ(tracker.keys[2].second[6], 1.0);  // jaws closed on arrival
  EXPECT_NEAR(r.path_mm[0], (inside - start).norm() + (over_fovea - inside).norm(), 1e-6);
  // The pedals and the fixture play along, at rest.
  drivers::sim::Script pedals;
  ASSERT_TRUE(drivers::sim::parse_script(r.device_scripts.at("pedals"), pedals, &err)) << err;
  for (const auto& k : pedals.keys) EXPECT_EQ(k.second[0], 0.0);
}

TEST_F(Resolving, PedalsAndToolSwitchesFollowTheWaypoints) {
  // Select the pick (one instrument-switch press, bit 2 by default), vacuum 0.5 from the second waypoint.
  const std::string text = std::string(kHead) +
                           "[[hand]]\n[[hand.waypoint]]\nto = \"port\"\nabove_mm = 3.0\ntool = \"pick\"\n"
                           "[[hand.waypoint]]\nto = \"port\"\nabove_mm = 4.0\nvacuum = 0.5\n";
  const ResolvedScript r = resolve_script(parse_surgical_script(text, "p.toml"), *case_, PedalMapping{});
  drivers::sim::Script pedals;
  std::string err;
  ASSERT_TRUE(drivers::sim::parse_script(r.device_scripts.at("pedals"), pedals, &err)) << err;
  int presses = 0;
  bool down = false;
  double last_vacuum = 0.0;
  for (const auto& k : pedals.keys) {
    const bool pressed = (static_cast<unsigned>(k.second[2]) & (1u << PedalMapping{}.instrument_switch)) != 0;
    if (pressed && !down) ++presses;
    down = pressed;
    last_vacuum = k.second[0];
  }
  EXPECT_EQ(presses, 1);
  EXPECT_DOUBLE_EQ(last_vacuum, 0.5);
  // The light pipe's pick: its own switch held from its waypoint on, never the laser's.
  const ResolvedScript picked = resolve_script(
      parse_surgical_script(std::string(kHead) + "[[hand]]\n[[hand.waypoint]]\nto = \"port\"\nabove_mm = 3.0\npick = true\n", "k.toml"), *case_,
      PedalMapping{});
  drivers::sim::Script pick_pedals;
  ASSERT_TRUE(drivers::sim::parse_script(picked.device_scripts.at("pedals"), pick_pedals, &err)) << err;
  const unsigned last_switches = static_cast<unsigned>(pick_pedals.keys.back().second[2]);
  EXPECT_EQ(last_switches, 1u << PedalMapping{}.pick_switch);
  // The presses choose the tool only because the working hand's handpiece names none (tool type 0):
  // a handpiece that names its tool would pin it (rig/runtime/README.md, tracker mapping).
  drivers::sim::Script hand;
  ASSERT_TRUE(drivers::sim::parse_script(r.device_scripts.at("tracker-0"), hand, &err)) << err;
  EXPECT_EQ(hand.tool, 0);
}

}  // namespace
}  // namespace vitreo::rig

namespace vitreo::rig {
namespace {

// The microscope pedal a script works, played key by key (linearly between keys, as the emulator
// plays them) through the rig's own pedal mapping into the core's microscope, 1 ms a step: where
// the field's centre, the zoom and the focus end up — checked against the landmark's place on the
// fundus, not against the resolver's arithmetic.
struct MicroscopeEnd {
  core::Vec2 centre;
  double zoom, focus, light;
};
MicroscopeEnd play_microscope_pedal(const std::string& emulator_script, const PreparedCase& c, double seconds) {
  drivers::sim::Script s;
  std::string err;
  EXPECT_TRUE(drivers::sim::parse_script(emulator_script, s, &err)) << err;
  EXPECT_EQ(s.pedal_id, 1);
  EXPECT_EQ(s.pedal_axes, 4);
  PedalMapper mapper;
  core::MicroscopeSettings settings;
  core::Microscope microscope(settings, c.scene->eye.fundus_coords(c.focus_mm));
  for (int k = 0; k < static_cast<int>(seconds * 1000); ++k) {
    const auto t_us = static_cast<std::uint64_t>(k) * 1000;
    std::vector<double> v = s.keys.back().second;
    for (std::size_t i = 0; i + 1 < s.keys.size(); ++i) {
      if (t_us >= s.keys[i].first && t_us < s.keys[i + 1].first) {
        const double f = static_cast<double>(t_us - s.keys[i].first) / static_cast<double>(s.keys[i + 1].first - s.keys[i].first);
        for (std::size_t j = 0; j < v.size(); ++j) v[j] = s.keys[i].second[j] + f * (s.keys[i + 1].second[j] - s.keys[i].second[j]);
        v[4] = s.keys[i].second[4];  // switches are held from the earlier key, not blended
        break;
      }
    }
    const SurgicalControls before = mapper.controls();
    PedalReading r;
    r.pedal_id = 1;
    r.axis_count = 4;
    for (int a = 0; a < 4; ++a) r.axes[a] = v[static_cast<std::size_t>(a)];
    r.switches = static_cast<std::uint16_t>(v[4]);
    EXPECT_TRUE(mapper.apply(r));
    if (mapper.controls().zoom != before.zoom) microscope.set_zoom(mapper.controls().zoom);
    if (mapper.controls().focus_offset_mm != before.focus_offset_mm) microscope.set_focus(mapper.controls().focus_offset_mm);
    microscope.step(0.001, core::MicroscopeInput{core::Vec2(mapper.controls().pan_x, mapper.controls().pan_y)});
  }
  return {microscope.center_mm(), microscope.zoom(), microscope.focus_mm(), mapper.controls().light_level};
}

TEST_F(Resolving, AScriptWorksTheMicroscopeAndLookAtCentresTheFieldOnItsLandmark) {
  const std::string text = std::string(kHead) +
                           "[[hand]]\n[[hand.waypoint]]\nto = \"port\"\nabove_mm = 3.0\nzoom = 2.0\nduration_s = 0.5\n"
                           "[[hand.waypoint]]\nto = \"port\"\nabove_mm = 3.5\nlook_at = \"disc\"\nduration_s = 0.5\n"
                           "[[hand.waypoint]]\nto = \"port\"\nabove_mm = 3.0\nat_s = 3.0\nfocus_mm = 1.0\nlight = 0.4\n";
  const SurgicalScript script = parse_surgical_script(text, "m.toml");
  EXPECT_TRUE(works_microscope(script));
  const ResolvedScript r = resolve_script(script, *case_, PedalMapping{});
  ASSERT_TRUE(r.device_scripts.count(kMicroscopePedalDevice));
  const MicroscopeEnd end = play_microscope_pedal(r.device_scripts.at(kMicroscopePedalDevice), *case_, 4.0);
  const core::Vec2 disc = case_->scene->eye.fundus_coords(case_->scene->eye.optic_disc_mm);
  const core::Vec2 start = case_->scene->eye.fundus_coords(case_->focus_mm);
  std::printf("field centre from (%.3f, %.3f) to (%.3f, %.3f) mm; the disc at (%.3f, %.3f) mm; zoom %.2f, focus %.2f mm\n", start.x(),
              start.y(), end.centre.x(), end.centre.y(), disc.x(), disc.y(), end.zoom, end.focus);
  EXPECT_GT((disc - start).norm(), 2.0) << "a pan worth testing";
  EXPECT_LT((end.centre - disc).norm(), 0.05) << "the field's centre on the disc";
  EXPECT_NEAR(end.zoom, 2.0, 1e-3);
  EXPECT_NEAR(end.focus, 1.0, 1e-3);
  EXPECT_NEAR(end.light, 0.4, 1e-9) << "three presses of the light's down switch from 0.7";
  // A script that leaves the microscope alone has no microscope pedal.
  EXPECT_FALSE(works_microscope(parse_surgical_script(std::string(kHead) + "[[hand]]\n[[hand.waypoint]]\nto = \"port\"\n", "n.toml")));
  EXPECT_FALSE(resolve_script(parse_surgical_script(std::string(kHead) + "[[hand]]\n[[hand.waypoint]]\nto = \"port\"\n", "n.toml"), *case_,
                              PedalMapping{})
                   .device_scripts.count(kMicroscopePedalDevice));
}

TEST_F(Resolving, MicroscopeChangesTheRigCannotMakeAreRefusedWithLineAndKey) {
  EXPECT_EQ(resolve_error(std::string(kHead) + "[[hand]]\n[[hand.waypoint]]\nto = \"port\"\nzoom = 9.0\n"),
            "r.toml:6: hand[0].waypoint[0].zoom: the microscope pedal zooms 1.000000 .. 4.000000");
  EXPECT_EQ(resolve_error(std::string(kHead) + "[[hand]]\n[[hand.waypoint]]\nto = \"port\"\nfocus_mm = 3.5\n"),
            "r.toml:6: hand[0].waypoint[0].focus_mm: the microscope pedal focuses ±3.000000 mm");
  EXPECT_NE(resolve_error(std::string(kHead) + "[[hand]]\n[[hand.waypoint]]\nto = \"port\"\nlook_at = \"macula_hole\"\n")
                .find("r.toml:8: hand[0].waypoint[0].look_at: unknown landmark 'macula_hole'"),
            std::string::npos);
  EXPECT_NE(resolve_error(std::string(kHead) + "[[hand]]\n[[hand.waypoint]]\nto = \"port\"\nlook_at = \"disc\"\n"
                                               "[[hand.waypoint]]\nto = \"port\"\nabove_mm = 1.0\nduration_s = 0.1\nzoom = 2.0\n")
                .find("r.toml:9: hand[0].waypoint[1].look_at: the field is still panning"),
            std::string::npos);
}

}  // namespace
}  // namespace vitreo::rig
