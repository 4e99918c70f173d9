#include "rig/session/scripted_session.hpp"

namespace vitreo::rig {

std::vector<DeviceSpec> simulated_devices(const SurgicalScript& script) {
  std::vector<DeviceSpec> devices = {{"tracker-0", DeviceRole::tracker, "sim:tracker?transport=pty", 1, kToolTracker, 0, 0, ""},
                                     {"pedals", DeviceRole::pedals, "sim:pedals?transport=pty", 2, 0, 0, 0, ""},
                                     {"eyeball", DeviceRole::eyeball, "sim:eyeball?transport=pty", 3, 0, 0, 0, ""}};
  for (const auto& h : script.hands) {
    if (h.tracker == kLightPipeTracker)
      devices.push_back({"tracker-1", DeviceRole::tracker, "sim:tracker?transport=pty", 4, kLightPipeTracker, 0, 0, ""});
  }
  return devices;
}

std::function<void(const PreparedCase&, std::vector<DeviceSpec>&)> play_script(SurgicalScript script, PedalMapping pedals) {
  return [script = std::move(script), pedals](const PreparedCase& c, std::vector<DeviceSpec>& specs) {
    const ResolvedScript resolved = resolve_script(script, c, pedals);
    for (auto& d : specs) {
      if (d.uri.rfind("sim:", 0) != 0 || !d.sim_script.empty()) continue;
      const std::string name = d.role == DeviceRole::tracker ? "tracker-" + std::to_string(d.channel)
                               : d.role == DeviceRole::pedals ? "pedals"
                                                               : "eyeball";
      if (const auto it = resolved.device_scripts.find(name); it != resolved.device_scripts.end()) d.sim_script = it->second;
    }
  };
}

}  // namespace vitreo::rig
