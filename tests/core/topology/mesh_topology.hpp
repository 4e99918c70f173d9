#pragma once
// Independent references for the cut tests (written for the tests, not from the code under test):
//  - corner_topology: components, boundary loops and Euler characteristic of a surface computed
//    from its triangles' corner lists alone (no springs, no edge–triangle links, no fans: none of
//    the surface's own bookkeeping), so a cut that only looks open in that bookkeeping counts as
//    closed here;
//  - RasterCut: the same numbers for a planar sheet cut along a polyline, from a raster of the
//    sheet with the path drawn in as a thin wall (flood fills), independent of any mesh.
#include <cstdint>
#include <string>
#include <vector>

#include "core/common/types.hpp"
#include "core/tissue/surface.hpp"

namespace vitreo::core::test {

struct CornerTopology {
  std::uint32_t vertices = 0, edges = 0, triangles = 0;
  std::uint32_t components = 0;      // triangles joined through shared edges (vertex pairs)
  std::uint32_t boundary_loops = 0;  // cycles of edges used by one triangle
  std::int64_t euler = 0;            // V − E + F
  // Problems that make the numbers meaningless: an edge used by more than two triangles, two
  // triangles using an edge in the same direction, a boundary vertex with more than one outgoing
  // boundary edge (a bow-tie), a degenerate triangle.
  std::vector<std::string> problems;
  bool ok() const { return problems.empty(); }
  std::string describe() const;
};
CornerTopology corner_topology(const Surface& s);

// A w × h sheet (origin at 0) cut along `path` (a polyline in the xy plane, or several: one per
// entry), drawn into a raster of `pixel_mm` pixels as a wall `wall_mm` thick. Regions are the
// 4-connected pieces of sheet left; pieces smaller than `min_region_mm2` are counted apart
// (tiny_regions) so a caller can reject paths that would make pieces the mesh cannot hold. The
// boundary loops of a planar region are the 8-connected pieces of its complement (the rest of
// the plane), so loops = Σ over regions of those.
struct RasterCut {
  std::uint32_t components = 0;
  std::uint32_t boundary_loops = 0;
  std::uint32_t tiny_regions = 0;
  double smallest_region_mm2 = 0.0;
};
RasterCut raster_cut(double w, double h, const std::vector<std::vector<Vec3>>& paths, double pixel_mm, double wall_mm,
                     double min_region_mm2);

}  // namespace vitreo::core::test
