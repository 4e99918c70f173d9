#pragma once
// The one way vitreo decodes LCM bytes that came from outside (a packet on the bus, an event in a
// log): decode_message() never throws and accepts a message only when its bytes add up exactly.
//
// Why a layer of its own: the decoders lcm-gen 1.3.1 generates trust a packet's lengths (a string
// length of 0 throws std::length_error, INT_MIN over-reads, a negative array count throws). The
// build patches them (cmake/PatchLcmDecoders.cmake); this layer is the second wall — it catches
// anything still thrown (std::bad_alloc included), refuses sizes an int cannot hold, and refuses a
// message whose encoding is shorter than the bytes given (trailing bytes mean a garbled or foreign
// packet: LCM messages carry no padding).
#include <climits>
#include <cstddef>
#include <cstdint>

namespace vitreo::telemetry {

enum class DecodeError : std::uint8_t {
  None = 0,
  Oversized,      // more bytes than the caller allows (or than an int can count)
  Malformed,      // the generated decoder refused it: wrong fingerprint, a length or count that does not fit
  TrailingBytes,  // decoded from fewer bytes than were given
  Exception,      // the decoder threw (it must not; counted apart so a test can tell)
};

constexpr const char* to_string(DecodeError e) noexcept {
  switch (e) {
    case DecodeError::None: return "ok";
    case DecodeError::Oversized: return "oversized";
    case DecodeError::Malformed: return "malformed (fingerprint, length or count)";
    case DecodeError::TrailingBytes: return "trailing bytes after the message";
    case DecodeError::Exception: return "decoder threw";
  }
  return "?";
}

// Decodes `size` bytes into `out` (left in an unspecified but valid state on failure).
template <class Msg>
DecodeError decode_message(const void* data, std::size_t size, Msg& out,
                           std::size_t max_size = static_cast<std::size_t>(INT_MAX)) noexcept {
  if (size > max_size || size > static_cast<std::size_t>(INT_MAX)) return DecodeError::Oversized;
  if (data == nullptr && size > 0) return DecodeError::Malformed;
  int used = -1;
  try {
    used = out.decode(data, 0, static_cast<int>(size));
  } catch (...) {
    return DecodeError::Exception;
  }
  if (used < 0) return DecodeError::Malformed;
  if (static_cast<std::size_t>(used) != size) return DecodeError::TrailingBytes;
  return DecodeError::None;
}

}  // namespace vitreo::telemetry
