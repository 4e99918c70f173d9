#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "core/common/types.hpp"

namespace vitreo::core {

// A plain indexed triangle mesh: the neutral form in which generators hand geometry to the tissue
// model, the anatomy and the renderer. Triangles are counter-clockwise seen from their normal side.
struct TriangleMesh {
  std::vector<Vec3> positions;
  std::vector<std::array<std::uint32_t, 3>> triangles;
  // Optional per-vertex surface coordinates (e.g. arc length along a profile and azimuth), used to
  // place anatomy (ora serrata, optic disc) and texture coordinates. Empty when not provided.
  std::vector<Vec2> surface_coords;

  std::size_t vertex_count() const { return positions.size(); }
  std::size_t triangle_count() const { return triangles.size(); }
};

// Total area of the mesh, mm².
double mesh_area(const TriangleMesh& mesh);

}  // namespace vitreo::core
