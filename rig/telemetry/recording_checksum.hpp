#pragma once
// The running checksum of a recording (RECORDING.md): CRC-32 (zlib's, the IEEE polynomial) over
// each event's channel name, a NUL and its data, in file order. Event numbers and log timestamps
// are left out, so a copy made by lcm-logplayer | lcm-logger (which renumbers and re-times events)
// still verifies; neither is used by a replay.
#include <zlib.h>

#include <cstddef>
#include <cstdint>
#include <string_view>

namespace vitreo::telemetry {

inline std::uint32_t checksum_event(std::uint32_t crc, std::string_view channel, const std::uint8_t* data,
                                    std::size_t size) noexcept {
  uLong c = crc;
  c = ::crc32(c, reinterpret_cast<const Bytef*>(channel.data()), static_cast<uInt>(channel.size()));
  const Bytef nul = 0;
  c = ::crc32(c, &nul, 1);
  // zlib takes uInt lengths: feed large data in pieces.
  while (size > 0) {
    const std::size_t n = size > (1u << 30) ? (1u << 30) : size;
    c = ::crc32(c, data, static_cast<uInt>(n));
    data += n;
    size -= n;
  }
  return static_cast<std::uint32_t>(c);
}

}  // namespace vitreo::telemetry
