// libFuzzer target: every vitreo LCM type through the checked decoder (rig/telemetry/lcm_decode.hpp).
// The first byte picks the type, the rest is the packet. Beyond "no crash, no sanitizer report": a
// message the decoder accepts must re-encode to exactly the bytes it came from — a decoder that
// accepted bytes it then described differently would be misreading them.
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "rig/telemetry/lcm_decode.hpp"
#include "vitreo_lcm/command_ack_t.hpp"
#include "vitreo_lcm/device_input_t.hpp"
#include "vitreo_lcm/device_status_t.hpp"
#include "vitreo_lcm/event_t.hpp"
#include "vitreo_lcm/instrument_state_t.hpp"
#include "vitreo_lcm/operator_command_t.hpp"
#include "vitreo_lcm/physics_timing_t.hpp"
#include "vitreo_lcm/receive_status_t.hpp"
#include "vitreo_lcm/recording_check_t.hpp"
#include "vitreo_lcm/recording_end_t.hpp"
#include "vitreo_lcm/recording_header_t.hpp"
#include "vitreo_lcm/score_t.hpp"

namespace {
template <class Msg>
void check(const std::uint8_t* data, std::size_t size) {
  Msg m;
  const auto e = vitreo::telemetry::decode_message(data, size, m);
  if (e == vitreo::telemetry::DecodeError::Exception) std::abort();  // the patched decoders never throw
  if (e != vitreo::telemetry::DecodeError::None) return;
  std::vector<std::uint8_t> again(static_cast<std::size_t>(m.getEncodedSize()));
  if (m.encode(again.data(), 0, static_cast<int>(again.size())) != static_cast<int>(size)) std::abort();
  if (std::memcmp(again.data(), data, size) != 0) std::abort();
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::uint8_t* p = data + 1;
  const std::size_t n = size - 1;
  switch (data[0] % 12) {
    case 0: check<vitreo_lcm::operator_command_t>(p, n); break;
    case 1: check<vitreo_lcm::command_ack_t>(p, n); break;
    case 2: check<vitreo_lcm::device_input_t>(p, n); break;
    case 3: check<vitreo_lcm::recording_header_t>(p, n); break;
    case 4: check<vitreo_lcm::score_t>(p, n); break;
    case 5: check<vitreo_lcm::device_status_t>(p, n); break;
    case 6: check<vitreo_lcm::instrument_state_t>(p, n); break;
    case 7: check<vitreo_lcm::event_t>(p, n); break;
    case 8: check<vitreo_lcm::physics_timing_t>(p, n); break;
    case 9: check<vitreo_lcm::receive_status_t>(p, n); break;
    case 10: check<vitreo_lcm::recording_check_t>(p, n); break;
    case 11: check<vitreo_lcm::recording_end_t>(p, n); break;
  }
  return 0;
}
