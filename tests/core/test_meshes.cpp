#include "test_meshes.hpp"

#include <cstdint>

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

}  // namespace vitreo::core::test
