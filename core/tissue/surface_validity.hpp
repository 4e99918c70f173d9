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

}  // namespace vitreo::core
