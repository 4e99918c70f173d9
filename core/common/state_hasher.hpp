#pragma once
// A cheap, stable 64-bit hash of simulation state, used to prove determinism (two runs, or a run and
// its replay, end in the same bits). It hashes bit patterns, so -0.0 and 0.0 differ and NaNs are
// caught: exactly what "bit-identical" means. Not cryptographic.
#include <cstdint>
#include <cstring>
#include <span>

#include "core/common/types.hpp"

namespace vitreo::core {

class StateHasher {
 public:
  void add_u64(std::uint64_t v) {
    // Multiply-xorshift mixing (after splitmix64): fast and good enough to detect any difference.
    h_ ^= v + 0x9e3779b97f4a7c15ULL + (h_ << 6) + (h_ >> 2);
    h_ *= 0xff51afd7ed558ccdULL;
    h_ ^= h_ >> 33;
  }
  void add_double(double d) {
    std::uint64_t bits;
    std::memcpy(&bits, &d, sizeof bits);
    add_u64(bits);
  }
  void add_vec3(const Vec3& v) {
    add_double(v.x());
    add_double(v.y());
    add_double(v.z());
  }
  std::uint64_t value() const { return h_; }

 private:
  std::uint64_t h_ = 0xcbf29ce484222325ULL;
};

}  // namespace vitreo::core
