#include "core/geometry/revolved_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "core/common/validate.hpp"

namespace vitreo::core {

double mesh_area(const TriangleMesh& mesh) {
  double area = 0.0;
  for (const auto& t : mesh.triangles) {
    const Vec3& a = mesh.positions[t[0]];
    area += 0.5 * (mesh.positions[t[1]] - a).cross(mesh.positions[t[2]] - a).norm();
  }
  return area;
}

namespace {

struct Ring {
  std::uint32_t first = 0;  // index of the first vertex of this ring
  std::uint32_t count = 0;  // 1 for a pole
  double phase_rad = 0.0;   // azimuth of the first vertex
};

// Point at arc length s along the polyline; `tangent` gets the unit (dz, drho) direction there.
ProfilePoint point_at(const std::vector<ProfilePoint>& p, const std::vector<double>& cumulative, double s) {
  const auto it = std::upper_bound(cumulative.begin(), cumulative.end(), s);
  std::size_t i = static_cast<std::size_t>(std::max<std::ptrdiff_t>(1, it - cumulative.begin())) - 1;
  i = std::min(i, p.size() - 2);
  const double len = cumulative[i + 1] - cumulative[i];
  const double t = len > 0.0 ? std::clamp((s - cumulative[i]) / len, 0.0, 1.0) : 0.0;
  return {p[i].z_mm + t * (p[i + 1].z_mm - p[i].z_mm), p[i].rho_mm + t * (p[i + 1].rho_mm - p[i].rho_mm)};
}

}  // namespace

TriangleMesh revolve_profile(const std::vector<ProfilePoint>& profile, const RevolveOptions& options) {
  if (profile.size() < 2) throw InvalidArgument("revolve_profile: profile needs at least two points");
  require_positive(options.target_edge_mm, "revolve_profile: target_edge_mm");
  require_range(options.sweep_rad, 1e-3, 2.0 * std::numbers::pi, "revolve_profile: sweep_rad");
  for (const auto& q : profile) {
    require_finite(q.z_mm, "revolve_profile: profile z");
    require_non_negative(q.rho_mm, "revolve_profile: profile rho");
  }
  const bool closed = options.sweep_rad > 2.0 * std::numbers::pi - 1e-9;
  const double h = options.target_edge_mm;

  std::vector<double> cumulative{0.0};
  for (std::size_t i = 1; i < profile.size(); ++i) {
    cumulative.push_back(cumulative.back() + std::hypot(profile[i].z_mm - profile[i - 1].z_mm,
                                                        profile[i].rho_mm - profile[i - 1].rho_mm));
  }
  const double total = cumulative.back();
  if (!(total > 0.0)) throw InvalidArgument("revolve_profile: profile has zero length");

  // Ring spacing: equilateral triangles between rings have height h·√3/2.
  const double ring_spacing = h * std::sqrt(3.0) / 2.0;
  const int ring_count = std::max(2, static_cast<int>(std::lround(total / ring_spacing)) + 1);

  TriangleMesh mesh;
  std::vector<Ring> rings;
  rings.reserve(static_cast<std::size_t>(ring_count));
  constexpr double kOnAxis = 1e-9;
  for (int r = 0; r < ring_count; ++r) {
    const double s = total * r / (ring_count - 1);
    const ProfilePoint q = point_at(profile, cumulative, s);
    Ring ring;
    ring.first = static_cast<std::uint32_t>(mesh.positions.size());
    if (q.rho_mm <= kOnAxis) {
      if (!closed) throw InvalidArgument("revolve_profile: a profile touching the axis needs a full sweep");
      ring.count = 1;
      mesh.positions.emplace_back(0.0, 0.0, q.z_mm);
      mesh.surface_coords.emplace_back(s, 0.0);
    } else {
      const double arc = q.rho_mm * options.sweep_rad;
      int n = std::max(3, static_cast<int>(std::lround(arc / h)));
      if (!closed) n += 1;  // an open sweep has vertices at both ends
      ring.count = static_cast<std::uint32_t>(n);
      // Staggering alternate rings by half a step gives equilateral rather than right triangles.
      ring.phase_rad = closed && (r % 2 == 1) ? 0.5 * options.sweep_rad / n : 0.0;
      const double step = closed ? options.sweep_rad / n : options.sweep_rad / (n - 1);
      for (int k = 0; k < n; ++k) {
        const double phi = ring.phase_rad + step * k;
        mesh.positions.emplace_back(q.rho_mm * std::cos(phi), q.rho_mm * std::sin(phi), q.z_mm);
        mesh.surface_coords.emplace_back(s, phi);
      }
    }
    rings.push_back(ring);
  }

  // Zip consecutive rings together. For a ring with n vertices around the axis, vertex k sits at
  // azimuth phase + step·k; we advance along whichever ring's next vertex comes first in azimuth.
  auto azimuth = [&](const Ring& ring, std::uint32_t k) {
    const double step = closed ? options.sweep_rad / ring.count : options.sweep_rad / (ring.count - 1);
    return ring.phase_rad + step * k;
  };
  for (std::size_t r = 0; r + 1 < rings.size(); ++r) {
    const Ring& a = rings[r];
    const Ring& b = rings[r + 1];
    if (a.count == 1 && b.count == 1) throw InvalidArgument("revolve_profile: two consecutive pole rings");
    // Orientation: seen from outside with ring a below ring b and azimuth increasing to the right,
    // (a_i, a_i+1, b_j) is counter-clockwise; emit(x, y, z) stores (x, z, y).
    auto emit = [&](std::uint32_t i0, std::uint32_t i1, std::uint32_t i2) { mesh.triangles.push_back({i0, i2, i1}); };
    if (a.count == 1 || b.count == 1) {
      const bool pole_first = a.count == 1;
      const Ring& ring = pole_first ? b : a;
      const std::uint32_t pole = pole_first ? a.first : b.first;
      for (std::uint32_t k = 0; k < ring.count; ++k) {
        const std::uint32_t k1 = (k + 1) % ring.count;
        if (pole_first) {
          emit(pole, ring.first + k, ring.first + k1);
        } else {
          emit(ring.first + k, pole, ring.first + k1);
        }
      }
      continue;
    }
    const std::uint32_t na = closed ? a.count : a.count - 1;  // number of segments on each ring
    const std::uint32_t nb = closed ? b.count : b.count - 1;
    std::uint32_t i = 0, j = 0;
    while (i < na || j < nb) {
      const std::uint32_t ia = a.first + (i % a.count), ia1 = a.first + ((i + 1) % a.count);
      const std::uint32_t jb = b.first + (j % b.count), jb1 = b.first + ((j + 1) % b.count);
      const bool advance_a =
          j >= nb || (i < na && azimuth(a, i + 1) + 0.0 <= azimuth(b, j + 1) + 1e-12);
      if (advance_a) {
        emit(ia, jb, ia1);
        ++i;
      } else {
        // b advances: (a_i, b_j+1, b_j) keeps the band counter-clockwise seen from outside.
        mesh.triangles.push_back({ia, jb1, jb});
        ++j;
      }
    }
  }
  return mesh;
}

std::vector<ProfilePoint> sphere_arc_profile(double radius_mm, double theta0_rad, double theta1_rad, int segments) {
  require_positive(radius_mm, "sphere_arc_profile: radius");
  if (segments < 1) throw InvalidArgument("sphere_arc_profile: segments must be >= 1");
  std::vector<ProfilePoint> p;
  for (int i = 0; i <= segments; ++i) {
    const double th = theta0_rad + (theta1_rad - theta0_rad) * i / segments;
    // Snap the poles exactly onto the axis.
    double rho = radius_mm * std::sin(th);
    if (std::abs(th) < 1e-12 || std::abs(th - std::numbers::pi) < 1e-12) rho = 0.0;
    p.push_back({-radius_mm * std::cos(th), std::max(0.0, rho)});
  }
  return p;
}

double edge_length_for_vertex_count(double radius_mm, double theta1_rad, int vertex_count) {
  require_positive(radius_mm, "edge_length_for_vertex_count: radius");
  if (vertex_count < 4) throw InvalidArgument("edge_length_for_vertex_count: need at least 4 vertices");
  // A triangulated surface of equilateral triangles with edge h has ~2/(√3 h²) vertices per unit area.
  const double area = 2.0 * std::numbers::pi * radius_mm * radius_mm * (1.0 - std::cos(theta1_rad));
  return std::sqrt(2.0 * area / (std::sqrt(3.0) * vertex_count));
}

}  // namespace vitreo::core
