#pragma once
// Operator commands over LCM (the thesis' keyboard table, ch. 2.6.1): VITREO_COMMAND in,
// VITREO_COMMAND_ACK out.
//
// Who decides what: the CommandServer lives on the telemetry thread (it shares that thread's
// lcm::LCM) and checks what needs no knowledge of the session — a valid source, a sequence number
// after the last one from that source, a known code, a finite zoom in the rig's range, a valid
// snapshot name. What depends on the session's state (pause while paused, next at the last case)
// is decided by physics, in order, at the step boundary where the command takes effect: it polls
// the accepted-so-far commands through a wait-free SPSC ring, decides each against the state left
// by the previous one (decide_command), applies it, and reports the outcome through a second ring.
// The server publishes each acknowledgement only then, in the order the commands came, so an ack
// reflects the state after its command — "pause" then "resume" typed together are both accepted,
// and the session ends up running, as the operator's last word said.
#include <cstdint>
#include <deque>
#include <map>
#include <string>

#include <lcm/lcm-cpp.hpp>

#include "rig/runtime/spsc_ring.hpp"
#include "rig/telemetry/lcm_subscribe.hpp"
#include "vitreo_lcm/operator_command_t.hpp"

namespace vitreo::telemetry {

enum class CommandCode : std::int8_t {
  NextCase = 1,
  PreviousCase = 2,
  Pause = 3,
  Resume = 4,
  Reset = 5,
  SaveSnapshot = 6,
  ToggleWireframe = 7,
  ToggleLabels = 8,
  Zoom = 9,
  Pan = 10,                // value = x, arg = y (mm, fundus plane) from the case's region of interest
  Focus = 11,              // value = focal plane offset from the fundus (mm, + toward the microscope)
  ToggleShading = 12,      // flat / smooth shading of the tissue (the thesis' F2)
  ToggleWideAngle = 13,    // the wide-angle viewing system in / out
  ToggleReinverter = 14,   // the wide-angle image re-inverter on / off
  LaserPower = 15,         // value = the endolaser's power (mW) for the shots that follow
  LaserDuration = 16,      // value = the endolaser's pulse duration (ms) for the shots that follow
};
inline constexpr int kLastCommandCode = 16;
const char* command_name(std::int8_t code) noexcept;

// The rig's limits, fixed for a session (the stateless checks).
struct CommandLimits {
  double zoom_min = 1.0;  // microscope magnification range of the rig
  double zoom_max = 25.0;
  double pan_range_mm = 20.0;    // |x|, |y| of a pan from the region of interest
  double focus_range_mm = 6.0;   // focus within ±half of this
  // The endolaser console's settings (the rig file's [laser] table is held to them too). A shot is
  // one pulse of power × duration (core/instruments: the burn's size follows its energy); the core
  // has no continuous mode, so a duration is never 0.
  double laser_power_min_mw = 50.0;
  double laser_power_max_mw = 2000.0;
  double laser_duration_min_ms = 10.0;
  double laser_duration_max_ms = 2000.0;
};

// The session's state a command is decided against, as physics sees it at that moment.
struct CommandContext {
  std::int32_t case_index = 0;  // the current case, or the one a pending switch leads to
  std::int32_t case_count = 1;
  bool paused = false;
};

// Why physics refused a command (no strings on the physics thread: the server words them).
enum class CommandRefusal : std::uint8_t { None, AtLastCase, AtFirstCase, AlreadyPaused, NotPaused, SnapshotBusy };

// Physics side: the state-dependent part of the rules. Pure, no allocation.
CommandRefusal decide_command(CommandCode code, const CommandContext& ctx) noexcept;
std::string refusal_text(CommandRefusal why, const CommandContext& ctx);

struct Verdict {
  bool accepted = false;
  std::string reason;  // empty when accepted
};

// The rules in one place (no state beyond the arguments): the stateless checks, then
// decide_command. The server applies the first half, physics the second.
Verdict check_command(const vitreo_lcm::operator_command_t& cmd, const CommandLimits& limits);
Verdict validate_command(const vitreo_lcm::operator_command_t& cmd, const CommandContext& ctx,
                         const CommandLimits& limits = {});

// A snapshot name: 1-64 characters of [A-Za-z0-9._-], not starting with '.'.
bool valid_snapshot_name(const std::string& s);

// The terminal's spelling of the commands (thesis ch. 2.6.1 keys, plus words), one per line:
//   n | next            p | prev | previous        space | pause     resume
//   r | reset           s NAME | save NAME          w | wireframe    l | labels
//   z X | zoom X        pan X Y            focus F        flat        wide        invert
//   laser_power MW      laser_duration MS
// Returns the command (utime_us/source/seq filled from the arguments) or an error message. The
// syntax is checked here (a snapshot name too: it is never shortened to fit), the rest by the rig,
// which answers with an ack.
struct ParsedCommand {
  bool ok = false;
  vitreo_lcm::operator_command_t command{};
  std::string error;
};
ParsedCommand parse_command_line(const std::string& line, const std::string& source, std::int64_t seq);

// A command that passed the server's checks, as physics receives it.
struct AcceptedCommand {
  CommandCode code = CommandCode::Pause;
  double value = 0;
  char arg[65] = {};
  std::int64_t seq = 0;
  std::uint64_t ticket = 0;  // hand it back with report()
};

// A command typed on the rig's own terminal (terminal_commands.hpp): handed to the telemetry
// thread through a ring, checked there and decided by physics exactly like one from LCM,
// acknowledged on LCM and back to the terminal.
struct LocalCommand {
  std::int8_t command = 0;
  double value = 0;
  char arg[65] = {};
  char source[32] = {};
  std::int64_t seq = 0;
};
struct LocalAck {
  std::int64_t seq = 0;
  std::int8_t command = 0;
  bool accepted = false;
  char reason[192] = {};
};

// Physics' decision on a command, on its way back to the server.
struct CommandOutcome {
  std::uint64_t ticket = 0;
  CommandRefusal why = CommandRefusal::None;
  CommandContext ctx;
};

class CommandServer {
 public:
  // Limits on what a sender may put in a command (refused with a reason beyond them).
  static constexpr std::size_t kMaxSourceLength = 31;   // printable ASCII, no spaces
  static constexpr std::size_t kMaxArgLength = 64;      // the longest snapshot name
  static constexpr std::size_t kMaxSources = 256;       // senders remembered for their sequence numbers

  // Subscribes to VITREO_COMMAND on `lcm` (checked: a malformed packet is counted in `counters`,
  // or in the server's own when null, and never reaches it); acks are published on the same object.
  // At most `queue_capacity` commands wait for physics; more are refused.
  explicit CommandServer(lcm::LCM& lcm, std::size_t queue_capacity = 64, ChannelCounters* counters = nullptr);
  ~CommandServer() = default;
  CommandServer(const CommandServer&) = delete;
  CommandServer& operator=(const CommandServer&) = delete;

  // Before the telemetry thread starts.
  void set_limits(const CommandLimits& limits) { limits_ = limits; }
  // Where "save snapshot NAME" files go: an accepted SAVE_SNAPSHOT's ack says "-> FOLDER/NAME.snapshot".
  void set_snapshot_folder(std::string folder) { snapshot_folder_ = std::move(folder); }

  // Physics side (one thread), wait-free: the next command to decide, and what was decided —
  // report every polled command exactly once, after applying it; `ctx` is the state it was
  // decided against (for the refusal's wording).
  bool poll(AcceptedCommand& out) noexcept { return queue_.try_pop(out); }
  void report(const AcceptedCommand& cmd, CommandRefusal why, const CommandContext& ctx) noexcept;

  // Terminal side (one producer thread): false when the ring is full.
  bool submit(const LocalCommand& cmd) noexcept { return local_in_.try_push(cmd); }
  bool poll_ack(LocalAck& out) noexcept { return local_acks_.try_pop(out); }

  // Telemetry thread: checks the submitted terminal commands (the same path as LCM's), takes
  // physics' decisions and publishes the acks that are due, in order. Call it often.
  void pump_local();
  // Telemetry thread, once physics has stopped: refuses what physics never decided.
  void abandon_pending(const std::string& why);

  std::uint64_t accepted() const noexcept { return accepted_; }
  std::uint64_t refused() const noexcept { return refused_; }
  std::size_t pending() const noexcept { return pending_.size(); }
  // Packets on VITREO_COMMAND: received, refused undecoded, handler failures.
  const ChannelCounters& receive_counters() const noexcept { return sub_.counters(); }

 private:
  struct Pending {
    std::uint64_t ticket = 0;
    std::string source;
    std::int64_t seq = 0;
    std::int8_t command = 0;
    bool local = false;    // typed on the terminal: its ack goes back there too
    bool decided = false;
    Verdict verdict;
  };
  void on_command(const vitreo_lcm::operator_command_t& cmd) { handle(cmd, false); }
  void handle(const vitreo_lcm::operator_command_t& cmd, bool local);
  void take_outcomes();
  void publish_due();
  struct Dispatch {
    CommandServer* self;
    void operator()(const vitreo_lcm::operator_command_t& cmd) { self->on_command(cmd); }
  } dispatch_{this};

  lcm::LCM& lcm_;
  CommandLimits limits_;
  runtime::SpscRing<AcceptedCommand> queue_;
  runtime::SpscRing<CommandOutcome> outcomes_;
  runtime::SpscRing<LocalCommand> local_in_{32};
  runtime::SpscRing<LocalAck> local_acks_{32};
  std::deque<Pending> pending_;  // in arrival order; acks go out from the front once decided
  std::uint64_t next_ticket_ = 1;
  struct SourceState {
    std::int64_t seq = 0;     // last sequence number seen: replays and reordering are refused
    std::uint64_t heard = 0;  // when (in commands handled) it was last heard from
  };
  std::map<std::string, SourceState> last_seq_;  // at most kMaxSources, least recently heard forgotten
  std::uint64_t heard_ = 0;
  std::string snapshot_folder_;
  std::uint64_t accepted_ = 0;
  std::uint64_t refused_ = 0;
  CheckedSubscription sub_;  // last: unsubscribed first, before what its handler uses goes away
};

}  // namespace vitreo::telemetry
