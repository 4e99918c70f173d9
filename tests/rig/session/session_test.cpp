// Whole sessions: firmware emulators behind ptys → the real serial drivers → the fixed-step physics
// thread on the retina → telemetry to an LCM log and a recording → replay. Wall-clock timing decides
// which samples each step sees, so only the recording can reproduce a run: the replay must end in
// the same state hash.
#include <gtest/gtest.h>
#include <unistd.h>

#include <lcm/lcm-cpp.hpp>

#include <cstdio>
#include <filesystem>
#include <cmath>
#include <map>
#include <string>

#include "rig/session/rig_session.hpp"
#include "rig/telemetry/channels.hpp"
#include "vitreo_lcm/device_status_t.hpp"
#include "vitreo_lcm/instrument_state_t.hpp"

using namespace vitreo;

namespace {

const char* kTracker =
    "device tracker\nrate_hz 1000\nserial 1001\ntool 3\ninstrument 0\n"
    "key 0 -12.5 3.7 6.2 0 0 0 0\nkey 500 -8 0.5 -4.5 0 0 0 0\nkey 1000 -7 -1.5 -3.5 0 0 20 1\n"
    "key 1500 -12.5 3.7 6.2 0 0 0 0\n";
const char* kPedals = "device pedals\nrate_hz 500\nserial 2001\nkey 0 0 0 0\nkey 400 0.7 0.2 0\nkey 1200 0 0 0\n";

std::string temp_path(const std::string& name) {
  return (std::filesystem::path(::testing::TempDir()) / ("vitreo-" + std::to_string(::getpid()) + "-" + name)).string();
}

rig::SessionConfig small_session(const std::string& tag, std::uint64_t steps) {
  rig::SessionConfig c;
  c.model.scene.retina_vertices = 2000;
  c.model.scene.membrane = true;
  rig::Port port;
  port.outward = core::Vec3(-0.81, 0.29, 0.5).normalized();
  port.position_mm = 11.5 * port.outward;
  c.model.ports = {port};
  c.steps = steps;
  c.lcm_url = "file://" + temp_path(tag + "-telemetry.lcmlog") + "?mode=w";
  c.record_path = temp_path(tag + "-session.lcmlog");
  c.devices = {{"tracker-0", temp_path(tag + "-tracker"), 1, 0, kTracker}, {"pedals", temp_path(tag + "-pedals"), 2, 0, kPedals}};
  return c;
}

}  // namespace

TEST(RigSession, ARecordedSessionReplaysToTheSameState) {
  const auto config = small_session("replay", 1500);
  const rig::SessionSummary live = rig::run_session(config);
  EXPECT_EQ(live.steps, 1500u);
  EXPECT_GT(live.inputs_applied, 500u) << "the simulated devices streamed";
  EXPECT_EQ(live.inputs_refused, 0u);
  EXPECT_EQ(live.recorder_dropped, 0u);
  EXPECT_EQ(live.inputs_recorded, live.inputs_applied + live.inputs_refused);

  const rig::ReplaySummary replay = rig::replay_session(config.record_path, config.model);
  EXPECT_EQ(replay.steps, live.steps);
  EXPECT_EQ(replay.state_hash, live.state_hash) << "replay diverged from the live session";
  const double speed = static_cast<double>(replay.steps) * 1e-3 / replay.wall_s;
  std::printf("replay of %llu steps: %.1fx real time\n", static_cast<unsigned long long>(replay.steps), speed);
  std::filesystem::remove(config.record_path);
}

TEST(RigSession, ALostTrackerFreezesItsInstrumentAndTheSessionCarriesOn) {
  auto config = small_session("lost", 2000);
  // Pull the tracker's cable at 0.5 s and plug it back at 1.2 s.
  config.on_step = [](std::uint64_t step, rig::DeviceHub& hub) {
    if (step == 500) hub.unplug(0);
    if (step == 1200) hub.plug(0);
  };
  const rig::SessionSummary live = rig::run_session(config);
  EXPECT_EQ(live.steps, 2000u) << "the simulation kept running while the device was gone";
  EXPECT_EQ(live.rolled_back, 0u);
  // The loss is seen at once (hang-up); frozen from ~step 500 until streaming again after 1200.
  EXPECT_GT(live.frozen_steps, 500u);
  EXPECT_LT(live.frozen_steps, 1200u) << "the instrument resumed after the reconnect";
  // The freeze was recorded, so the replay freezes at the same steps.
  const rig::ReplaySummary replay = rig::replay_session(config.record_path, config.model);
  EXPECT_EQ(replay.state_hash, live.state_hash);

  // The loss went out on telemetry: a device status "lost" for the tracker, then "active" again.
  lcm::LogFile log(config.lcm_url.substr(7, config.lcm_url.find('?') - 7), "r");
  ASSERT_TRUE(log.good());
  bool saw_lost = false, saw_active_after = false;
  int instrument_states = 0, frozen_states = 0;
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    if (ev->channel == telemetry::kChanDeviceStatus) {
      vitreo_lcm::device_status_t s;
      ASSERT_GE(s.decode(ev->data, 0, ev->datalen), 0);
      if (s.name == "tracker-0" && s.state == vitreo_lcm::device_status_t::STATE_LOST) saw_lost = true;
      if (saw_lost && s.name == "tracker-0" && s.state == vitreo_lcm::device_status_t::STATE_ACTIVE) saw_active_after = true;
    } else if (ev->channel == telemetry::kChanInstrumentState) {
      vitreo_lcm::instrument_state_t s;
      ASSERT_GE(s.decode(ev->data, 0, ev->datalen), 0);
      ++instrument_states;
      frozen_states += s.frozen ? 1 : 0;
    }
  }
  EXPECT_TRUE(saw_lost);
  EXPECT_TRUE(saw_active_after);
  EXPECT_GT(instrument_states, 300);
  EXPECT_GT(frozen_states, 100) << "telemetry shows the instrument frozen while its tracker was lost";
  std::filesystem::remove(config.record_path);
}

TEST(RigSession, RendersStereoFramesOfTheRunAndTheLastOne) {
  auto config = small_session("render", 600);
  config.render = true;
  config.eye_width = 160;
  config.eye_height = 128;
  config.png_dir = temp_path("frames");
  config.png_every_frames = 5;
  std::filesystem::create_directories(config.png_dir);
  const rig::SessionSummary s = rig::run_session(config);
  EXPECT_GT(s.frames_rendered, 0u);
  ASSERT_FALSE(s.pngs.empty());
  // The last frame shows the last step.
  EXPECT_NE(s.pngs.back().find("step_000000599"), std::string::npos) << s.pngs.back();
  EXPECT_TRUE(std::filesystem::exists(s.pngs.back() + "_stereo.png")) << s.pngs.back();
  std::filesystem::remove_all(config.png_dir);
}

TEST(SimulationModel, OperatorCommandsAreRecordedInputs) {
  rig::ModelConfig mc;
  mc.scene.retina_vertices = 500;
  rig::SimulationModel model(mc);
  rig::SimulationModel fresh(mc);
  auto command = [](int code, double value) {
    telemetry::DeviceInput in;
    in.device_kind = rig::kCommandKind;
    in.n_values = 2;
    in.values[0] = code;
    in.values[1] = value;
    return in;
  };
  for (int i = 0; i < 50; ++i) model.step();
  const auto moved = model.world().state_hash();
  EXPECT_NE(moved, fresh.world().state_hash());
  ASSERT_TRUE(model.apply(command(3, 0)));  // pause
  for (int i = 0; i < 20; ++i) model.step();
  EXPECT_EQ(model.world().state_hash(), moved) << "paused physics does not advance";
  ASSERT_TRUE(model.apply(command(4, 0)));  // resume
  ASSERT_TRUE(model.apply(command(5, 0)));  // reset
  EXPECT_EQ(model.world().state_hash(), fresh.world().state_hash()) << "reset returns the case to its start";
  ASSERT_TRUE(model.apply(command(9, 2.5)));
  EXPECT_EQ(model.zoom_override(), 2.5);
  telemetry::DeviceInput bad = command(9, std::nan(""));
  EXPECT_FALSE(model.apply(bad));
  EXPECT_EQ(model.zoom_override(), 2.5);
}
