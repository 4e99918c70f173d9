#include "topology_test_util.hpp"

#include <cmath>
#include <cstdlib>
#include <numeric>
#include <random>

#include "core/topology/geometry.hpp"
#include "../test_meshes.hpp"

namespace vitreo::core::test {

SurfaceDescription sheet(double w, double h, int cols, int rows, double jitter, unsigned seed) {
  SurfaceDescription d;
  d.mesh = rectangle(w, h, cols, rows);
  d.contained_by_globe = false;
  d.capacity.growth_fraction = 10.0;
  d.capacity.minimum_extra = 4096;
  if (jitter > 0.0) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-jitter, jitter);
    for (auto& p : d.mesh.positions) {
      if (p.x() > 0.0 && p.x() < w && p.y() > 0.0 && p.y() < h) {
        p.x() += u(rng) * w / cols;
        p.y() += u(rng) * h / rows;
      }
    }
  }
  return d;
}

std::uint32_t components(const Surface& s) {
  std::vector<std::uint32_t> parent(s.triangle_slots());
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (std::uint32_t e = 0; e < s.edge_slots(); ++e) {
    if (!s.edge_alive(e)) continue;
    const auto et = s.edge_triangles(e);
    if (et[0] != kNone && et[1] != kNone) parent[find(et[0])] = find(et[1]);
  }
  std::uint32_t n = 0;
  for (std::uint32_t t = 0; t < s.triangle_slots(); ++t) {
    if (s.triangle_alive(t) && find(t) == t) ++n;
  }
  return n;
}

std::vector<Segment> new_boundary(const Surface& s, double w, double h) {
  std::vector<Segment> out;
  auto on_rim = [&](const Vec3& p) {
    return std::abs(p.x()) < 1e-9 || std::abs(p.y()) < 1e-9 || std::abs(p.x() - w) < 1e-9 || std::abs(p.y() - h) < 1e-9;
  };
  for (std::uint32_t e = 0; e < s.edge_slots(); ++e) {
    if (!s.edge_alive(e) || s.edge_triangles(e)[1] != kNone) continue;
    const auto [a, b] = s.edge_vertices(e);
    const Vec3 pa = s.rest_position(a), pb = s.rest_position(b);
    const Vec3 mid = 0.5 * (pa + pb);
    if (on_rim(pa) && on_rim(pb) && on_rim(mid)) continue;
    out.push_back({pa, pb});
  }
  return out;
}

double distance_point_polyline(const Vec3& p, const std::vector<Vec3>& path) {
  double d = INFINITY;
  for (std::size_t i = 0; i + 1 < path.size(); ++i) d = std::min(d, topology::distance_to_segment(p, path[i], path[i + 1]));
  return d;
}

double distance_point_segments(const Vec3& p, const std::vector<Segment>& segs) {
  double d = INFINITY;
  for (const auto& s : segs) d = std::min(d, topology::distance_to_segment(p, s.a, s.b));
  return d;
}

double max_rest_vector_error(const Surface& s) {
  double err = 0.0;
  for (std::uint32_t e = 0; e < s.edge_slots(); ++e) {
    if (!s.edge_alive(e)) continue;
    const auto [a, b] = s.edge_vertices(e);
    err = std::max(err, (s.edge_rest_vector(e) - (s.rest_position(b) - s.rest_position(a))).norm());
  }
  return err;
}

bool long_tests() {
  const char* v = std::getenv("VITREO_LONG_TESTS");
  return v != nullptr && v[0] != '\0' && v[0] != '0';
}

ValidityLimits quality_limits(const QualitySettings& q) {
  ValidityLimits l;
  l.min_spring_rest_mm = q.min_spring_mm;
  l.min_rest_angle_deg = q.min_angle_deg;
  l.min_rest_area_mm2 = q.min_area_mm2();
  return l;
}

}  // namespace vitreo::core::test
