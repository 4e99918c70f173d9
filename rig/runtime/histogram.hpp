#pragma once
// Fixed-bucket duration histogram for the hot loop: recording is one increment, nothing allocates
// after construction, and quantiles are exact to one bucket width (1 µs by default). Values past the
// last bucket land in it and quantiles that fall there report the exact maximum instead.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace vitreo::runtime {

class DurationHistogram {
 public:
  explicit DurationHistogram(std::int64_t bucket_ns = 1000, std::size_t buckets = 8192);

  void record(std::int64_t ns) noexcept;
  void reset() noexcept;

  std::uint64_t count() const noexcept { return count_; }
  std::int64_t min_ns() const noexcept { return count_ ? min_ : 0; }
  std::int64_t max_ns() const noexcept { return count_ ? max_ : 0; }
  double mean_ns() const noexcept { return count_ ? static_cast<double>(sum_) / static_cast<double>(count_) : 0.0; }
  // Nearest-rank quantile, q in [0,1]: the lower edge of the bucket holding the ceil(q*n)-th
  // smallest value (clamped to [min, max]); 0 when empty.
  std::int64_t quantile_ns(double q) const noexcept;
  std::int64_t bucket_ns() const noexcept { return bucket_ns_; }

 private:
  std::int64_t bucket_ns_;
  std::vector<std::uint32_t> counts_;
  std::uint64_t count_ = 0;
  std::int64_t min_ = 0;
  std::int64_t max_ = 0;
  std::int64_t sum_ = 0;
};

}  // namespace vitreo::runtime
