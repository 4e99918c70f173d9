#pragma once
// Mechanical description of one tissue surface. Values carry units in their names; scenes give a
// source for each (scenes/materials). Defaults are the retina's.
#include <string>

namespace vitreo::core {

struct TissueMaterial {
  std::string name = "retina";

  // Mass: areal density = volumetric density × thickness. Retina 1.0174 g/ml (Michels et al. 1990,
  // quoted in the thesis ch. 2.3.3), 0.25 mm thick.
  double density_g_per_mm3 = 1.0174e-3;
  double thickness_mm = 0.25;

  // In-plane elasticity as a 2-D membrane modulus E·t (Pa·mm = µN/mm), with Poisson's ratio 1/3
  // (what a network of springs can represent). Springs get their stiffness from the triangles'
  // linear elasticity (Surface::triangle_spring_share): Van Gelder's k = E·t · (adjacent rest
  // area) / (rest length)² on equilateral triangles (Van Gelder 1998; the thesis used the same
  // area weighting after Wilhelms & Van Gelder 1997), corrected on other shapes so a uniform
  // stretch stores the continuum's energy. Retina E ≈ 20 kPa → 5000 µN/mm at 0.25 mm.
  double membrane_modulus_pa_mm = 5000.0;

  // Bending modulus D (flexural rigidity, µN·mm): resistance to curving the sheet, energy ½ D κ²
  // per unit area for a curvature κ. For a homogeneous plate D = E t³ / (12 (1 − ν²)) (Kirchhoff);
  // with the spring network's Poisson ratio of 1/3 that is membrane_modulus × t² / (32/3). Retina:
  // 5000 µN/mm × (0.25 mm)² × 3/32 ≈ 29 µN·mm. 0 switches bending off (a chain, a string).
  double bending_modulus_un_mm = 29.3;

  // Tearing: a spring stretched past this engineering strain splits (retina tears at 35–55 %
  // stretch, Michels et al. 1990). Infinity disables tearing.
  double tear_strain = 0.45;

  // Drag from the surrounding gel and fluid, per unit area (µN·s/mm³ = Pa·s/mm): damps absolute
  // motion so tissue released in vitreous settles instead of oscillating. A 0.25 mm sheet weighs so
  // little that the medium, not its own inertia, sets how fast it moves: with 20 Pa·s/mm a net
  // 150 Pa detachment pressure lifts the retina at ~7 mm/s. It also adds h·c to the effective mass
  // of each substep, which keeps the one-iteration solver close to the nominal stiffness on fine
  // meshes (see README, "Solver accuracy").
  double drag_pa_s_per_mm = 20.0;

  // Internal (viscoelastic) damping of the springs, as a time constant: each spring carries a
  // dashpot of coefficient τ·k in parallel (stiffness-proportional Rayleigh damping). Soft tissue is
  // strongly viscous; without this a light membrane rings after every release. Applied implicitly in
  // each vertex's Newton step as ½ (τ k / h) (n · Δd)² over the substep (stage_solve.cpp).
  double internal_damping_s = 0.01;

  // Added mass: a sheet this thin cannot move without moving the fluid around it, and that fluid
  // outweighs the sheet many times over. Modelled as a fluid layer of this thickness moving with the
  // tissue (inertia only — it has no weight). A disc of radius a moving broadside carries
  // 8/3 ρ a³ of fluid (Lamb, Hydrodynamics §108), ≈ 0.85 ρ a per unit area: 1.5 mm matches
  // the ~2 mm patches that move together in surgery. Ignored above the fluid level (under gas).
  double entrained_fluid_mm = 1.5;

  // Plasticity: above `plastic_yield_strain` (strain, and bend in radians across a spring) the rest
  // lengths and curvatures creep toward the current shape at `plastic_rate_per_s`, so a membrane
  // released after a pull stays roughly where it was left (surgeons' complaint about springing
  // back, thesis ch. 3). Rate 0 disables it.
  double plastic_yield_strain = 0.05;
  double plastic_rate_per_s = 0.0;

  double areal_density_g_per_mm2() const { return density_g_per_mm3 * thickness_mm; }

  // Throws InvalidArgument naming the first value out of its documented range.
  void validate() const;
};

// The material's fields, listed once for snapshots in both directions (core/common/state_io.hpp).
template <class IO, class M>
void material_io(IO& io, M& m) {
  io.str(m.name);
  io.pod(m.density_g_per_mm3);
  io.pod(m.thickness_mm);
  io.pod(m.membrane_modulus_pa_mm);
  io.pod(m.bending_modulus_un_mm);
  io.pod(m.tear_strain);
  io.pod(m.drag_pa_s_per_mm);
  io.pod(m.internal_damping_s);
  io.pod(m.entrained_fluid_mm);
  io.pod(m.plastic_yield_strain);
  io.pod(m.plastic_rate_per_s);
}

}  // namespace vitreo::core
