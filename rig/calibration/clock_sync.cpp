#include "rig/calibration/clock_sync.hpp"

#include <algorithm>
#include <cmath>

namespace vitreo::rig::calibration {

double ClockResult::device_to_host_us(double device_us) const {
  // device = host + offset + drift·(host − ref)  ⇒  host = (device − offset + drift·ref) / (1 + drift)
  const double d = drift_ppm * 1e-6, ref = static_cast<double>(reference_host_us);
  return (device_us - offset_ms * 1e3 + d * ref) / (1.0 + d);
}

ClockResult estimate_clock(const std::vector<TimeSyncExchange>& ex, const ClockLimits& limits) {
  ClockResult r;
  r.exchanges = ex.size();
  if (ex.size() < std::max<std::size_t>(limits.min_exchanges, 2)) {
    r.error = "too few time-sync exchanges: " + std::to_string(ex.size()) + " (need " +
              std::to_string(std::max<std::size_t>(limits.min_exchanges, 2)) + ")";
    return r;
  }
  struct Point {
    double host_mid_us, offset_us, delay_us;
  };
  std::vector<Point> pts;
  for (const TimeSyncExchange& e : ex) {
    if (e.host_rx_us < e.host_tx_us || e.device_tx_us < e.device_rx_us) {
      r.error = "a time-sync exchange has its timestamps out of order";
      return r;
    }
    // Differences first, in signed 64-bit: the two clocks' epochs are far apart.
    const double a = static_cast<double>(static_cast<std::int64_t>(e.device_rx_us - e.host_tx_us));
    const double b = static_cast<double>(static_cast<std::int64_t>(e.device_tx_us - e.host_rx_us));
    const double delay = static_cast<double>(e.host_rx_us - e.host_tx_us) - static_cast<double>(e.device_tx_us - e.device_rx_us);
    pts.push_back({0.5 * (static_cast<double>(e.host_tx_us) + static_cast<double>(e.host_rx_us)), 0.5 * (a + b),
                   std::max(0.0, delay)});
  }
  std::vector<double> delays;
  for (const Point& p : pts) delays.push_back(p.delay_us);
  std::nth_element(delays.begin(), delays.begin() + static_cast<std::ptrdiff_t>(delays.size() / 2), delays.end());
  const double cut = delays[delays.size() / 2];
  std::vector<Point> kept;
  for (const Point& p : pts)
    if (p.delay_us <= cut) kept.push_back(p);
  double lo = kept.front().host_mid_us, hi = lo;
  for (const Point& p : kept) lo = std::min(lo, p.host_mid_us), hi = std::max(hi, p.host_mid_us);
  if ((hi - lo) * 1e-6 < limits.min_span_s) {
    r.error = "the time-sync exchanges span " + std::to_string((hi - lo) * 1e-6) + " s (need " +
              std::to_string(limits.min_span_s) + " s) to measure drift";
    return r;
  }
  // Least-squares line offset = c0 + c1·(host − ref), with ref the latest host time so that the
  // reported offset is the one in force now.
  const double ref = hi;
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  const double n = static_cast<double>(kept.size());
  for (const Point& p : kept) {
    const double x = p.host_mid_us - ref;
    sx += x, sy += p.offset_us, sxx += x * x, sxy += x * p.offset_us;
  }
  const double c1 = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  const double c0 = (sy - c1 * sx) / n;
  double sq = 0;
  for (const Point& p : kept) {
    const double e = p.offset_us - (c0 + c1 * (p.host_mid_us - ref));
    sq += e * e;
  }
  std::vector<double> kd;
  for (const Point& p : kept) kd.push_back(p.delay_us);
  std::nth_element(kd.begin(), kd.begin() + static_cast<std::ptrdiff_t>(kd.size() / 2), kd.end());
  r.reference_host_us = static_cast<std::uint64_t>(ref);
  r.offset_ms = c0 * 1e-3;
  r.drift_ppm = c1 * 1e6;
  r.latency_ms = 0.5 * kd[kd.size() / 2] * 1e-3;
  r.rms_ms = std::sqrt(sq / n) * 1e-3;
  r.used = kept.size();
  r.ok = true;
  return r;
}

}  // namespace vitreo::rig::calibration
