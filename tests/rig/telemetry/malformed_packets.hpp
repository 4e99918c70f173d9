#pragma once
// A catalogue of malformed LCM payloads, for the unit tests, the live udpm test (lcm_probe inject)
// and the fuzz seed corpus: the packets that crashed the rig (issue 20) and their relatives.
#include <climits>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "tests/rig/telemetry/lcm_bytes.hpp"
#include "vitreo_lcm/command_ack_t.hpp"
#include "vitreo_lcm/operator_command_t.hpp"

namespace vitreo::test {

struct NamedPacket {
  std::string name;
  std::vector<std::uint8_t> bytes;
};

// operator_command_t / command_ack_t fields up to the first string, with that string's length field
// saying `len` whatever follows.
inline LcmBytes command_with_source_length(std::int32_t len, const std::string& body = "abc") {
  LcmBytes b;
  b.i64(vitreo_lcm::operator_command_t::getHash()).i64(1).str_len(len).raw(body);
  b.i64(1).i8(vitreo_lcm::operator_command_t::PAUSE).f64(0).str("");
  return b;
}

inline LcmBytes ack_with_source_length(std::int32_t len) {
  LcmBytes b;
  b.i64(vitreo_lcm::command_ack_t::getHash()).i64(1).str_len(len).raw("ci");
  b.i64(1).i8(vitreo_lcm::operator_command_t::PAUSE).boolean(true).str("");
  return b;
}

// Every packet here must be refused by the checked decoder of the type it pretends to be.
inline std::vector<NamedPacket> malformed_commands() {
  std::vector<NamedPacket> out;
  auto add = [&](std::string name, const LcmBytes& b) { out.push_back({std::move(name), b.data()}); };
  add("source-length-INT_MIN", command_with_source_length(INT_MIN));
  add("source-length-0", command_with_source_length(0, ""));
  add("source-length-minus-1", command_with_source_length(-1));
  add("source-length-INT_MAX", command_with_source_length(INT_MAX));
  add("source-length-past-end", command_with_source_length(1000));
  {
    LcmBytes b;
    b.i64(vitreo_lcm::operator_command_t::getHash()).i64(1).str("ci").i64(1).i8(3).f64(0).str_len(INT_MIN);
    add("arg-length-INT_MIN", b);
  }
  {
    LcmBytes b = command_with_source_length(4, "ci\0");
    LcmBytes wrong;
    wrong.i64(vitreo_lcm::operator_command_t::getHash() ^ 0x5a5a).raw(std::string(b.data().begin() + 8, b.data().end()));
    add("wrong-fingerprint", wrong);
  }
  {
    LcmBytes b;
    b.i64(vitreo_lcm::operator_command_t::getHash()).i64(1);
    add("truncated", b);
  }
  {
    LcmBytes b;
    b.i64(vitreo_lcm::operator_command_t::getHash()).i64(1).str("ci").i64(1).i8(3).f64(0).str("").bytes(5, 0xee);
    add("trailing-bytes", b);
  }
  add("empty", LcmBytes());
  add("oversized-70k", LcmBytes().bytes(70 * 1024, 0x41));
  return out;
}

inline std::vector<NamedPacket> malformed_acks() {
  return {{"ack-source-length-INT_MIN", ack_with_source_length(INT_MIN).data()},
          {"ack-source-length-0", ack_with_source_length(0).data()}};
}

}  // namespace vitreo::test
