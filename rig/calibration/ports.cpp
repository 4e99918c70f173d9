#include "rig/calibration/ports.hpp"

#include <cmath>
#include <sstream>

namespace vitreo::rig::calibration {

HeldPoint held_point(const std::vector<core::Vec3>& tips) {
  HeldPoint h;
  for (const core::Vec3& p : tips) h.mean_mm += p;
  h.mean_mm /= static_cast<double>(tips.size());
  double sq = 0.0;
  for (const core::Vec3& p : tips) sq += (p - h.mean_mm).squaredNorm();
  h.spread_mm = std::sqrt(sq / static_cast<double>(tips.size()));
  return h;
}

PortResult measure_port(const std::vector<core::Vec3>& tips, const PortLimits& limits) {
  PortResult r;
  r.samples = tips.size();
  if (tips.size() < std::max<std::size_t>(limits.min_samples, 1)) {
    r.error = "too few samples at the port: " + std::to_string(tips.size()) + " (need " +
              std::to_string(std::max<std::size_t>(limits.min_samples, 1)) + "); hold the tip in the trocar longer";
    return r;
  }
  for (const core::Vec3& p : tips) {
    if (!p.allFinite()) {
      r.error = "a tip sample is not finite";
      return r;
    }
  }
  const HeldPoint held = held_point(tips);
  r.position_mm = held.mean_mm;
  r.spread_mm = held.spread_mm;
  if (r.position_mm.norm() < 1e-6) {
    r.error = "the port measured at the globe centre; is the registration applied?";
    return r;
  }
  r.outward = r.position_mm.normalized();
  if (!(r.spread_mm <= limits.max_spread_mm)) {
    std::ostringstream s;
    s.setf(std::ios::fixed);
    s.precision(3);
    s << "the tip moved while at the port (spread " << r.spread_mm << " mm, limit " << limits.max_spread_mm
      << " mm); hold it still in the trocar";
    r.error = s.str();
    return r;
  }
  r.ok = true;
  return r;
}

}  // namespace vitreo::rig::calibration
