// Operator commands: validation rules, and the CommandServer over a real memq LCM (commands in,
// acknowledgements out, accepted commands queued to physics).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "rig/telemetry/channels.hpp"
#include "rig/telemetry/commands.hpp"
#include "rig/telemetry/items.hpp"
#include "rig/telemetry/lcm_subscribe.hpp"
#include "tests/rig/telemetry/physics_stand_in.hpp"
#include "vitreo_lcm/command_ack_t.hpp"
#include "vitreo_lcm/operator_command_t.hpp"

using namespace vitreo::telemetry;
using Cmd = vitreo_lcm::operator_command_t;

namespace {
Cmd make(std::int8_t code, std::int64_t seq = 1, double value = 0, std::string arg = {}, std::string source = "test") {
  Cmd c;
  c.utime_us = 0;
  c.source = std::move(source);
  c.seq = seq;
  c.command = code;
  c.value = value;
  c.arg = std::move(arg);
  return c;
}
}  // namespace

TEST(CommandValidation, AcceptsValidCommandsAndRefusesBadOnesWithAReason) {
  CommandContext ctx;
  ctx.case_index = 0;
  ctx.case_count = 3;
  ctx.paused = false;
  EXPECT_TRUE(validate_command(make(Cmd::NEXT_CASE), ctx).accepted);
  EXPECT_FALSE(validate_command(make(Cmd::PREVIOUS_CASE), ctx).accepted);
  EXPECT_EQ(validate_command(make(Cmd::PREVIOUS_CASE), ctx).reason, "already at the first case");
  ctx.case_index = 2;
  EXPECT_FALSE(validate_command(make(Cmd::NEXT_CASE), ctx).accepted);
  EXPECT_TRUE(validate_command(make(Cmd::PREVIOUS_CASE), ctx).accepted);

  EXPECT_TRUE(validate_command(make(Cmd::PAUSE), ctx).accepted);
  EXPECT_FALSE(validate_command(make(Cmd::RESUME), ctx).accepted);
  ctx.paused = true;
  EXPECT_FALSE(validate_command(make(Cmd::PAUSE), ctx).accepted);
  EXPECT_TRUE(validate_command(make(Cmd::RESUME), ctx).accepted);

  EXPECT_TRUE(validate_command(make(Cmd::RESET), ctx).accepted);
  EXPECT_TRUE(validate_command(make(Cmd::TOGGLE_WIREFRAME), ctx).accepted);
  EXPECT_TRUE(validate_command(make(Cmd::TOGGLE_LABELS), ctx).accepted);

  EXPECT_TRUE(validate_command(make(Cmd::ZOOM, 1, 10.0), ctx).accepted);
  EXPECT_TRUE(validate_command(make(Cmd::ZOOM, 1, 25.0), ctx).accepted);
  EXPECT_FALSE(validate_command(make(Cmd::ZOOM, 1, 0.5), ctx).accepted);
  EXPECT_FALSE(validate_command(make(Cmd::ZOOM, 1, 26.0), ctx).accepted);
  EXPECT_FALSE(validate_command(make(Cmd::ZOOM, 1, std::nan("")), ctx).accepted);
  EXPECT_FALSE(validate_command(make(Cmd::ZOOM, 1, std::numeric_limits<double>::infinity()), ctx).accepted);

  EXPECT_TRUE(validate_command(make(Cmd::PAN, 1, 1.5, "-2"), ctx).accepted);
  EXPECT_TRUE(validate_command(make(Cmd::PAN, 1, -20.0, "20"), ctx).accepted);
  EXPECT_FALSE(validate_command(make(Cmd::PAN, 1, 21.0, "0"), ctx).accepted);
  EXPECT_FALSE(validate_command(make(Cmd::PAN, 1, 0.0, "-21"), ctx).accepted);
  EXPECT_FALSE(validate_command(make(Cmd::PAN, 1, 0.0, ""), ctx).accepted) << "y is required";
  EXPECT_FALSE(validate_command(make(Cmd::PAN, 1, 0.0, "2mm"), ctx).accepted);
  EXPECT_FALSE(validate_command(make(Cmd::PAN, 1, std::nan(""), "0"), ctx).accepted);
  EXPECT_TRUE(validate_command(make(Cmd::FOCUS, 1, 3.0), ctx).accepted);
  EXPECT_FALSE(validate_command(make(Cmd::FOCUS, 1, -3.5), ctx).accepted);
  EXPECT_FALSE(validate_command(make(Cmd::FOCUS, 1, std::nan("")), ctx).accepted);
  EXPECT_TRUE(validate_command(make(Cmd::TOGGLE_SHADING), ctx).accepted);
  EXPECT_TRUE(validate_command(make(Cmd::TOGGLE_WIDE_ANGLE), ctx).accepted);
  EXPECT_TRUE(validate_command(make(Cmd::TOGGLE_REINVERTER), ctx).accepted);

  // The endolaser's settings: 50..2000 mW, 10..2000 ms (a pulse per shot, never 0: no continuous mode).
  EXPECT_TRUE(validate_command(make(Cmd::LASER_POWER, 1, 50.0), ctx).accepted);
  EXPECT_TRUE(validate_command(make(Cmd::LASER_POWER, 1, 2000.0), ctx).accepted);
  EXPECT_EQ(validate_command(make(Cmd::LASER_POWER, 1, 2500.0), ctx).reason, "laser power 2500 mW outside the rig's range 50..2000 mW");
  EXPECT_FALSE(validate_command(make(Cmd::LASER_POWER, 1, 49.0), ctx).accepted);
  EXPECT_FALSE(validate_command(make(Cmd::LASER_POWER, 1, std::nan("")), ctx).accepted);
  EXPECT_TRUE(validate_command(make(Cmd::LASER_DURATION, 1, 10.0), ctx).accepted);
  EXPECT_TRUE(validate_command(make(Cmd::LASER_DURATION, 1, 2000.0), ctx).accepted);
  EXPECT_EQ(validate_command(make(Cmd::LASER_DURATION, 1, 0.0), ctx).reason,
            "laser pulse 0 ms outside the rig's range 10..2000 ms (a pulse per shot: no continuous mode)");
  EXPECT_FALSE(validate_command(make(Cmd::LASER_DURATION, 1, 2001.0), ctx).accepted);
  EXPECT_FALSE(validate_command(make(Cmd::LASER_DURATION, 1, -std::numeric_limits<double>::infinity()), ctx).accepted);

  EXPECT_TRUE(validate_command(make(Cmd::SAVE_SNAPSHOT, 1, 0, "before-peel_2.v1"), ctx).accepted);
  for (const char* bad : {"", "../etc/passwd", "a/b", ".hidden", "spa ce", "x\n"}) {
    const Verdict v = validate_command(make(Cmd::SAVE_SNAPSHOT, 1, 0, bad), ctx);
    EXPECT_FALSE(v.accepted) << "'" << bad << "'";
    EXPECT_FALSE(v.reason.empty());
  }
  EXPECT_FALSE(validate_command(make(Cmd::SAVE_SNAPSHOT, 1, 0, std::string(65, 'a')), ctx).accepted);

  const Verdict unknown = validate_command(make(42), ctx);
  EXPECT_FALSE(unknown.accepted);
  EXPECT_EQ(unknown.reason, "unknown command code 42");
}

TEST(CommandServer, AcksEveryCommandInOrderOnceItsOutcomeIsKnown) {
  lcm::LCM lc("memq://");
  ASSERT_TRUE(lc.good());
  CommandServer server(lc);
  struct Acks {
    std::vector<vitreo_lcm::command_ack_t> got;
    void operator()(const vitreo_lcm::command_ack_t& a) { got.push_back(a); }
  } acks;
  auto sub1 = subscribe_to<vitreo_lcm::command_ack_t>(lc, kChanCommandAck, &acks);
  vitreo::test::PhysicsStandIn physics;  // case 1 of 2, running
  physics.ctx.case_count = 2;

  const std::vector<Cmd> sent = {
      make(Cmd::ZOOM, 1, 12.5),
      make(Cmd::PREVIOUS_CASE, 2),                 // refused by physics: first case
      make(Cmd::ZOOM, 2, 8.0),                     // refused by the server: seq 2 again from "test"
      make(Cmd::SAVE_SNAPSHOT, 3, 0, "peel-start"),
      make(Cmd::PAUSE, 1, 0, {}, "instructor-ui"),  // another source has its own sequence
      make(Cmd::RESUME, 4),                        // decided after the pause: accepted
      make(Cmd::PAUSE, 5, 0, {}, ""),              // refused by the server: no source
  };
  for (const auto& c : sent) lc.publish(kChanCommand, &c);
  while (lc.handleTimeout(0) > 0) {
  }
  EXPECT_TRUE(acks.got.empty()) << "no ack before physics decided the commands ahead of it";
  physics.step(server);
  while (lc.handleTimeout(0) > 0) {
  }

  ASSERT_EQ(acks.got.size(), 7u);
  const std::vector<bool> want = {true, false, false, true, true, true, false};
  for (std::size_t i = 0; i < want.size(); ++i) {
    EXPECT_EQ(static_cast<bool>(acks.got[i].accepted), want[i]) << i << ": " << acks.got[i].reason;
    EXPECT_EQ(acks.got[i].seq, sent[i].seq);
    EXPECT_EQ(acks.got[i].command, sent[i].command);
    EXPECT_EQ(acks.got[i].source, sent[i].source);
  }
  EXPECT_EQ(acks.got[1].reason, "already at the first case");
  EXPECT_NE(acks.got[2].reason.find("duplicate or reordered"), std::string::npos) << acks.got[2].reason;
  EXPECT_EQ(acks.got[6].reason, "command has no source");
  EXPECT_EQ(server.accepted(), 4u);
  EXPECT_EQ(server.refused(), 3u);
  ASSERT_EQ(physics.applied.size(), 4u);
  EXPECT_EQ(physics.applied[0].code, CommandCode::Zoom);
  EXPECT_DOUBLE_EQ(physics.applied[0].value, 12.5);
  EXPECT_EQ(physics.applied[1].code, CommandCode::SaveSnapshot);
  EXPECT_STREQ(physics.applied[1].arg, "peel-start");
  EXPECT_FALSE(physics.ctx.paused) << "pause then resume: running, as the last command said";
}

// Issue 20: "pause" and "resume" typed together gave pause accepted, resume refused ("physics is
// not paused") — decided against a state one step stale — and left the session paused.
TEST(CommandServer, PauseThenResumeTypedTogetherLeaveTheSessionRunning) {
  lcm::LCM lc("memq://");
  CommandServer server(lc);
  vitreo::test::PhysicsStandIn physics;
  LocalCommand pause, resume;
  pause.command = Cmd::PAUSE;
  pause.seq = 1;
  copy_text(pause.source, "terminal");
  resume = pause;
  resume.command = Cmd::RESUME;
  resume.seq = 2;
  ASSERT_TRUE(server.submit(pause));
  ASSERT_TRUE(server.submit(resume));
  server.pump_local();  // both checked and queued in the same telemetry tick
  physics.step(server);
  LocalAck a1, a2;
  ASSERT_TRUE(server.poll_ack(a1));
  ASSERT_TRUE(server.poll_ack(a2));
  EXPECT_TRUE(a1.accepted) << a1.reason;
  EXPECT_TRUE(a2.accepted) << a2.reason;
  EXPECT_EQ(a1.seq, 1);
  EXPECT_EQ(a2.seq, 2);
  EXPECT_FALSE(physics.ctx.paused);
}

TEST(CommandServer, FullPhysicsQueueRefusesWithAReason) {
  lcm::LCM lc("memq://");
  CommandServer server(lc, 2);
  struct Acks {
    std::vector<vitreo_lcm::command_ack_t> got;
    void operator()(const vitreo_lcm::command_ack_t& a) { got.push_back(a); }
  } acks;
  auto sub2 = subscribe_to<vitreo_lcm::command_ack_t>(lc, kChanCommandAck, &acks);
  for (int i = 1; i <= 3; ++i) {
    const Cmd c = make(Cmd::TOGGLE_LABELS, i);
    lc.publish(kChanCommand, &c);
  }
  while (lc.handleTimeout(0) > 0) {
  }
  vitreo::test::PhysicsStandIn physics;
  physics.step(server);
  while (lc.handleTimeout(0) > 0) {
  }
  ASSERT_EQ(acks.got.size(), 3u);
  EXPECT_TRUE(acks.got[0].accepted);
  EXPECT_TRUE(acks.got[1].accepted);
  EXPECT_FALSE(acks.got[2].accepted);
  EXPECT_EQ(acks.got[2].reason, "physics command queue is full");
}

TEST(CommandServer, CommandsPhysicsNeverDecidedAreRefusedWhenTheSessionEnds) {
  lcm::LCM lc("memq://");
  CommandServer server(lc);
  struct Acks {
    std::vector<vitreo_lcm::command_ack_t> got;
    void operator()(const vitreo_lcm::command_ack_t& a) { got.push_back(a); }
  } acks;
  auto sub3 = subscribe_to<vitreo_lcm::command_ack_t>(lc, kChanCommandAck, &acks);
  const Cmd c = make(Cmd::RESET, 1);
  lc.publish(kChanCommand, &c);
  while (lc.handleTimeout(0) > 0) {
  }
  server.abandon_pending("the session ended");
  while (lc.handleTimeout(0) > 0) {
  }
  ASSERT_EQ(acks.got.size(), 1u);
  EXPECT_FALSE(acks.got[0].accepted);
  EXPECT_EQ(acks.got[0].reason, "the session ended");
}

TEST(CommandLine, ParsesTheTerminalSpellingAndRejectsBadSyntax) {
  struct Case {
    const char* line;
    std::int8_t code;
    double value;
    const char* arg;
  };
  for (const Case& k : {Case{"n", Cmd::NEXT_CASE, 0, ""}, Case{"previous", Cmd::PREVIOUS_CASE, 0, ""},
                        Case{" ", Cmd::PAUSE, 0, ""}, Case{"pause", Cmd::PAUSE, 0, ""},
                        Case{"resume", Cmd::RESUME, 0, ""}, Case{"  r  ", Cmd::RESET, 0, ""},
                        Case{"w", Cmd::TOGGLE_WIREFRAME, 0, ""}, Case{"labels", Cmd::TOGGLE_LABELS, 0, ""},
                        Case{"s before-peel", Cmd::SAVE_SNAPSHOT, 0, "before-peel"},
                        Case{"zoom 12.5", Cmd::ZOOM, 12.5, ""}, Case{"z 8\n", Cmd::ZOOM, 8, ""},
                        Case{"pan 1.5 -2", Cmd::PAN, 1.5, "-2"}, Case{"focus -0.75", Cmd::FOCUS, -0.75, ""},
                        Case{"flat", Cmd::TOGGLE_SHADING, 0, ""}, Case{"wide", Cmd::TOGGLE_WIDE_ANGLE, 0, ""},
                        Case{"invert", Cmd::TOGGLE_REINVERTER, 0, ""}, Case{"laser_power 350", Cmd::LASER_POWER, 350, ""},
                        Case{"laser_duration 0.15e3", Cmd::LASER_DURATION, 150, ""}}) {
    const ParsedCommand p = parse_command_line(k.line, "terminal", 7);
    ASSERT_TRUE(p.ok) << "'" << k.line << "': " << p.error;
    EXPECT_EQ(p.command.command, k.code) << k.line;
    EXPECT_DOUBLE_EQ(p.command.value, k.value) << k.line;
    EXPECT_EQ(p.command.arg, k.arg) << k.line;
    EXPECT_EQ(p.command.source, "terminal");
    EXPECT_EQ(p.command.seq, 7);
  }
  // A snapshot name is checked whole: 70 characters were cut to 64 and accepted on the terminal.
  for (const char* bad : {"", "   ", "zoom", "zoom x", "zoom 3x", "save", "n 3", "fly",
                          "s aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa", "s ../x", "s .hidden",
                          "zoom nan", "zoom inf", "z -inf", "zoom 1e999", "pan", "pan 1", "pan 1 x",
                          "pan 1 2 3", "focus", "focus far", "wide 2", "focus nan", "pan 1e999 0", "pan 0 -1e999",
                          "laser_power", "laser_power 200mW", "laser_duration", "laser_duration 100 ms", "laser_power inf"}) {
    const ParsedCommand p = parse_command_line(bad, "terminal", 1);
    EXPECT_FALSE(p.ok) << "'" << bad << "' parsed";
    EXPECT_FALSE(p.error.empty());
  }
}
