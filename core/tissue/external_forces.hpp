#pragma once
// External acceleration fields applied from outside the step (an instrument's suction, a
// magnet): the force hook for mechanisms that are not part of the solver's own stages.
//
// Call between steps (at the step boundary), with the dt of the coming step: each vertex's velocity
// gains a·dt (a symplectic-Euler kick; the step's implicit drag and constraints then act on it as on
// any other velocity), and the touched vertices are woken. Anchored and dead vertices are skipped.
// Nothing allocates.
#include <cstdint>
#include <span>

#include "core/common/status.hpp"
#include "core/common/types.hpp"
#include "core/tissue/surface.hpp"

namespace vitreo::core {

struct AccelerationSample {
  std::uint32_t vertex;
  Vec3 acceleration_mm_s2;
};

// Refuses (changing nothing) a non-finite or non-positive dt, a vertex index out of range or a
// non-finite acceleration.
Status apply_external_accelerations(Surface& surface, std::span<const AccelerationSample> samples, double dt_s);

}  // namespace vitreo::core
