#pragma once
// Small meshes for core tests.
#include "core/geometry/triangle_mesh.hpp"

namespace vitreo::core::test {

// A flat rectangle in the xy plane from (0,0) to (width, height), cols × rows cells, each cell split
// into two triangles (alternating diagonals), normals +z. Vertex (i, j) has index j * (cols + 1) + i.
TriangleMesh rectangle(double width_mm, double height_mm, int cols, int rows);

}  // namespace vitreo::core::test
