#pragma once
// The topology hook (core/tissue/topology_hook.hpp) the scenes install on every surface, so that
// the solver's own tears and plastic creep leave a mesh as clean as the tools' operations do
// (issue 3 items 4 and 5):
//  - a tear is Surface::tear_edge — the most strained spring (the solver tears the most strained
//    first, so the one where the forceps pull) split at its middle, the crack through to the
//    opposite vertices — then MeshQuality's cleanup around the two fracture vertices (every
//    triangle the tear made has one of them as a corner);
//  - where creep has shrunk a spring below the quality floor, the same cleanup around its ends.
// Both at the step boundary, allocation-free (the MeshQuality scratch is sized once here).
//
// Why not tear_spring's short crack with tips inside the triangles (tear.hpp, what the tools and
// propagate_tears use)? Under the solver's sustained pulls its tips leave one-triangle flaps and
// near-collinear slivers that are above the quality floor yet flip between two configurations
// every substep: a torn traction membrane (scenes/traction_perpendicular.toml) never came to rest
// (10 mm/s after 1.2 s against 0.2 mm/s with the through crack). The through crack leaves whole
// triangles behind it.
#include <cstdint>
#include <span>

#include "core/tissue/tissue_world.hpp"
#include "core/tissue/topology_hook.hpp"
#include "core/topology/quality.hpp"

namespace vitreo::core {

class CleanTopology final : public TopologyHook {
 public:
  // Springs shorter than min_tear_rest_mm are not torn (each tear halves the spring: 10 µm keeps
  // its halves well above the 2 µm floor). Throws InvalidArgument on invalid quality settings.
  explicit CleanTopology(Surface& surface, QualitySettings quality = {}, double min_tear_rest_mm = 0.01);

  TopologyHookResult tear(EdgeId spring) override;
  double min_tear_rest_mm() const override { return min_tear_rest_mm_; }
  double min_rest_mm() const override { return quality_.settings().min_spring_mm; }
  TopologyHookResult clean_around(std::span<const std::uint32_t> vertices) override;

 private:
  Surface& surface_;
  MeshQuality quality_;
  double min_tear_rest_mm_;
};

// Installs a CleanTopology on every surface of the world (replacing any hook it had).
void install_clean_topology(TissueWorld& world, const QualitySettings& quality = {});

}  // namespace vitreo::core
