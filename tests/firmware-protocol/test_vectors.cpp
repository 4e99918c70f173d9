// The checked-in vectors (firmware-protocol/vectors/, written by an independent Python
// implementation of PROTOCOL.md) must decode to their stated meaning through the C codec and the
// C++ helpers, and the meaning must encode back to the same bytes.
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "firmware-protocol/vp.hpp"

namespace {

using vitreo::proto::Bytes;

struct Vector {
  std::string file, transport, meaning;
};

const std::string kDir = std::string(VITREO_SOURCE_DIR) + "/firmware-protocol/vectors/";

std::vector<Vector> load() {
  std::ifstream in(kDir + "vectors.txt");
  std::vector<Vector> v;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    auto bar = line.find(" | ");
    std::istringstream head(line.substr(0, bar));
    Vector x;
    head >> x.file >> x.transport;
    x.meaning = line.substr(bar + 3);
    v.push_back(x);
  }
  return v;
}

Bytes read(const std::string& f) {
  std::ifstream in(kDir + f, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), {});
}

int status_from_name(const std::string& s) {
  for (int st = VP_OK; st >= VP_ERR_ARG; --st) {
    static const char* names[] = {"OK", "TRUNCATED", "CRC", "VERSION", "UNKNOWN_TYPE", "LENGTH",
                                  "RANGE", "FRAMING", "OVERFLOW", "SEQUENCE", "ARG"};
    if (s == names[-st]) return st;
  }
  ADD_FAILURE() << "unknown status name " << s;
  return 99;
}

struct CanRec {
  std::uint32_t id;
  bool fd;
  Bytes data;
};
std::vector<CanRec> split_can(const Bytes& b) {
  std::vector<CanRec> out;
  std::size_t i = 0;
  while (i + 6 <= b.size()) {
    CanRec r;
    r.id = std::uint32_t(b[i]) << 24 | std::uint32_t(b[i + 1]) << 16 | std::uint32_t(b[i + 2]) << 8 | b[i + 3];
    r.fd = b[i + 4] == 1;
    std::size_t n = b[i + 5];
    r.data.assign(b.begin() + long(i + 6), b.begin() + long(i + 6 + n));
    out.push_back(r);
    i += 6 + n;
  }
  EXPECT_EQ(i, b.size());
  return out;
}

// Decodes a vector file through the C API; returns the last status and message.
int decode(const Vector& v, const Bytes& bytes, vp_message& m) {
  if (v.transport == "serial") {
    vp_serial_rx rx;
    vp_serial_rx_init(&rx);
    std::size_t used = 0;
    int st = vp_serial_rx_push(&rx, bytes.data(), bytes.size(), &used, &m);
    EXPECT_EQ(used, bytes.size()) << v.file << ": one frame per file";
    return st;
  }
  if (v.transport == "usb") return vp_usb_decode(bytes.data(), bytes.size(), &m);
  vp_can_rx rx;
  vp_can_rx_init(&rx);
  int st = VP_NEED_MORE;
  for (auto& f : split_can(bytes)) {
    std::uint8_t node = 0;
    st = f.fd ? vp_canfd_decode(f.id, f.data.data(), f.data.size(), &node, &m)
              : vp_can_rx_push(&rx, f.id, f.data.data(), f.data.size(), &node, &m);
    if (st == VP_OK) {
      EXPECT_EQ(node, 17);
    }
  }
  return st;
}

TEST(ProtocolVectors, AllVectorsPresent) { EXPECT_EQ(load().size(), 53u); }

TEST(ProtocolVectors, DecodeToStatedMeaning) {
  for (const auto& v : load()) {
    SCOPED_TRACE(v.file);
    Bytes bytes = read(v.file);
    ASSERT_FALSE(bytes.empty());
    vp_message m{};
    int st = decode(v, bytes, m);
    if (v.meaning.rfind("error ", 0) == 0) {
      EXPECT_EQ(st, status_from_name(v.meaning.substr(6))) << vp_status_name(st);
      continue;
    }
    ASSERT_EQ(st, VP_OK) << vp_status_name(st);
    std::string err;
    auto expected = vitreo::proto::parse(v.meaning, &err);
    ASSERT_TRUE(expected) << err;
    EXPECT_EQ(vitreo::proto::describe(m), vitreo::proto::describe(*expected));
    EXPECT_EQ(vitreo::proto::describe(m), v.meaning) << "text form is the one in vectors.txt";
  }
}

TEST(ProtocolVectors, MeaningEncodesToSameBytes) {
  int checked = 0;
  for (const auto& v : load()) {
    if (v.meaning.rfind("error ", 0) == 0 || v.file.rfind("newer_minor", 0) == 0) continue;
    SCOPED_TRACE(v.file);
    auto m = vitreo::proto::parse(v.meaning);
    ASSERT_TRUE(m);
    Bytes bytes = read(v.file);
    if (v.transport == "serial") {
      EXPECT_EQ(vitreo::proto::encode_serial(*m), bytes);
    } else if (v.transport == "usb") {
      EXPECT_EQ(vitreo::proto::encode_usb(*m), bytes);
    } else {
      auto recs = split_can(bytes);
      ASSERT_FALSE(recs.empty());
      if (recs[0].fd) {
        auto f = vitreo::proto::encode_canfd(*m, 17);
        ASSERT_TRUE(f);
        EXPECT_EQ(f->id, recs[0].id);
        EXPECT_EQ(f->data, recs[0].data);
      } else {
        auto frames = vitreo::proto::encode_can_classic(*m, 17, recs[0].data.back() & 0x1F);
        ASSERT_EQ(frames.size(), recs.size());
        for (std::size_t i = 0; i < frames.size(); ++i) {
          EXPECT_EQ(frames[i].id, recs[i].id);
          EXPECT_EQ(frames[i].data, recs[i].data);
        }
      }
    }
    ++checked;
  }
  EXPECT_EQ(checked, 43);
}

// The C++ stream decoder must agree with the C decoder on the concatenation of all serial vectors,
// fed one byte at a time (the worst chunking a UART driver can produce).
TEST(ProtocolVectors, StreamDecoderOnConcatenatedSerialVectors) {
  Bytes all;
  std::vector<std::string> expected;
  for (const auto& v : load()) {
    if (v.transport != "serial") continue;
    Bytes b = read(v.file);
    all.insert(all.end(), b.begin(), b.end());
    expected.push_back(v.meaning);
  }
  vitreo::proto::SerialDecoder dec;
  std::vector<std::string> got;
  for (std::uint8_t b : all)
    dec.feed(std::span<const std::uint8_t>(&b, 1), [&](int st, const vp_message& m) {
      if (st == VP_OK) {
        got.push_back(vitreo::proto::describe(m));
      } else {
        static const char* names[] = {"OK", "TRUNCATED", "CRC", "VERSION", "UNKNOWN_TYPE", "LENGTH",
                                      "RANGE", "FRAMING", "OVERFLOW", "SEQUENCE", "ARG"};
        got.push_back(std::string("error ") + names[-st]);
      }
    });
  EXPECT_EQ(got, expected);
}

}  // namespace
