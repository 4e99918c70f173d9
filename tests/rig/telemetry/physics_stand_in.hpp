#pragma once
// What physics does with operator commands, for tests of the command server without a session:
// poll, decide against the state the previous command left, apply, report (rig_session.cpp does the
// same with the real model), then let the server publish the acks that are due.
#include <vector>

#include "rig/telemetry/commands.hpp"

namespace vitreo::test {

struct PhysicsStandIn {
  telemetry::CommandContext ctx;
  std::vector<telemetry::AcceptedCommand> applied;

  void step(telemetry::CommandServer& server) {
    telemetry::AcceptedCommand a;
    while (server.poll(a)) {
      const telemetry::CommandContext before = ctx;
      const telemetry::CommandRefusal why = telemetry::decide_command(a.code, ctx);
      if (why == telemetry::CommandRefusal::None) {
        switch (a.code) {
          case telemetry::CommandCode::Pause: ctx.paused = true; break;
          case telemetry::CommandCode::Resume: ctx.paused = false; break;
          case telemetry::CommandCode::NextCase: ++ctx.case_index; break;
          case telemetry::CommandCode::PreviousCase: --ctx.case_index; break;
          default: break;
        }
        applied.push_back(a);
      }
      server.report(a, why, before);
    }
    server.pump_local();
  }
};

}  // namespace vitreo::test
