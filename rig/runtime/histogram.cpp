#include "rig/runtime/histogram.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace vitreo::runtime {

DurationHistogram::DurationHistogram(std::int64_t bucket_ns, std::size_t buckets)
    : bucket_ns_(bucket_ns), counts_(buckets, 0) {
  if (bucket_ns <= 0 || buckets < 2) throw std::invalid_argument("DurationHistogram: bucket_ns > 0, buckets >= 2");
}

void DurationHistogram::record(std::int64_t ns) noexcept {
  if (ns < 0) ns = 0;
  const auto idx = std::min<std::size_t>(static_cast<std::size_t>(ns / bucket_ns_), counts_.size() - 1);
  ++counts_[idx];
  if (count_ == 0) {
    min_ = max_ = ns;
  } else {
    min_ = std::min(min_, ns);
    max_ = std::max(max_, ns);
  }
  ++count_;
  sum_ += ns;
}

void DurationHistogram::reset() noexcept {
  std::fill(counts_.begin(), counts_.end(), 0u);
  count_ = 0;
  min_ = max_ = sum_ = 0;
}

std::int64_t DurationHistogram::quantile_ns(double q) const noexcept {
  if (count_ == 0) return 0;
  q = std::clamp(q, 0.0, 1.0);
  const auto rank = std::max<std::uint64_t>(1, static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(count_))));
  std::uint64_t seen = 0;
  for (std::size_t i = 0; i < counts_.size(); ++i) {
    seen += counts_[i];
    if (seen >= rank) {
      if (i == counts_.size() - 1) return max_;  // overflow bucket: only the max is known exactly
      return std::clamp(static_cast<std::int64_t>(i) * bucket_ns_, min_, max_);
    }
  }
  return max_;
}

}  // namespace vitreo::runtime
