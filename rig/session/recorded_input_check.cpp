// What a recorded input may say (check_recorded_input, simulation_model.hpp): the reader of a
// recording calls it on every input, so a damaged one is a corruption, not a state.
#include <cmath>

#include "rig/session/device_inputs.hpp"
#include "rig/telemetry/commands.hpp"
#include "rig/session/simulation_model.hpp"

namespace vitreo::rig {

// ---- Recorded inputs ----------------------------------------------------------------------------

const char* check_recorded_input(const telemetry::DeviceInput& in) noexcept {
  for (std::uint8_t i = 0; i < in.n_values && i < telemetry::DeviceInput::kMaxValues; ++i) {
    if (!std::isfinite(in.values[i])) return "a value that is not a finite number";
  }
  auto integral = [](double v, double lo, double hi) { return v >= lo && v <= hi && v == std::floor(v); };
  switch (in.device_kind) {
    case static_cast<std::int8_t>(InputKind::Tracker):
    case static_cast<std::int8_t>(InputKind::Pedals):
    case static_cast<std::int8_t>(InputKind::Eyeball):
      return nullptr;  // device samples: the model range-checks them as it does live
    case kLinkKind:
      if (in.n_values < 1 || !integral(in.values[0], 1, 3)) return "a link change that is not up, lost or stuck";
      if (in.n_values >= 2 && !integral(in.values[1], 0, 3)) return "a link change of an unknown device type";
      return nullptr;
    case kSessionEndKind:
      if (in.n_values != 1 || in.values[0] != static_cast<double>(in.step + 1))
        return "a session-end marker whose step count is not its own step + 1";
      return nullptr;
    case kCommandKind:
      if (in.n_values < 2 || !integral(in.values[0], 1, telemetry::kLastCommandCode)) return "an operator command with an unknown code";
      return nullptr;
    case kCaseKind:
      if (in.n_values < 1 || !integral(in.values[0], 0, 4096)) return "a case index out of range";
      return nullptr;
    default:
      return "an input of an unknown kind";
  }
}

}  // namespace vitreo::rig
