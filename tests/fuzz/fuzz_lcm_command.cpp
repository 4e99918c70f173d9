// libFuzzer target: the rig's whole receive path for operator commands. The input is published as
// a raw packet on VITREO_COMMAND of a memq LCM; the checked subscription decodes it and hands it to
// a real CommandServer, a stand-in for physics decides it, the ack goes out. Invariants: every
// packet is counted as received, and exactly one of refused-undecoded or answered-by-an-ack.
#include <lcm/lcm.h>

#include <cstdint>
#include <cstdlib>

#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>

#include "rig/telemetry/channels.hpp"
#include "rig/telemetry/commands.hpp"
#include "rig/telemetry/lcm_subscribe.hpp"
#include "tests/rig/telemetry/physics_stand_in.hpp"
#include "vitreo_lcm/command_ack_t.hpp"

using namespace vitreo::telemetry;

namespace {
struct World {
  lcm::LCM lc{"memq://"};
  CommandServer server{lc, 8};
  vitreo::test::PhysicsStandIn physics;
  std::uint64_t acks = 0;
  struct Count {
    std::uint64_t* n;
    void operator()(const vitreo_lcm::command_ack_t&) { ++*n; }
  } count{&acks};
  CheckedSubscription ack_sub = subscribe_to<vitreo_lcm::command_ack_t>(lc, kChanCommandAck, &count);
  World() {
    spdlog::set_level(spdlog::level::off);
    physics.ctx.case_count = 3;
  }
};
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static World w;
  const auto before_rx = w.server.receive_counters().received();
  const auto before_bad = w.server.receive_counters().rejected();
  const auto before_acks = w.acks;
  if (lcm_publish(w.lc.getUnderlyingLCM(), kChanCommand, data, static_cast<unsigned>(size)) != 0) return 0;
  while (w.lc.handleTimeout(0) > 0) {
  }
  w.physics.step(w.server);  // decide, then publish the due acks
  while (w.lc.handleTimeout(0) > 0) {
  }
  const auto rx = w.server.receive_counters().received() - before_rx;
  const auto bad = w.server.receive_counters().rejected() - before_bad;
  const auto acks = w.acks - before_acks;
  if (rx != 1 || bad + acks != 1 || w.server.pending() != 0) std::abort();
  if (w.server.receive_counters().handler_errors() != 0) std::abort();
  return 0;
}
