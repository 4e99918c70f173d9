#include "rig/telemetry/commands.hpp"

#include <cmath>
#include <cstdlib>

#include <spdlog/spdlog.h>

#include "rig/telemetry/channels.hpp"
#include "rig/telemetry/items.hpp"
#include "rig/telemetry/lcm_subscribe.hpp"
#include "rig/telemetry/publisher.hpp"
#include "vitreo_lcm/command_ack_t.hpp"

namespace vitreo::telemetry {

const char* command_name(std::int8_t code) noexcept {
  switch (static_cast<CommandCode>(code)) {
    case CommandCode::NextCase: return "next_case";
    case CommandCode::PreviousCase: return "previous_case";
    case CommandCode::Pause: return "pause";
    case CommandCode::Resume: return "resume";
    case CommandCode::Reset: return "reset";
    case CommandCode::SaveSnapshot: return "save_snapshot";
    case CommandCode::ToggleWireframe: return "toggle_wireframe";
    case CommandCode::ToggleLabels: return "toggle_labels";
    case CommandCode::Zoom: return "zoom";
    case CommandCode::Pan: return "pan";
    case CommandCode::Focus: return "focus";
    case CommandCode::ToggleShading: return "toggle_shading";
    case CommandCode::ToggleWideAngle: return "toggle_wide_angle";
    case CommandCode::ToggleReinverter: return "toggle_reinverter";
  }
  return "unknown";
}

namespace {
bool valid_snapshot_name(const std::string& s) {
  if (s.empty() || s.size() > 64 || s.front() == '.') return false;
  for (char c : s) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
                    c == '_' || c == '-';
    if (!ok) return false;
  }
  return true;
}
}  // namespace

ParsedCommand parse_command_line(const std::string& line, const std::string& source, std::int64_t seq) {
  ParsedCommand out;
  // Split into a word and an optional argument; a line that is exactly " " means the space key.
  std::string word, arg;
  if (line == " ") {
    word = "space";
  } else {
    const auto b = line.find_first_not_of(" \t");
    if (b == std::string::npos) {
      out.error = "empty command";
      return out;
    }
    const auto e = line.find_first_of(" \t", b);
    word = line.substr(b, e == std::string::npos ? std::string::npos : e - b);
    if (e != std::string::npos) {
      const auto ab = line.find_first_not_of(" \t", e);
      const auto ae = line.find_last_not_of(" \t\r\n");
      if (ab != std::string::npos && ae >= ab) arg = line.substr(ab, ae - ab + 1);
    }
  }
  auto& c = out.command;
  c.utime_us = wall_time_us();
  c.source = source;
  c.seq = seq;
  c.value = 0;
  auto simple = [&](CommandCode code) {
    if (!arg.empty()) {
      out.error = "'" + word + "' takes no argument";
      return;
    }
    c.command = static_cast<std::int8_t>(code);
    out.ok = true;
  };
  if (word == "n" || word == "next") {
    simple(CommandCode::NextCase);
  } else if (word == "p" || word == "prev" || word == "previous") {
    simple(CommandCode::PreviousCase);
  } else if (word == "space" || word == "pause") {
    simple(CommandCode::Pause);
  } else if (word == "resume") {
    simple(CommandCode::Resume);
  } else if (word == "r" || word == "reset") {
    simple(CommandCode::Reset);
  } else if (word == "w" || word == "wireframe") {
    simple(CommandCode::ToggleWireframe);
  } else if (word == "l" || word == "labels") {
    simple(CommandCode::ToggleLabels);
  } else if (word == "s" || word == "save") {
    if (arg.empty()) {
      out.error = "save needs a snapshot name";
    } else {
      c.command = static_cast<std::int8_t>(CommandCode::SaveSnapshot);
      c.arg = arg;
      out.ok = true;
    }
  } else if (word == "z" || word == "zoom" || word == "focus") {
    char* end = nullptr;
    const double v = arg.empty() ? 0.0 : std::strtod(arg.c_str(), &end);
    if (arg.empty() || end == arg.c_str() || *end != '\0') {
      out.error = word == "focus" ? "focus needs a number (mm), e.g. 'focus 0.8'" : "zoom needs a number, e.g. 'zoom 12.5'";
    } else {
      c.command = static_cast<std::int8_t>(word == "focus" ? CommandCode::Focus : CommandCode::Zoom);
      c.value = v;
      out.ok = true;
    }
  } else if (word == "pan") {
    // Two numbers: x into `value`, y kept as text in `arg` (the message has one number field).
    char* end = nullptr;
    const double x = std::strtod(arg.c_str(), &end);
    const char* rest = end;
    char* end_y = nullptr;
    const double y = arg.empty() ? 0.0 : std::strtod(rest, &end_y);
    if (arg.empty() || end == arg.c_str() || end_y == rest || *end_y != '\0') {
      out.error = "pan needs two numbers (mm from the region of interest), e.g. 'pan 1.5 -2'";
    } else {
      c.command = static_cast<std::int8_t>(CommandCode::Pan);
      c.value = x;
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.17g", y);
      c.arg = buf;
      out.ok = true;
    }
  } else if (word == "flat") {
    simple(CommandCode::ToggleShading);
  } else if (word == "wide") {
    simple(CommandCode::ToggleWideAngle);
  } else if (word == "invert") {
    simple(CommandCode::ToggleReinverter);
  } else {
    out.error = "unknown command '" + word + "' (n, p, pause, resume, r, s NAME, w, l, z X, pan X Y, focus F, flat, wide, invert)";
  }
  return out;
}

Verdict validate_command(const vitreo_lcm::operator_command_t& cmd, const CommandContext& ctx) {
  auto refuse = [](std::string why) { return Verdict{false, std::move(why)}; };
  switch (static_cast<CommandCode>(cmd.command)) {
    case CommandCode::NextCase:
      if (ctx.case_index + 1 >= ctx.case_count)
        return refuse("already at the last case (" + std::to_string(ctx.case_index + 1) + " of " +
                      std::to_string(ctx.case_count) + ")");
      break;
    case CommandCode::PreviousCase:
      if (ctx.case_index <= 0) return refuse("already at the first case");
      break;
    case CommandCode::Pause:
      if (ctx.paused) return refuse("physics is already paused");
      break;
    case CommandCode::Resume:
      if (!ctx.paused) return refuse("physics is not paused");
      break;
    case CommandCode::SaveSnapshot:
      if (!valid_snapshot_name(cmd.arg))
        return refuse("snapshot name must be 1-64 characters of [A-Za-z0-9._-], not starting with '.'");
      break;
    case CommandCode::Zoom:
      if (!std::isfinite(cmd.value)) return refuse("zoom value is not a finite number");
      if (cmd.value < ctx.zoom_min || cmd.value > ctx.zoom_max)
        return refuse(fmt::format("zoom {:g} outside the rig's range {:g}..{:g}", cmd.value, ctx.zoom_min, ctx.zoom_max));
      break;
    case CommandCode::Focus:
      if (!std::isfinite(cmd.value) || std::abs(cmd.value) > 0.5 * ctx.focus_range_mm)
        return refuse(fmt::format("focus {:g} mm outside the rig's range ±{:g} mm", cmd.value, 0.5 * ctx.focus_range_mm));
      break;
    case CommandCode::Pan: {
      char* end = nullptr;
      const double y = std::strtod(cmd.arg.c_str(), &end);
      if (cmd.arg.empty() || *end != '\0' || !std::isfinite(y) || !std::isfinite(cmd.value))
        return refuse("pan needs x (value) and y (arg) as finite numbers of mm");
      if (std::abs(cmd.value) > ctx.pan_range_mm || std::abs(y) > ctx.pan_range_mm)
        return refuse(fmt::format("pan {:g} {:g} mm outside the rig's range ±{:g} mm", cmd.value, y, ctx.pan_range_mm));
      break;
    }
    case CommandCode::Reset:
    case CommandCode::ToggleWireframe:
    case CommandCode::ToggleLabels:
    case CommandCode::ToggleShading:
    case CommandCode::ToggleWideAngle:
    case CommandCode::ToggleReinverter:
      break;
    default:
      return refuse("unknown command code " + std::to_string(cmd.command));
  }
  return Verdict{true, {}};
}

CommandServer::CommandServer(lcm::LCM& lcm, std::size_t queue_capacity) : lcm_(lcm), queue_(queue_capacity) {
  sub_ = subscribe_to<vitreo_lcm::operator_command_t>(lcm_, kChanCommand, &dispatch_);
}

CommandServer::~CommandServer() {
  if (sub_) lcm_.unsubscribe(sub_);
}

void CommandServer::pump_local() {
  LocalCommand in;
  while (local_in_.try_pop(in)) {
    vitreo_lcm::operator_command_t cmd{};
    cmd.utime_us = wall_time_us();
    cmd.source = text(in.source);
    cmd.seq = in.seq;
    cmd.command = in.command;
    cmd.value = in.value;
    cmd.arg = text(in.arg);
    const Verdict v = handle(cmd);
    LocalAck ack;
    ack.seq = in.seq;
    ack.command = in.command;
    ack.accepted = v.accepted;
    copy_text(ack.reason, v.reason);
    (void)local_acks_.try_push(ack);  // a terminal that stopped reading acks loses them, nothing else
  }
}

Verdict CommandServer::handle(const vitreo_lcm::operator_command_t& command) {
  const vitreo_lcm::operator_command_t* cmd = &command;
  Verdict v;
  auto last = last_seq_.find(cmd->source);
  if (cmd->source.empty()) {
    v = {false, "command has no source"};
  } else if (last != last_seq_.end() && cmd->seq <= last->second) {
    v = {false, "sequence " + std::to_string(cmd->seq) + " is not after " + std::to_string(last->second) +
                    " from '" + cmd->source + "' (duplicate or reordered)"};
  } else {
    v = validate_command(*cmd, context_.read());
  }
  if (!cmd->source.empty() && (last == last_seq_.end() || cmd->seq > last->second)) last_seq_[cmd->source] = cmd->seq;

  if (v.accepted) {
    AcceptedCommand a;
    a.code = static_cast<CommandCode>(cmd->command);
    a.value = cmd->value;
    copy_text(a.arg, cmd->arg);
    a.seq = cmd->seq;
    if (!queue_.try_push(a)) v = {false, "physics command queue is full"};
    if (v.accepted && a.code == CommandCode::SaveSnapshot && !snapshot_folder_.empty()) {
      v.reason = "-> " + snapshot_folder_ + "/" + cmd->arg + ".snapshot";
    }
  }
  vitreo_lcm::command_ack_t ack;
  ack.utime_us = wall_time_us();
  ack.source = cmd->source;
  ack.seq = cmd->seq;
  ack.command = cmd->command;
  ack.accepted = v.accepted;
  ack.reason = v.reason;
  lcm_.publish(kChanCommandAck, &ack);
  if (v.accepted) {
    ++accepted_;
    spdlog::info("command {} #{} from '{}' accepted", command_name(cmd->command), cmd->seq, cmd->source);
  } else {
    ++refused_;
    spdlog::warn("command {} #{} from '{}' refused: {}", command_name(cmd->command), cmd->seq, cmd->source, v.reason);
  }
  return v;
}

}  // namespace vitreo::telemetry
