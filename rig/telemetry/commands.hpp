#pragma once
// Operator commands over LCM (the thesis' keyboard table, ch. 2.6.1): VITREO_COMMAND in,
// VITREO_COMMAND_ACK out. The CommandServer lives on the telemetry thread (it shares that thread's
// lcm::LCM): each command is validated against the latest CommandContext that physics published
// through a triple buffer, answered with an acknowledgement (accepted, or refused with a reason),
// and — if accepted — queued to physics through an SPSC ring that physics polls once per step.
// Physics never waits for a command; the context may be one step stale, so physics still treats a
// command as a request (e.g. clamps zoom) rather than trusting it blindly.
#include <cstdint>
#include <map>
#include <string>

#include <lcm/lcm-cpp.hpp>

#include "rig/runtime/spsc_ring.hpp"
#include "rig/runtime/triple_buffer.hpp"
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
};
const char* command_name(std::int8_t code) noexcept;

// What physics knows that validation needs; physics publishes it each step (or on change).
struct CommandContext {
  std::int32_t case_index = 0;
  std::int32_t case_count = 1;
  bool paused = false;
  double zoom_min = 1.0;   // microscope magnification range of the rig
  double zoom_max = 25.0;
};

struct Verdict {
  bool accepted = false;
  std::string reason;  // empty when accepted
};

// Pure validation (no state beyond the arguments).
Verdict validate_command(const vitreo_lcm::operator_command_t& cmd, const CommandContext& ctx);

// The terminal's spelling of the commands (thesis ch. 2.6.1 keys, plus words), one per line:
//   n | next            p | prev | previous        space | pause     resume
//   r | reset           s NAME | save NAME          w | wireframe    l | labels
//   z X | zoom X
// Returns the command (utime_us/source/seq filled from the arguments) or an error message. Only
// the syntax is checked here; the rig validates the rest and answers with an ack.
struct ParsedCommand {
  bool ok = false;
  vitreo_lcm::operator_command_t command{};
  std::string error;
};
ParsedCommand parse_command_line(const std::string& line, const std::string& source, std::int64_t seq);

// An accepted command, as physics receives it.
struct AcceptedCommand {
  CommandCode code = CommandCode::Pause;
  double value = 0;
  char arg[65] = {};
  std::int64_t seq = 0;
};

// A command typed on the rig's own terminal (rig/session/terminal_commands.hpp): handed to the
// telemetry thread through a ring, validated there exactly like one from LCM, acknowledged on LCM
// and back to the terminal.
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

class CommandServer {
 public:
  // Limits on what a sender may put in a command (refused with a reason beyond them).
  static constexpr std::size_t kMaxSourceLength = 31;   // printable ASCII, no spaces
  static constexpr std::size_t kMaxArgLength = 64;      // the longest snapshot name
  static constexpr std::size_t kMaxSources = 256;       // senders remembered for their sequence numbers

  // Subscribes to VITREO_COMMAND on `lcm` (checked: a malformed packet is counted in `counters`,
  // or in the server's own when null, and never reaches it); acks are published on the same object.
  explicit CommandServer(lcm::LCM& lcm, std::size_t queue_capacity = 64, ChannelCounters* counters = nullptr);
  ~CommandServer() = default;
  CommandServer(const CommandServer&) = delete;
  CommandServer& operator=(const CommandServer&) = delete;

  // Physics side.
  runtime::TripleBuffer<CommandContext>& context() noexcept { return context_; }
  bool poll(AcceptedCommand& out) noexcept { return queue_.try_pop(out); }

  // Where "save snapshot NAME" files go: an accepted SAVE_SNAPSHOT's ack says "→ FOLDER/NAME.snapshot"
  // in its reason field. Before the telemetry thread starts.
  void set_snapshot_folder(std::string folder) { snapshot_folder_ = std::move(folder); }

  // Terminal side (one producer thread): false when the ring is full.
  bool submit(const LocalCommand& cmd) noexcept { return local_in_.try_push(cmd); }
  bool poll_ack(LocalAck& out) noexcept { return local_acks_.try_pop(out); }
  // Telemetry thread: validates and queues the submitted commands (the same path as LCM's).
  void pump_local();

  std::uint64_t accepted() const noexcept { return accepted_; }
  std::uint64_t refused() const noexcept { return refused_; }
  // Packets on VITREO_COMMAND: received, refused undecoded, handler failures.
  const ChannelCounters& receive_counters() const noexcept { return sub_.counters(); }

 private:
  void on_command(const vitreo_lcm::operator_command_t& cmd) { (void)handle(cmd); }
  Verdict handle(const vitreo_lcm::operator_command_t& cmd);
  struct Dispatch {
    CommandServer* self;
    void operator()(const vitreo_lcm::operator_command_t& cmd) { self->on_command(cmd); }
  } dispatch_{this};

  lcm::LCM& lcm_;
  runtime::TripleBuffer<CommandContext> context_;
  runtime::SpscRing<AcceptedCommand> queue_;
  runtime::SpscRing<LocalCommand> local_in_{32};
  runtime::SpscRing<LocalAck> local_acks_{32};
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
