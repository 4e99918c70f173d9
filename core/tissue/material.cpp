#include "core/tissue/material.hpp"

#include <cmath>

#include "core/common/validate.hpp"

namespace vitreo::core {

void TissueMaterial::validate() const {
  const std::string p = "material '" + name + "': ";
  require_range(density_g_per_mm3, 1e-4, 1e-2, p + "density_g_per_mm3");
  require_range(thickness_mm, 1e-4, 5.0, p + "thickness_mm");
  // Documented stiffness range (retina ~5e3, epiretinal and fibrovascular membranes up to ~5e4);
  // the solver is stable over all of it at dt = 1 ms (tests/core).
  require_range(membrane_modulus_pa_mm, 0.0, 1e5, p + "membrane_modulus_pa_mm");
  require_range(bending_modulus_un_mm, 0.0, 1e4, p + "bending_modulus_un_mm");
  if (!(tear_strain > 0.0)) throw InvalidArgument(p + "tear_strain must be > 0 (or infinity)");
  require_range(drag_pa_s_per_mm, 0.0, 1e3, p + "drag_pa_s_per_mm");
  require_range(internal_damping_s, 0.0, 1.0, p + "internal_damping_s");
  require_range(entrained_fluid_mm, 0.0, 20.0, p + "entrained_fluid_mm");
  require_range(plastic_yield_strain, 0.0, 10.0, p + "plastic_yield_strain");
  require_range(plastic_rate_per_s, 0.0, 1e3, p + "plastic_rate_per_s");
}

}  // namespace vitreo::core
