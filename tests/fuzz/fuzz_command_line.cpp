// libFuzzer target: the terminal's command lines (parse_command_line). A line it accepts must hold
// a known command, a finite zoom, focus or pan, a valid snapshot name — whatever the bytes. Only the
// range-checked commands (zoom, focus, pan, laser power and duration) may still be refused by the
// rig's limits.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "rig/telemetry/commands.hpp"

using namespace vitreo::telemetry;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string line(reinterpret_cast<const char*>(data), size);
  const ParsedCommand p = parse_command_line(line, "terminal", 1);
  if (!p.ok) {
    if (p.error.empty()) std::abort();
    return 0;
  }
  const auto code = static_cast<CommandCode>(p.command.command);
  const bool ranged = code == CommandCode::Zoom || code == CommandCode::Focus || code == CommandCode::Pan ||
                      code == CommandCode::LaserPower || code == CommandCode::LaserDuration;
  if (check_command(p.command, CommandLimits{}).accepted == false && !ranged) std::abort();
  if (code == CommandCode::SaveSnapshot && !valid_snapshot_name(p.command.arg)) std::abort();
  if (ranged && !std::isfinite(p.command.value)) std::abort();
  if (code == CommandCode::Pan && !std::isfinite(std::strtod(p.command.arg.c_str(), nullptr))) std::abort();
  return 0;
}
