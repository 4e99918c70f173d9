#pragma once
// A simple retina: a spherical cap lining a spherical globe, anchored at the ora serrata and around
// the optic disc, optionally with a detached region and an epiretinal membrane attached to it.
//
// This is the embedded default of the main job and the workload of the solver benchmark; the full
// procedural eye (non-spherical globe, lens, iris, gel, ports) is built by core/anatomy's eye model.
#include <cstdint>

#include "core/tissue/tissue_world.hpp"

namespace vitreo::core {

struct RetinaCapOptions {
  double globe_radius_mm = 12.0;
  // Polar angle of the ora serrata from the posterior pole (the retina covers 0..this).
  double ora_serrata_deg = 110.0;
  int retina_vertices = 20000;
  // Optic disc: angular offset from the posterior pole (nasal, +x) and radius of the anchored rim.
  double optic_disc_offset_deg = 15.0;
  double optic_disc_radius_mm = 0.9;

  // Detachment (thesis ch. 2.4): a pressure toward the globe centre on the retina within this
  // angular radius of `detachment_center_deg` (polar angle, on the temporal side −x).
  bool detachment = true;
  double detachment_center_deg = 60.0;
  double detachment_radius_deg = 25.0;
  // Net of intraocular pressure this is ~150 Pa inward: enough for a bullous detachment a few
  // millimetres high held by the retina's tension, as in a fresh rhegmatogenous detachment.
  double detachment_pressure_pa = units::mmhg_to_pa(15.0) + 150.0;

  // An epiretinal membrane over the posterior pole: a copy of the retina's mesh within
  // `membrane_radius_deg` of the pole, attached to the retina at every
  // `membrane_attachment_stride`-th vertex through coincident "instance vertices" (thesis ch. 2.3.1).
  bool membrane = false;
  double membrane_radius_deg = 20.0;
  int membrane_attachment_stride = 4;
  double membrane_break_force_un = 50.0;

  TissueMaterial retina;  // defaults are the retina's
  SolverSettings solver;
  Environment environment;
};

struct RetinaCapScene {
  TissueWorld world;
  std::uint32_t retina = 0;
  std::uint32_t membrane = kNone;
  std::uint32_t detachment_force = kNone;
  std::uint32_t anchored_vertices = 0;
  std::uint32_t attachments = 0;
};

// Builds the world: a spherical globe wall, the retina (and membrane). Throws InvalidArgument on
// out-of-range options.
RetinaCapScene build_retina_cap(const RetinaCapOptions& options);

}  // namespace vitreo::core
