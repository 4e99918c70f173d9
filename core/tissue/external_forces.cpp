#include "core/tissue/external_forces.hpp"

#include <cmath>

#include "core/common/validate.hpp"

namespace vitreo::core {

Status apply_external_accelerations(Surface& surface, std::span<const AccelerationSample> samples, double dt_s) {
  if (!std::isfinite(dt_s) || !(dt_s > 0.0) || dt_s > 0.02) {
    return Status::error("apply_external_accelerations: dt must be finite and in (0, 0.02] s");
  }
  for (const auto& s : samples) {
    if (s.vertex >= surface.vertex_slots()) return Status::error("apply_external_accelerations: vertex out of range");
    if (!is_finite(s.acceleration_mm_s2)) return Status::error("apply_external_accelerations: non-finite acceleration");
  }
  for (const auto& s : samples) {
    if (!surface.vertex_alive(s.vertex) || surface.is_fixed(s.vertex)) continue;
    const Vec3 v = surface.velocity(s.vertex) + dt_s * s.acceleration_mm_s2;
    (void)surface.set_velocity(surface.vertex_id(s.vertex), v);  // wakes the vertex
  }
  return Status::ok();
}

}  // namespace vitreo::core
