#pragma once
// LCM's wire format written by hand, for tests that need packets the generated encoders would never
// produce (negative lengths, short strings, counts that lie). Independent of the generated code but
// for the type fingerprint: LCM encodes big-endian; a string is int32 length (bytes + 1), the bytes
// and a NUL; arrays have no header of their own (their count is a field before them).
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace vitreo::test {

class LcmBytes {
 public:
  LcmBytes& i8(std::int8_t v) {
    b_.push_back(static_cast<std::uint8_t>(v));
    return *this;
  }
  LcmBytes& i16(std::int16_t v) { return be(static_cast<std::uint16_t>(v), 2); }
  LcmBytes& i32(std::int32_t v) { return be(static_cast<std::uint32_t>(v), 4); }
  LcmBytes& i64(std::int64_t v) { return be(static_cast<std::uint64_t>(v), 8); }
  LcmBytes& f64(double v) {
    std::uint64_t u;
    std::memcpy(&u, &v, 8);
    return be(u, 8);
  }
  LcmBytes& f32(float v) {
    std::uint32_t u;
    std::memcpy(&u, &v, 4);
    return be(u, 4);
  }
  LcmBytes& boolean(bool v) { return i8(v ? 1 : 0); }
  // A well-formed string.
  LcmBytes& str(const std::string& s) {
    i32(static_cast<std::int32_t>(s.size() + 1));
    raw(s);
    b_.push_back(0);
    return *this;
  }
  // A string whose length field says `length` whatever follows.
  LcmBytes& str_len(std::int32_t length) { return i32(length); }
  LcmBytes& raw(const std::string& s) {
    b_.insert(b_.end(), s.begin(), s.end());
    return *this;
  }
  LcmBytes& bytes(std::size_t n, std::uint8_t fill) {
    b_.insert(b_.end(), n, fill);
    return *this;
  }
  const std::vector<std::uint8_t>& data() const { return b_; }
  std::size_t size() const { return b_.size(); }

 private:
  LcmBytes& be(std::uint64_t v, int n) {
    for (int i = n - 1; i >= 0; --i) b_.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
    return *this;
  }
  std::vector<std::uint8_t> b_;
};

}  // namespace vitreo::test
