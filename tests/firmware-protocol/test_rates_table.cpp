// PROTOCOL.md §7 "Rates and bus load" read from the document itself and checked against the
// codec: every row's serial frame size and classic-CAN frame count must be what vp_serial_encode and
// vp_can_segment produce for that message, and the per-second figures the rate times those. A table
// that drifts from the segmentation rules (it once said 1750 eyeball frames/s and 20 heartbeat
// frames/s where the code makes 8 and 3 frames of a message) fails here.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "drivers/session.hpp"
#include "firmware-protocol/vp.h"

namespace {

struct Row {
  std::string device, message;
  long rate_hz = 0, serial_bytes_per_s = 0, serial_frame = 0, can_frames_per_s = 0;
};

std::vector<Row> rates_table() {
  std::ifstream in(std::string(VITREO_SOURCE_DIR) + "/firmware-protocol/PROTOCOL.md");
  std::string line;
  bool in_section = false;
  std::vector<Row> rows;
  // | tracker, per instrument | POSE_SAMPLE | 1000 Hz | 51 000 (51 B) | 7 000 |
  // Split on '|' by hand: GCC 12's <regex> trips -Werror=maybe-uninitialized under the sanitizers.
  auto number = [](std::string s) {
    s.erase(std::remove(s.begin(), s.end(), ' '), s.end());
    return std::stol(s);
  };
  auto trim = [](const std::string& s) {
    const auto b = s.find_first_not_of(' ');
    const auto e = s.find_last_not_of(' ');
    return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
  };
  auto ends_with = [](const std::string& s, const std::string& tail) {
    return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
  };
  while (std::getline(in, line)) {
    if (line.rfind("## ", 0) == 0) in_section = line.find("Rates and bus load") != std::string::npos;
    if (!in_section || line.rfind("| ", 0) != 0) continue;
    std::vector<std::string> cells;
    std::stringstream split(line.substr(1));
    for (std::string cell; std::getline(split, cell, '|');) cells.push_back(trim(cell));
    if (cells.size() != 5 || !ends_with(cells[2], " Hz")) continue;  // the header row
    const std::string& serial = cells[3];  // "51 000 (51 B)"
    const auto open = serial.find('('), close = serial.find(" B)");
    if (open == std::string::npos || close == std::string::npos) continue;
    rows.push_back({cells[0], cells[1], number(cells[2].substr(0, cells[2].size() - 3)),
                    number(serial.substr(0, open)), number(serial.substr(open + 1, close - open - 1)),
                    number(cells[4])});
  }
  return rows;
}

// A message of the type with every field at its largest legal value (COBS's overhead does not
// depend on the values beyond zero bytes, and a maximal frame is the budget's worst case).
vp_message typical(const std::string& name) {
  static const std::map<std::string, std::uint8_t> types = {{"POSE_SAMPLE", VP_MSG_POSE_SAMPLE},
                                                            {"PEDAL_STATE", VP_MSG_PEDAL_STATE},
                                                            {"EYEBALL_STATE", VP_MSG_EYEBALL_STATE},
                                                            {"HEARTBEAT", VP_MSG_HEARTBEAT}};
  vp_message m{};
  m.version_minor = VP_PROTO_MINOR;
  m.type = types.at(name);
  m.seq = 7;
  return m;
}

}  // namespace

TEST(ProtocolRatesTable, FrameSizesAndCountsFollowTheCodec) {
  const std::vector<Row> rows = rates_table();
  ASSERT_EQ(rows.size(), 4u) << "PROTOCOL.md §7 lists the tracker, pedals, eyeball and heartbeat";
  for (const Row& r : rows) {
    SCOPED_TRACE(r.device + " " + r.message);
    const vp_message m = typical(r.message);
    std::uint8_t frame[VP_SERIAL_MAX_FRAME];
    size_t serial_len = 0;
    ASSERT_EQ(vp_serial_encode(&m, frame, sizeof frame, &serial_len), VP_OK);
    vp_can_frame8 frames[VP_CAN_MAX_SEGMENTS];
    size_t can_frames = 0;
    std::uint32_t id = 0;
    ASSERT_EQ(vp_can_segment(&m, 5, 0, &id, frames, VP_CAN_MAX_SEGMENTS, &can_frames), VP_OK);
    // COBS(packet ‖ CRC-32C) ‖ 0x00: one byte of COBS overhead below 254 bytes, whatever the values.
    EXPECT_EQ(r.serial_frame, static_cast<long>(serial_len));
    EXPECT_EQ(r.serial_bytes_per_s, r.rate_hz * r.serial_frame) << "bytes/s = rate x frame";
    EXPECT_EQ(r.can_frames_per_s, r.rate_hz * static_cast<long>(can_frames))
        << "classic CAN: " << can_frames << " frames a message at " << r.rate_hz << " Hz";
  }
}

// The table's rates are the ones the host configures when the rig file names none.
TEST(ProtocolRatesTable, TheHostConfiguresTheTablesRates) {
  std::map<std::string, long> rate;
  for (const Row& r : rates_table()) rate[r.message] = r.rate_hz;
  EXPECT_EQ(rate["POSE_SAMPLE"], vitreo::drivers::nominal_sample_rate_hz(VP_DEVICE_TRACKER));
  EXPECT_EQ(rate["PEDAL_STATE"], vitreo::drivers::nominal_sample_rate_hz(VP_DEVICE_PEDAL));
  EXPECT_EQ(rate["EYEBALL_STATE"], vitreo::drivers::nominal_sample_rate_hz(VP_DEVICE_EYEBALL));
}
