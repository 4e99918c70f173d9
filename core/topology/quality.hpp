#pragma once
// Mesh cleanup after a cut, a removal or a tear (issue 3 item 5): no triangle below a minimum rest
// angle, no spring below a minimum rest length — hence no triangle below
// min_area = ½ · min_spring² · sin(min_angle).
//
// The cut, removal and tear code already refuses to make pieces smaller than its snap tolerance,
// but existing geometry can still force slivers (a vertex lying very close to the cut line, a tear
// crack ending next to a vertex, repeated cuts at one spot). Left alone they pile up: the long
// stability run reached springs of 1 nm. MeshQuality removes them, at the step boundary, right
// after the operation that made them, by edge collapse (Surface::collapse_edge).
//
// Rules (documented in core/topology/README.md):
//  - A triangle is poor when one of its springs is shorter than min_spring_mm or one of its
//    angles (measured on the springs' rest vectors: the shape the solver restores) is below
//    min_angle_deg.
//  - A poor triangle's springs are tried shortest first. Of a spring's two ends the one kept is
//    the more constrained: fixed or carrying extra mass (an anchor, a bead) before a boundary
//    vertex (the cut edge keeps its shape) before an interior one; on a tie the lower slot (so the
//    result does not depend on visiting order). A collapse that would flip a triangle, break
//    manifoldness (link condition), pinch the surface, create an angle below the limit or move a
//    spring below min_spring_mm is refused and the next spring is tried.
//  - Everything not removed keeps its handle; the removed vertex's handle goes stale (like
//    removed material: an attachment on it breaks). Rest area and mass are exact (see
//    Surface::collapse_edge): the removed triangles' rest area goes to their neighbours.
//  - A cap (apex almost on its longest spring, every spring above min_spring_mm) none of whose
//    springs can be collapsed is flipped (split the longest spring at the apex's foot, collapse the
//    foot into the apex) when both new triangles are above the limit. A needle (a short spring) is
//    not: flipping only moves the short spring on.
//  - Last resort: the sliver is merged into the neighbour across its longest spring
//    (Surface::dissolve_triangle: its rest area moves there, mass exact; the surface opens along
//    it); a lone one-triangle fragment is removed as material, its mass reported in
//    QualityResult::removed_mass_g.
//  - A poor triangle nothing can fix is counted in `unresolved` and left as is (simulated; XPBD
//    keeps it stable), as is one still poor when max_passes run out. The property tests assert
//    the floor after every one of their operations.
//
// No allocation after construction; visits only the triangles around the vertices it is given.
#include <cstdint>
#include <span>
#include <vector>

#include "core/tissue/surface.hpp"

namespace vitreo::core {

struct QualitySettings {
  double min_spring_mm = 0.002;  // 2 µm
  double min_angle_deg = 1.0;
  std::uint32_t max_passes = 8;
  double min_area_mm2() const;
  void validate() const;  // throws InvalidArgument
};

struct QualityResult {
  std::uint32_t collapses = 0;
  std::uint32_t dissolved = 0;   // slivers merged into a neighbour (Surface::dissolve_triangle)
  std::uint32_t fragments_removed = 0;  // lone sliver triangles (pieces of one triangle) removed
  double removed_mass_g = 0.0;   // their mass: total_mass() drops by exactly this much
  std::uint32_t unresolved = 0;  // poor triangles met that no collapse could fix (at most)
};

// True when triangle t is below the limits.
bool is_poor_triangle(const Surface& s, std::uint32_t t, const QualitySettings& q);

class MeshQuality {
 public:
  explicit MeshQuality(Surface& surface, QualitySettings settings = {});
  // Checks the triangles around the given vertices (dead ones are skipped) and collapses poor
  // ones, re-checking around every vertex a collapse keeps, until none is left or max_passes.
  QualityResult clean_around(std::span<const std::uint32_t> vertices);
  // The whole surface (O(size), allocates: for tests and for loading a scene, not the step path).
  QualityResult clean_all();
  const QualitySettings& settings() const { return settings_; }
  // A list with room for every vertex, for callers to collect the vertices to pass to
  // clean_around without allocating (e.g. with Surface::separate_vertex_fans' copies).
  std::vector<std::uint32_t>& seeds() { return seeds_; }
  // Mass of the fragments removed by every call so far (g).
  double total_removed_mass_g() const { return total_removed_mass_g_; }

 private:
  bool try_fix(std::uint32_t t);
  Surface& surface_;
  QualitySettings settings_;
  double min_angle_sin2_ = 0.0;  // sin² of settings_.min_angle_deg (0: no angle limit)
  std::vector<std::uint32_t> work_, next_, tri_stamp_, seeds_;
  std::uint32_t round_ = 0;
  std::uint64_t budget_ = 0;  // cap splits (flips) this clean_around may still make
  double total_removed_mass_g_ = 0.0;
  QualityResult result_;
};

}  // namespace vitreo::core
