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
};
const char* command_name(std::int8_t code) noexcept;

// What physics knows that validation needs; physics publishes it each step (or on change).
struct CommandContext {
  std::int32_t case_index = 0;
  std::int32_t case_count = 1;
  bool paused = false;
  double zoom_min = 1.0;   // microscope magnification range of the rig
  double zoom_max = 25.0;
  double pan_range_mm = 20.0;    // |x|, |y| of a pan from the region of interest
  double focus_range_mm = 6.0;   // focus within ±half of this
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
//   z X | zoom X        pan X Y            focus F        flat        wide        invert
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
  // Subscribes to VITREO_COMMAND on `lcm`; acks are published on the same object.
  explicit CommandServer(lcm::LCM& lcm, std::size_t queue_capacity = 64);
  ~CommandServer();
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

 private:
  void on_command(const vitreo_lcm::operator_command_t& cmd) { (void)handle(cmd); }
  Verdict handle(const vitreo_lcm::operator_command_t& cmd);
  struct Dispatch {
    CommandServer* self;
    void operator()(const vitreo_lcm::operator_command_t& cmd) { self->on_command(cmd); }
  } dispatch_{this};

  lcm::LCM& lcm_;
  lcm::Subscription* sub_ = nullptr;
  runtime::TripleBuffer<CommandContext> context_;
  runtime::SpscRing<AcceptedCommand> queue_;
  runtime::SpscRing<LocalCommand> local_in_{32};
  runtime::SpscRing<LocalAck> local_acks_{32};
  std::map<std::string, std::int64_t> last_seq_;  // per source: replays and reordering are refused
  std::string snapshot_folder_;
  std::uint64_t accepted_ = 0;
  std::uint64_t refused_ = 0;
};

}  // namespace vitreo::telemetry
