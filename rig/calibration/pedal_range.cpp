#include "rig/calibration/pedal_range.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace vitreo::rig::calibration {

namespace {
double quantile(std::vector<double> v, double q) {  // by copy: nth_element reorders
  const std::size_t k = static_cast<std::size_t>(std::lround(q * static_cast<double>(v.size() - 1)));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}
}  // namespace

PedalRangeResult measure_pedal_range(const std::vector<double>& rest, const std::vector<double>& travel,
                                     const PedalRangeLimits& limits) {
  PedalRangeResult r;
  for (const std::vector<double>* v : {&rest, &travel})
    for (double x : *v)
      if (!std::isfinite(x)) {
        r.error = "a pedal reading is not finite";
        return r;
      }
  // At least one sample each whatever the limits say: the quantiles below need one.
  if (rest.size() < std::max<std::size_t>(limits.min_rest_samples, 1)) {
    r.error = "too few readings at rest: " + std::to_string(rest.size()) + " (need " +
              std::to_string(limits.min_rest_samples) + "); leave the pedal alone a little longer";
    return r;
  }
  if (travel.size() < std::max<std::size_t>(limits.min_travel_samples, 1)) {
    r.error = "too few readings over the travel: " + std::to_string(travel.size()) + " (need " +
              std::to_string(limits.min_travel_samples) + ")";
    return r;
  }
  // The rest reading is its median (jitter is symmetric about it); the far end is a high quantile
  // of the travel rather than its maximum, so that one noisy sample does not stretch the range.
  const double rest_median = quantile(rest, 0.5);
  double jitter = 0.0;
  for (double x : rest) jitter = std::max(jitter, std::abs(x - rest_median));
  r.rest_jitter = jitter;
  const double far = quantile(travel, 0.995);
  r.range.lo = rest_median;
  r.range.hi = far;
  if (!(far - rest_median >= limits.min_range)) {
    std::ostringstream s;
    s.setf(std::ios::fixed);
    s.precision(3);
    s << "the pedal travelled only " << (far - rest_median) << " of its reading (need " << limits.min_range
      << "); press it all the way down";
    r.error = s.str();
    return r;
  }
  r.range.dead_zone = std::min(0.5, jitter / (far - rest_median) + limits.dead_zone_margin);
  r.ok = true;
  return r;
}

}  // namespace vitreo::rig::calibration
