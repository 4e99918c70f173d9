#pragma once
// Checks that a surface is a valid simulation mesh. Used by tests after every topology change and
// available to the rig for diagnostics (it walks everything: not for the hot path).
#include <string>
#include <vector>

#include "core/tissue/surface.hpp"

namespace vitreo::core {

struct ValidityReport {
  std::vector<std::string> problems;  // empty when valid
  bool ok() const { return problems.empty(); }
  std::string summary() const;
};

// Verifies: live triangles reference live vertices and live edges joining exactly their corners;
// every edge has at most two triangles, and two triangles sharing an edge traverse it in opposite
// directions (consistent orientation); each vertex's triangles form a single fan (manifold, no
// bow-ties); every live vertex's lumped mass equals density × adjacent rest area / 3 (+ extra);
// rest areas are positive; positions and velocities are finite.
ValidityReport check_surface(const Surface& surface);

// Quality limits for meshes after topology changes (cuts, tears, removal): what the cleanup in
// core/topology/quality.hpp guarantees (QualitySettings: min_spring, min_angle, min_area).
struct ValidityLimits {
  double min_rest_area_mm2 = 0.0;
  double min_rest_angle_deg = 0.0;  // measured on the springs' rest vectors
  double min_spring_rest_mm = 0.0;  // triangle springs
};
// check_surface plus: springs that are neither line springs nor edges of a triangle, triangles
// and springs below the limits.
ValidityReport check_surface(const Surface& surface, const ValidityLimits& limits);

}  // namespace vitreo::core
