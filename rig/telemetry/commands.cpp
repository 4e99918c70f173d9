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
    case CommandCode::LaserPower: return "laser_power";
    case CommandCode::LaserDuration: return "laser_duration";
  }
  return "unknown";
}

bool valid_snapshot_name(const std::string& s) {
  if (s.empty() || s.size() > 64 || s.front() == '.') return false;
  for (char c : s) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
                    c == '_' || c == '-';
    if (!ok) return false;
  }
  return true;
}

namespace {
constexpr const char* kSnapshotNameRule = "snapshot name must be 1-64 characters of [A-Za-z0-9._-], not starting with '.'";
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
    } else if (!valid_snapshot_name(arg)) {
      out.error = kSnapshotNameRule;  // refused whole, never shortened to something that fits
    } else {
      c.command = static_cast<std::int8_t>(CommandCode::SaveSnapshot);
      c.arg = arg;
      out.ok = true;
    }
  } else if (word == "z" || word == "zoom" || word == "focus") {
    char* end = nullptr;
    const double v = arg.empty() ? 0.0 : std::strtod(arg.c_str(), &end);
    if (arg.empty() || end != arg.c_str() + arg.size() || !std::isfinite(v)) {  // the whole argument, NULs included
      out.error = word == "focus" ? "focus needs a finite number (mm), e.g. 'focus 0.8'" : "zoom needs a finite number, e.g. 'zoom 12.5'";
    } else {
      c.command = static_cast<std::int8_t>(word == "focus" ? CommandCode::Focus : CommandCode::Zoom);
      c.value = v;
      out.ok = true;
    }
  } else if (word == "laser_power" || word == "laser_duration") {
    char* end = nullptr;
    const double v = arg.empty() ? 0.0 : std::strtod(arg.c_str(), &end);
    if (arg.empty() || end != arg.c_str() + arg.size() || !std::isfinite(v)) {
      out.error = word == "laser_power" ? "laser_power needs a finite number (mW), e.g. 'laser_power 250'"
                                        : "laser_duration needs a finite number (ms), e.g. 'laser_duration 150'";
    } else {
      c.command = static_cast<std::int8_t>(word == "laser_power" ? CommandCode::LaserPower : CommandCode::LaserDuration);
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
    if (arg.empty() || end == arg.c_str() || end_y == rest || end_y != arg.c_str() + arg.size() || !std::isfinite(x) || !std::isfinite(y)) {
      out.error = "pan needs two finite numbers (mm from the region of interest), e.g. 'pan 1.5 -2'";
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
    out.error = "unknown command '" + word + "' (n, p, pause, resume, r, s NAME, w, l, z X, pan X Y, focus F, flat, wide, invert, "
                "laser_power MW, laser_duration MS)";
  }
  return out;
}

Verdict check_command(const vitreo_lcm::operator_command_t& cmd, const CommandLimits& limits) {
  auto refuse = [](std::string why) { return Verdict{false, std::move(why)}; };
  switch (static_cast<CommandCode>(cmd.command)) {
    case CommandCode::SaveSnapshot:
      if (!valid_snapshot_name(cmd.arg)) return refuse(kSnapshotNameRule);
      break;
    case CommandCode::Zoom:
      if (!std::isfinite(cmd.value)) return refuse("zoom value is not a finite number");
      if (cmd.value < limits.zoom_min || cmd.value > limits.zoom_max)
        return refuse(fmt::format("zoom {:g} outside the rig's range {:g}..{:g}", cmd.value, limits.zoom_min, limits.zoom_max));
      break;
    case CommandCode::Focus:
      if (!std::isfinite(cmd.value) || std::abs(cmd.value) > 0.5 * limits.focus_range_mm)
        return refuse(fmt::format("focus {:g} mm outside the rig's range ±{:g} mm", cmd.value, 0.5 * limits.focus_range_mm));
      break;
    case CommandCode::Pan: {
      char* end = nullptr;
      const double y = std::strtod(cmd.arg.c_str(), &end);
      if (cmd.arg.empty() || *end != '\0' || !std::isfinite(y) || !std::isfinite(cmd.value))
        return refuse("pan needs x (value) and y (arg) as finite numbers of mm");
      if (std::abs(cmd.value) > limits.pan_range_mm || std::abs(y) > limits.pan_range_mm)
        return refuse(fmt::format("pan {:g} {:g} mm outside the rig's range ±{:g} mm", cmd.value, y, limits.pan_range_mm));
      break;
    }
    case CommandCode::LaserPower:
      if (!std::isfinite(cmd.value) || cmd.value < limits.laser_power_min_mw || cmd.value > limits.laser_power_max_mw)
        return refuse(fmt::format("laser power {:g} mW outside the rig's range {:g}..{:g} mW", cmd.value,
                                  limits.laser_power_min_mw, limits.laser_power_max_mw));
      break;
    case CommandCode::LaserDuration:
      if (!std::isfinite(cmd.value) || cmd.value < limits.laser_duration_min_ms || cmd.value > limits.laser_duration_max_ms)
        return refuse(fmt::format("laser pulse {:g} ms outside the rig's range {:g}..{:g} ms (a pulse per shot: no continuous mode)",
                                  cmd.value, limits.laser_duration_min_ms, limits.laser_duration_max_ms));
      break;
    case CommandCode::NextCase:
    case CommandCode::PreviousCase:
    case CommandCode::Pause:
    case CommandCode::Resume:
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

CommandRefusal decide_command(CommandCode code, const CommandContext& ctx) noexcept {
  switch (code) {
    case CommandCode::NextCase: return ctx.case_index + 1 >= ctx.case_count ? CommandRefusal::AtLastCase : CommandRefusal::None;
    case CommandCode::PreviousCase: return ctx.case_index <= 0 ? CommandRefusal::AtFirstCase : CommandRefusal::None;
    case CommandCode::Pause: return ctx.paused ? CommandRefusal::AlreadyPaused : CommandRefusal::None;
    case CommandCode::Resume: return ctx.paused ? CommandRefusal::None : CommandRefusal::NotPaused;
    default: return CommandRefusal::None;
  }
}

std::string refusal_text(CommandRefusal why, const CommandContext& ctx) {
  switch (why) {
    case CommandRefusal::None: return {};
    case CommandRefusal::AtLastCase:
      return "already at the last case (" + std::to_string(ctx.case_index + 1) + " of " + std::to_string(ctx.case_count) + ")";
    case CommandRefusal::AtFirstCase: return "already at the first case";
    case CommandRefusal::AlreadyPaused: return "physics is already paused";
    case CommandRefusal::NotPaused: return "physics is not paused";
    case CommandRefusal::SnapshotBusy: return "the last two snapshots are still being written";
  }
  return "refused";
}

Verdict validate_command(const vitreo_lcm::operator_command_t& cmd, const CommandContext& ctx, const CommandLimits& limits) {
  Verdict v = check_command(cmd, limits);
  if (!v.accepted) return v;
  const CommandRefusal why = decide_command(static_cast<CommandCode>(cmd.command), ctx);
  if (why != CommandRefusal::None) return Verdict{false, refusal_text(why, ctx)};
  return v;
}

CommandServer::CommandServer(lcm::LCM& lcm, std::size_t queue_capacity, ChannelCounters* counters)
    : lcm_(lcm), queue_(queue_capacity), outcomes_(queue_capacity) {
  sub_ = subscribe_to<vitreo_lcm::operator_command_t>(lcm_, kChanCommand, &dispatch_, counters);
}

void CommandServer::report(const AcceptedCommand& cmd, CommandRefusal why, const CommandContext& ctx) noexcept {
  // Never full: at most queue capacity commands are in flight between the server and physics.
  (void)outcomes_.try_push(CommandOutcome{cmd.ticket, why, ctx});
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
    handle(cmd, true);
  }
  take_outcomes();
  publish_due();
}

void CommandServer::take_outcomes() {
  CommandOutcome o;
  while (outcomes_.try_pop(o)) {
    for (auto& p : pending_) {
      if (p.ticket != o.ticket) continue;
      p.decided = true;
      if (o.why != CommandRefusal::None) {
        p.verdict = Verdict{false, refusal_text(o.why, o.ctx)};
      }
      break;
    }
  }
}

void CommandServer::abandon_pending(const std::string& why) {
  take_outcomes();
  for (auto& p : pending_) {
    if (!p.decided) {
      p.decided = true;
      p.verdict = Verdict{false, why};
    }
  }
  publish_due();
}

namespace {// A source names a sender in acks and logs: short printable ASCII, so a crafted one cannot forge log
// lines or grow without bound.
bool valid_source(const std::string& s) {
  if (s.empty() || s.size() > CommandServer::kMaxSourceLength) return false;
  for (char c : s) {
    if (c < 0x21 || c > 0x7e) return false;
  }
  return true;
}
}  // namespace

void CommandServer::handle(const vitreo_lcm::operator_command_t& command, bool local) {
  const vitreo_lcm::operator_command_t* cmd = &command;
  Verdict v;
  auto last = last_seq_.find(cmd->source);
  if (cmd->source.empty()) {
    v = {false, "command has no source"};
  } else if (!valid_source(cmd->source)) {
    v = {false, "source must be 1-" + std::to_string(kMaxSourceLength) + " printable ASCII characters without spaces"};
  } else if (cmd->arg.size() > kMaxArgLength) {
    v = {false, "argument longer than " + std::to_string(kMaxArgLength) + " characters"};
  } else if (last != last_seq_.end() && cmd->seq <= last->second.seq) {
    v = {false, "sequence " + std::to_string(cmd->seq) + " is not after " + std::to_string(last->second.seq) +
                    " from '" + cmd->source + "' (duplicate or reordered)"};
  } else {
    v = check_command(*cmd, limits_);
  }
  if (valid_source(cmd->source) && (last == last_seq_.end() || cmd->seq > last->second.seq)) {
    if (last == last_seq_.end() && last_seq_.size() >= kMaxSources) {
      // Forget the source heard from least recently: the map stays bounded whatever a sender invents.
      auto oldest = last_seq_.begin();
      for (auto it = last_seq_.begin(); it != last_seq_.end(); ++it) {
        if (it->second.heard < oldest->second.heard) oldest = it;
      }
      last_seq_.erase(oldest);
    }
    last_seq_[cmd->source] = SourceState{cmd->seq, ++heard_};
  }

  Pending p;
  p.ticket = next_ticket_++;
  p.source = cmd->source.substr(0, 256);  // echoed so the sender can match it; a valid one is short
  p.seq = cmd->seq;
  p.command = cmd->command;
  p.local = local;
  if (v.accepted) {
    AcceptedCommand a;
    a.code = static_cast<CommandCode>(cmd->command);
    a.value = cmd->value;
    copy_text(a.arg, cmd->arg);
    a.seq = cmd->seq;
    a.ticket = p.ticket;
    // Waiting commands are bounded by the queue: that also keeps physics' outcome ring from filling.
    if (pending_.size() >= queue_.capacity() || !queue_.try_push(a)) {
      v = {false, "physics command queue is full"};
    } else if (a.code == CommandCode::SaveSnapshot && !snapshot_folder_.empty()) {
      v.reason = "-> " + snapshot_folder_ + "/" + cmd->arg + ".snapshot";
    }
  }
  p.decided = !v.accepted;  // refused here: nothing for physics to decide
  p.verdict = std::move(v);
  pending_.push_back(std::move(p));
  take_outcomes();
  publish_due();
}

void CommandServer::publish_due() {
  while (!pending_.empty() && pending_.front().decided) {
    const Pending& p = pending_.front();
    vitreo_lcm::command_ack_t ack;
    ack.utime_us = wall_time_us();
    ack.source = p.source;
    ack.seq = p.seq;
    ack.command = p.command;
    ack.accepted = p.verdict.accepted;
    ack.reason = p.verdict.reason;
    lcm_.publish(kChanCommandAck, &ack);
    const std::string who = valid_source(p.source) ? p.source : std::string("(invalid source)");
    if (p.verdict.accepted) {
      ++accepted_;
      spdlog::info("command {} #{} from '{}' accepted", command_name(p.command), p.seq, who);
    } else {
      ++refused_;
      spdlog::warn("command {} #{} from '{}' refused: {}", command_name(p.command), p.seq, who, p.verdict.reason);
    }
    if (p.local) {
      LocalAck la;
      la.seq = p.seq;
      la.command = p.command;
      la.accepted = p.verdict.accepted;
      copy_text(la.reason, p.verdict.reason);
      (void)local_acks_.try_push(la);  // a terminal that stopped reading acks loses them, nothing else
    }
    pending_.pop_front();
  }
}

}  // namespace vitreo::telemetry
