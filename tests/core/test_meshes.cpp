#include "test_meshes.hpp"

#include <cstdint>
#include <vector>

namespace vitreo::core::test {

TriangleMesh rectangle(double width_mm, double height_mm, int cols, int rows) {
  TriangleMesh m;
  for (int j = 0; j <= rows; ++j) {
    for (int i = 0; i <= cols; ++i) m.positions.emplace_back(width_mm * i / cols, height_mm * j / rows, 0.0);
  }
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(j * (cols + 1) + i); };
  for (int j = 0; j < rows; ++j) {
    for (int i = 0; i < cols; ++i) {
      if ((i + j) % 2 == 0) {
        m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
        m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
      } else {
        m.triangles.push_back({id(i, j), id(i + 1, j), id(i, j + 1)});
        m.triangles.push_back({id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
      }
    }
  }
  return m;
}

TriangleMesh equilateral_sheet(double width_mm, double height_mm, double edge_mm) {
  TriangleMesh m;
  const int cols = static_cast<int>(width_mm / edge_mm + 1e-9);
  const int rows = static_cast<int>(height_mm / (edge_mm * 0.8660254037844386) + 1e-9);
  // Row j has cols + 1 vertices; odd rows are shifted right by half an edge and have cols.
  std::vector<std::uint32_t> first;
  for (int j = 0; j <= rows; ++j) {
    first.push_back(static_cast<std::uint32_t>(m.positions.size()));
    const double shift = (j % 2) * 0.5 * edge_mm;
    const int n = j % 2 ? cols : cols + 1;
    for (int i = 0; i < n; ++i) m.positions.emplace_back(shift + i * edge_mm, j * edge_mm * 0.8660254037844386, 0.0);
  }
  for (int j = 0; j < rows; ++j) {
    const std::uint32_t a = first[static_cast<std::size_t>(j)], b = first[static_cast<std::size_t>(j) + 1];
    if (j % 2 == 0) {  // this row has cols + 1, the next (shifted) cols
      for (int i = 0; i < cols; ++i) {
        const auto u = static_cast<std::uint32_t>(i);
        m.triangles.push_back({a + u, a + u + 1, b + u});
        if (i + 1 < cols) m.triangles.push_back({a + u + 1, b + u + 1, b + u});
      }
    } else {  // this (shifted) row has cols, the next cols + 1
      for (int i = 0; i < cols; ++i) {
        const auto u = static_cast<std::uint32_t>(i);
        m.triangles.push_back({a + u, b + u + 1, b + u});
        if (i + 1 < cols) m.triangles.push_back({a + u, a + u + 1, b + u + 1});
      }
    }
  }
  return m;
}

}  // namespace vitreo::core::test
