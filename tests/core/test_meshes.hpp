#pragma once
// Small meshes for core tests.
#include "core/geometry/triangle_mesh.hpp"

namespace vitreo::core::test {

// A flat rectangle in the xy plane from (0,0) to (width, height), cols × rows cells, each cell split
// into two triangles (alternating diagonals), normals +z. Vertex (i, j) has index j * (cols + 1) + i.
TriangleMesh rectangle(double width_mm, double height_mm, int cols, int rows);

// A flat sheet in the xy plane of (near) equilateral triangles of side edge_mm: rows of vertices
// √3/2 edge apart, every other row shifted by half an edge, covering [0, width] × [0, height] (the
// shifted rows start at edge/2). Normals +z. Isotropic, like the retina's revolved mesh.
TriangleMesh equilateral_sheet(double width_mm, double height_mm, double edge_mm);

}  // namespace vitreo::core::test
