#pragma once
// What the solver hands to the topology layer at the step boundary: tearing a spring it found
// overstrained, and tidying up where plastic creep has shrunk springs below the mesh-quality floor.
//
// The solver (TissueWorld) detects both; how the mesh is changed belongs to core/topology, which
// is built on Surface and must not be included from here (it would make core/tissue depend on the
// layer built on it). So a surface may carry a TopologyHook, installed by whoever builds the world
// (core/topology/clean_topology.hpp: install_clean_topology, used by the scene and retina builders).
// Without one the solver falls back to Surface::tear_edge and does no tidying — the foundation's
// behaviour, kept for the solver's own tests.
#include <cstdint>
#include <span>

#include "core/common/status.hpp"
#include "core/tissue/handles.hpp"

namespace vitreo::core {

struct TopologyHookResult {
  Status status = Status::ok();
  double removed_mass_g = 0.0;  // lone sliver fragments removed as material (exact)
};

class TopologyHook {
 public:
  virtual ~TopologyHook() = default;
  // Tears `spring` (a live triangle spring of the hook's surface) where it is strained, leaving a
  // valid mesh. A failed status changes nothing (the solver tries again next step).
  virtual TopologyHookResult tear(EdgeId spring) = 0;
  // Springs shorter than this (rest length) are never torn: the solver skips them.
  virtual double min_tear_rest_mm() const = 0;
  // The quality floor on rest length: the solver reports the ends of springs that creep below it.
  virtual double min_rest_mm() const = 0;
  // Restores the quality floor around these vertices (dead ones are skipped).
  virtual TopologyHookResult clean_around(std::span<const std::uint32_t> vertices) = 0;
};

}  // namespace vitreo::core
