// libFuzzer target: the firmware emulators' scripts (drivers/sim parse_script). An accepted script
// has keys of the device's width in increasing time and finite values, and it must drive an
// emulator for a simulated second without trouble.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "drivers/sim/emulator.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  vitreo::drivers::sim::Script s;
  std::string err;
  if (!vitreo::drivers::sim::parse_script(text, s, &err)) {
    if (err.rfind("line ", 0) != 0) std::abort();
    return 0;
  }
  if (s.keys.empty()) std::abort();
  for (std::size_t i = 0; i < s.keys.size(); ++i) {
    if (i > 0 && s.keys[i].first <= s.keys[i - 1].first) std::abort();
    for (double v : s.keys[i].second)
      if (!std::isfinite(v)) std::abort();
  }
  for (const auto& f : s.faults)
    if (!std::isfinite(f.value)) std::abort();
  s.rate_hz = s.rate_hz > 2000 ? 2000 : s.rate_hz;  // keep one input cheap
  vitreo::drivers::sim::FirmwareEmulator emu(s);
  std::vector<vitreo::proto::Bytes> packets;
  vp_message stream{};
  stream.type = VP_MSG_CONFIG;
  stream.u.config = {VP_CFG_SET, VP_CFG_KEY_STREAMING, 1};
  emu.on_host_message(stream, 0);
  for (std::uint64_t t = 0; t <= 1'000'000; t += 10'000) {
    emu.step(t, packets);
    for (auto& p : packets) emu.corrupt(p);
    packets.clear();
  }
  return 0;
}
