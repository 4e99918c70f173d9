#pragma once
// A device's last second of samples, for its device_status_t: how many arrived per second and how
// late each was (device timestamp mapped to the host clock → host receive). Driver thread only:
// on_sample() per sample, measure() at the status rate. Fixed storage, no allocation after
// construction (2048 samples: two seconds of a 1 kHz tracker, so a second is always covered).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>

namespace vitreo::rig {

class SampleWindow {
 public:
  static constexpr std::uint64_t kSpanUs = 1'000'000;

  void on_sample(std::uint64_t received_us, std::uint64_t latency_us) noexcept {
    received_[next_] = received_us;
    latency_[next_] = static_cast<std::uint32_t>(std::min<std::uint64_t>(latency_us, UINT32_MAX));
    next_ = (next_ + 1) % kCapacity;
    count_ = std::min(count_ + 1, kCapacity);
    if (first_us_ == 0) first_us_ = received_us;
  }
  // A new link: its rate is measured from its own first sample.
  void reset() noexcept { count_ = next_ = 0, first_us_ = 0; }

  struct Measured {
    float rate_hz = 0, latency_p50_us = 0, latency_p99_us = 0;
  };
  // Over the samples received within the last second before now_us (or since the link's first
  // sample, when that was more recent).
  Measured measure(std::uint64_t now_us) noexcept {
    std::size_t n = 0;
    for (std::size_t i = 0; i < count_; ++i) {
      const std::size_t at = (next_ + kCapacity - 1 - i) % kCapacity;
      if (received_[at] + kSpanUs < now_us) break;
      scratch_[n++] = latency_[at];
    }
    Measured m;
    if (n == 0) return m;
    const std::uint64_t span = std::min(kSpanUs, now_us > first_us_ ? now_us - first_us_ : 0);
    // The link's first 10 ms say nothing about its rate.
    if (span >= 10'000) m.rate_hz = static_cast<float>(static_cast<double>(n) * 1e6 / static_cast<double>(span));
    auto nearest_rank = [&](double q) {
      const auto k = static_cast<std::size_t>(std::max(1.0, std::ceil(q * static_cast<double>(n)))) - 1;
      std::nth_element(scratch_.begin(), scratch_.begin() + static_cast<std::ptrdiff_t>(k), scratch_.begin() + static_cast<std::ptrdiff_t>(n));
      return static_cast<float>(scratch_[k]);
    };
    m.latency_p50_us = nearest_rank(0.5);
    m.latency_p99_us = nearest_rank(0.99);
    return m;
  }

 private:
  static constexpr std::size_t kCapacity = 2048;
  std::array<std::uint64_t, kCapacity> received_{};
  std::array<std::uint32_t, kCapacity> latency_{};
  std::array<std::uint32_t, kCapacity> scratch_{};
  std::size_t next_ = 0, count_ = 0;
  std::uint64_t first_us_ = 0;
};

}  // namespace vitreo::rig
