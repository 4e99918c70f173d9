#include "core/topology/clean_topology.hpp"

#include <array>
#include <memory>

namespace vitreo::core {

CleanTopology::CleanTopology(Surface& surface, QualitySettings quality, double min_tear_rest_mm)
    : surface_(surface), quality_(surface, quality), min_tear_rest_mm_(min_tear_rest_mm) {}

TopologyHookResult CleanTopology::tear(EdgeId spring) {
  const Surface::TearResult t = surface_.tear_edge(spring);
  if (!t.status) {
    TopologyHookResult r;
    r.status = t.status;
    return r;
  }
  // Every triangle the tear made has one of the two fracture vertices as a corner.
  const std::array<std::uint32_t, 2> seeds{t.vertex_a_side, t.vertex_b_side};
  return clean_around(seeds);
}

TopologyHookResult CleanTopology::clean_around(std::span<const std::uint32_t> vertices) {
  const QualityResult q = quality_.clean_around(vertices);
  TopologyHookResult r;
  r.removed_mass_g = q.removed_mass_g;
  return r;
}

void install_clean_topology(TissueWorld& world, const QualitySettings& quality) {
  for (std::uint32_t s = 0; s < world.surface_count(); ++s) {
    world.set_topology_hook(s, std::make_unique<CleanTopology>(world.surface(s), quality));
  }
}

}  // namespace vitreo::core
