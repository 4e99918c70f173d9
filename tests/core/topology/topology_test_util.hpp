#pragma once
// Helpers for the topology tests: sheets, components, new boundary edges, distances to a path.
#include <cstdint>
#include <vector>

#include "core/tissue/surface.hpp"
#include "core/tissue/surface_validity.hpp"
#include "core/topology/quality.hpp"

namespace vitreo::core::test {

// A width × height sheet in z = 0 (cols × rows cells), interior vertices jittered in-plane by up to
// `jitter` of a cell when jitter > 0 (seeded), with room for many topology changes.
SurfaceDescription sheet(double width_mm, double height_mm, int cols, int rows, double jitter = 0.0, unsigned seed = 1);

// The sheet most topology tests cut, tear and suck: 4 × 3 mm in 16 × 12 cells of 0.25 mm.
constexpr double kSheetW = 4.0, kSheetH = 3.0;
constexpr int kSheetCols = 16, kSheetRows = 12;
constexpr double kSheetCell = kSheetW / kSheetCols;

// Number of connected pieces (triangles joined through shared springs).
std::uint32_t components(const Surface& s);

// Boundary springs (one triangle) that do not lie on the sheet's outer rectangle.
struct Segment {
  Vec3 a, b;
};
std::vector<Segment> new_boundary(const Surface& s, double width_mm, double height_mm);

double distance_point_polyline(const Vec3& p, const std::vector<Vec3>& path);
double distance_point_segments(const Vec3& p, const std::vector<Segment>& segs);

// Every rest vector equals the difference of its vertices' rest positions (no plasticity).
double max_rest_vector_error(const Surface& s);

bool long_tests();

// What the cleanup after every operation guarantees (core/topology/quality.hpp), as limits for
// check_surface.
ValidityLimits quality_limits(const QualitySettings& q = {});

}  // namespace vitreo::core::test
