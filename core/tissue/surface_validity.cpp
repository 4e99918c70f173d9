#include "core/tissue/surface_validity.hpp"

#include <cmath>
#include <sstream>

#include "core/common/validate.hpp"

namespace vitreo::core {

std::string ValidityReport::summary() const {
  std::ostringstream out;
  out << problems.size() << " problem(s)";
  for (std::size_t i = 0; i < problems.size() && i < 10; ++i) out << "\n  " << problems[i];
  return out.str();
}

ValidityReport check_surface(const Surface& s) {
  ValidityReport r;
  auto fail = [&](const std::string& what) {
    if (r.problems.size() < 100) r.problems.push_back(what);
  };

  for (std::uint32_t t = 0; t < s.triangle_slots(); ++t) {
    if (!s.triangle_alive(t)) continue;
    const auto v = s.triangle_vertices(t);
    const auto e = s.triangle_edges(t);
    if (!(s.triangle_rest_area(t) > 0.0)) fail("triangle " + std::to_string(t) + " has non-positive rest area");
    for (std::uint32_t k = 0; k < 3; ++k) {
      if (!s.vertex_alive(v[k])) fail("triangle " + std::to_string(t) + " uses a dead vertex");
      if (!s.edge_alive(e[k])) {
        fail("triangle " + std::to_string(t) + " uses a dead edge");
        continue;
      }
      const auto ev = s.edge_vertices(e[k]);
      const std::uint32_t a = v[k], b = v[(k + 1) % 3];
      if (!((ev[0] == a && ev[1] == b) || (ev[0] == b && ev[1] == a))) {
        fail("triangle " + std::to_string(t) + " edge " + std::to_string(k) + " does not join its corners");
      }
      const auto et = s.edge_triangles(e[k]);
      if (et[0] != t && et[1] != t) fail("edge " + std::to_string(e[k]) + " does not list triangle " + std::to_string(t));
    }
  }

  for (std::uint32_t e = 0; e < s.edge_slots(); ++e) {
    if (!s.edge_alive(e)) continue;
    const auto ev = s.edge_vertices(e);
    if (!s.vertex_alive(ev[0]) || !s.vertex_alive(ev[1])) fail("edge " + std::to_string(e) + " uses a dead vertex");
    if (!(s.edge_rest_length(e) > 0.0)) fail("edge " + std::to_string(e) + " has zero rest length");
    const auto et = s.edge_triangles(e);
    if (et[0] != kNone && et[1] != kNone) {
      // Opposite traversal directions ⇔ consistent orientation.
      auto forward = [&](std::uint32_t t) {
        const auto v = s.triangle_vertices(t);
        for (std::uint32_t k = 0; k < 3; ++k) {
          if (v[k] == ev[0] && v[(k + 1) % 3] == ev[1]) return true;
        }
        return false;
      };
      if (forward(et[0]) == forward(et[1])) fail("edge " + std::to_string(e) + ": adjacent triangles disagree in orientation");
    }
  }

  const double rho_a = s.material().areal_density_g_per_mm2();
  for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) {
    if (!s.vertex_alive(v)) continue;
    if (!is_finite(s.position(v)) || !is_finite(s.velocity(v))) fail("vertex " + std::to_string(v) + " is not finite");
    double area = 0.0;
    std::uint32_t tris = 0;
    s.for_each_triangle_of(v, [&](std::uint32_t t, std::uint32_t) {
      area += s.triangle_rest_area(t) / 3.0;
      ++tris;
    });
    const double expected = rho_a * area + s.extra_mass(v);
    if (std::abs(s.mass(v) - expected) > 1e-9 * expected) {
      fail("vertex " + std::to_string(v) + " mass " + std::to_string(s.mass(v)) + " differs from its area share " +
           std::to_string(expected));
    }
    // Single fan: walking triangles around v across edges through v must reach them all.
    if (tris >= 2) {
      std::uint32_t reached = 1, start = kNone;
      s.for_each_triangle_of(v, [&](std::uint32_t t, std::uint32_t) {
        if (start == kNone) start = t;
      });
      // Breadth-first over the fan, bounded by its size.
      std::uint32_t frontier[64];
      std::uint32_t seen[64];
      std::uint32_t nseen = 0, nfront = 0;
      if (tris > 64) continue;
      seen[nseen++] = start;
      frontier[nfront++] = start;
      while (nfront > 0) {
        const std::uint32_t t = frontier[--nfront];
        for (auto e : s.triangle_edges(t)) {
          const auto ev = s.edge_vertices(e);
          if (ev[0] != v && ev[1] != v) continue;
          for (auto u : s.edge_triangles(e)) {
            if (u == kNone) continue;
            bool known = false;
            for (std::uint32_t i = 0; i < nseen; ++i) known = known || seen[i] == u;
            if (!known && nseen < 64) {
              seen[nseen++] = u;
              frontier[nfront++] = u;
              ++reached;
            }
          }
        }
      }
      if (reached != tris) fail("vertex " + std::to_string(v) + " joins " + std::to_string(tris) + " triangles in more than one fan");
    }
  }
  return r;
}

ValidityReport check_surface(const Surface& s, const ValidityLimits& limits) {
  ValidityReport r = check_surface(s);
  auto fail = [&](const std::string& what) {
    if (r.problems.size() < 100) r.problems.push_back(what);
  };
  for (std::uint32_t e = 0; e < s.edge_slots(); ++e) {
    if (s.edge_alive(e) && !s.edge_is_line(e) && s.edge_triangles(e)[0] == kNone) {
      fail("spring " + std::to_string(e) + " belongs to no triangle");
    }
  }
  for (std::uint32_t e = 0; e < s.edge_slots(); ++e) {
    if (s.edge_alive(e) && !s.edge_is_line(e) && !(s.edge_rest_length(e) >= limits.min_spring_rest_mm)) {
      fail("spring " + std::to_string(e) + " rest length " + std::to_string(s.edge_rest_length(e)) + " mm below the limit");
    }
  }
  const double min_angle = limits.min_rest_angle_deg * 3.14159265358979323846 / 180.0;
  for (std::uint32_t t = 0; t < s.triangle_slots(); ++t) {
    if (!s.triangle_alive(t)) continue;
    if (s.triangle_rest_area(t) < limits.min_rest_area_mm2) {
      fail("triangle " + std::to_string(t) + " rest area " + std::to_string(s.triangle_rest_area(t)) + " below the limit");
    }
    if (limits.min_rest_angle_deg <= 0.0) continue;
    const double angle = s.triangle_min_rest_angle(t);
    if (!(angle >= min_angle)) {
      fail("triangle " + std::to_string(t) + " rest angle " + std::to_string(angle * 180.0 / 3.14159265358979323846) +
           "° below the limit");
    }
  }
  return r;
}

}  // namespace vitreo::core
