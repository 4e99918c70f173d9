#pragma once
// Tearing that starts where the tissue is pulled (thesis ch. 2.6.2.3, issue 3 item 4).
//
// tear_spring splits an overstrained spring at the strained spot (parameter `at`, the middle by
// default) and opens a short crack across it: in each adjacent triangle the crack runs from the
// split point toward the opposite vertex for `crack_fraction` of the way and ends there, inside the
// triangle (a crack tip), instead of cutting through to the far vertex. The springs at the crack
// tip then carry the load, so the next tear starts there: propagate_tears tears the most strained
// spring, re-measures, and repeats — the crack grows from where the forceps pull. Where a
// triangle is too small to hold a tip (its spoke shorter than twice min_spring_length_mm), the
// crack runs through to its opposite vertex on that side instead: a tear always opens.
//
// Built on Surface::split_edge / disconnect_edge / separate_vertex_fans: rest vectors by vector
// addition, mass exact, check_surface() passes after every tear. The solver's own end-of-step
// tears use it too, through the topology hook (clean_topology.hpp); Surface::tear_edge is the
// solver's fallback for surfaces without a hook.
#include <cstdint>

#include "core/common/status.hpp"
#include "core/tissue/surface.hpp"
#include "core/topology/quality.hpp"

namespace vitreo::core {

struct TearSettings {
  double at = 0.5;              // split parameter along the spring, in [0.1, 0.9]
  double crack_fraction = 0.5;  // how far the crack runs toward each opposite vertex, in [0.1, 0.9]
  // Springs shorter than this (rest length) are not split: each tear halves the springs at its
  // crack tip, and without a floor a pull held at one spot would split them without end into
  // ever smaller, stiffer pieces (the thesis had to switch those off). tear_spring refuses them;
  // propagate_tears passes on to the most strained spring that is long enough.
  double min_spring_length_mm = 0.01;
};

struct SpringTearResult {
  Status status = Status::ok();
  std::uint32_t vertices_added = 0;
  std::uint32_t collapsed = 0;   // slivers removed by the cleanup (with a MeshQuality)
  std::uint32_t unresolved = 0;
  double removed_mass_g = 0.0;  // lone sliver fragments the cleanup removed (exact)
};

// With a MeshQuality, the slivers the tear made are collapsed afterwards (quality.hpp).
SpringTearResult tear_spring(Surface& surface, EdgeId spring, const TearSettings& settings = {},
                             MeshQuality* quality = nullptr);

// Tears, one at a time, the most strained triangle spring whose strain exceeds `strain_threshold`,
// up to max_tears. Returns how many were torn. O(springs) per tear; meant for the step boundary.
std::uint32_t propagate_tears(Surface& surface, double strain_threshold, std::uint32_t max_tears,
                              const TearSettings& settings = {}, MeshQuality* quality = nullptr);

}  // namespace vitreo::core
