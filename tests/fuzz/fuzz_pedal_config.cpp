// libFuzzer target: pedal mappings (parse_pedal_mapping) behind the TOML guard, toml++ header-only
// with assertions and UBSan (see fuzz_scene_file.cpp). An accepted mapping must be consistent: no
// switch or axis doing two jobs on one pedal.
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "rig/input/controls.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const vitreo::rig::PedalMapping m = vitreo::rig::parse_pedal_mapping(text, "fuzz.toml");
    const int sw[] = {m.reflux_switch, m.laser_switch, m.instrument_switch, m.air_switch};
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j)
        if (sw[i] >= 0 && sw[i] == sw[j]) std::abort();
    if (m.zoom_max < m.zoom_min || m.vitrectomy_pedal_id == m.microscope_pedal_id) std::abort();
  } catch (const std::runtime_error&) {
  }
  return 0;
}
