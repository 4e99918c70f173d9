#include "core/topology/tear.hpp"

#include <array>
#include <cmath>

namespace vitreo::core {

SpringTearResult tear_spring(Surface& s, EdgeId id, const TearSettings& settings, MeshQuality* quality) {
  SpringTearResult r;
  if (!s.is_current(id)) {
    r.status = Status::error("tear_spring: stale or invalid spring handle");
    return r;
  }
  if (!(settings.at >= 0.1 && settings.at <= 0.9) || !(settings.crack_fraction >= 0.1 && settings.crack_fraction <= 0.9)) {
    r.status = Status::error("tear_spring: at and crack_fraction must lie in [0.1, 0.9]");
    return r;
  }
  if (s.edge_rest_length(id.index) < 2.0 * settings.min_spring_length_mm) {
    r.status = Status::error("tear_spring: spring shorter than twice min_spring_length_mm");
    return r;
  }
  if (s.edge_is_line(id.index)) {
    r.status = Status::error("tear_spring: line springs have no surface to tear");
    return r;
  }
  // Split (1 vertex), two crack springs split (2), copies of the split vertex (up to 2).
  if (!s.has_room(6, 16, 8)) {
    r.status = Status::error("tear_spring: pools full (raise the surface capacity)");
    return r;
  }
  // Every triangle the tear makes has one of these: the spring's ends, the split point, a tip.
  std::array<std::uint32_t, 5> touched{s.edge_vertices(id.index)[0], s.edge_vertices(id.index)[1], kNone, kNone, kNone};
  const auto split = s.split_edge(id, settings.at);
  if (!split.status) {
    r.status = split.status;
    return r;
  }
  const std::uint32_t m = split.vertex;
  touched[2] = m;
  ++r.vertices_added;
  // The springs from m to the opposite vertices are the new ones that are neither half of the
  // torn spring; a half ends at a former end of the spring, which lies on the spring's line.
  std::array<EdgeId, 2> crack{};
  int ncrack = 0;
  std::array<std::uint32_t, 2> ends{kNone, kNone};
  // The two halves of the torn spring: collinear with it in the rest state. Find them as the pair
  // of springs at m whose rest vectors are opposite.
  std::array<std::uint32_t, 8> spokes{};
  std::uint32_t nspokes = 0;
  s.for_each_triangle_of(m, [&](std::uint32_t t, std::uint32_t) {
    for (auto e : s.triangle_edges(t)) {
      const auto ev = s.edge_vertices(e);
      if (ev[0] != m && ev[1] != m) continue;
      bool known = false;
      for (std::uint32_t i = 0; i < nspokes; ++i) known = known || spokes[i] == e;
      if (!known && nspokes < spokes.size()) spokes[nspokes++] = e;
    }
  });
  for (std::uint32_t i = 0; i < nspokes && ends[0] == kNone; ++i) {
    for (std::uint32_t j = i + 1; j < nspokes; ++j) {
      const Vec3 ri = s.edge_rest_vector(spokes[i]) * (s.edge_vertices(spokes[i])[0] == m ? 1.0 : -1.0);
      const Vec3 rj = s.edge_rest_vector(spokes[j]) * (s.edge_vertices(spokes[j])[0] == m ? 1.0 : -1.0);
      if (ri.normalized().dot(rj.normalized()) < -1.0 + 1e-9) {
        ends = {spokes[i], spokes[j]};
        break;
      }
    }
  }
  for (std::uint32_t i = 0; i < nspokes; ++i) {
    if (spokes[i] == ends[0] || spokes[i] == ends[1]) continue;
    if (ncrack < 2) crack[static_cast<std::size_t>(ncrack++)] = s.edge_id(spokes[i]);
  }
  // Run the crack part of the way toward each opposite vertex: split the spoke there. A spoke too
  // short to hold a tip (a small triangle's) is opened whole: the crack reaches the opposite vertex
  // on that side. Either way the tear opens, so a spring torn once is never torn "again" in place.
  std::array<EdgeId, 2> open{};
  std::array<std::uint32_t, 2> reached{kNone, kNone};  // opposite vertices the crack runs into
  int nopen = 0;
  for (int i = 0; i < ncrack; ++i) {
    const EdgeId c = crack[static_cast<std::size_t>(i)];
    const auto ev = s.edge_vertices(c.index);
    const std::uint32_t opposite = ev[0] == m ? ev[1] : ev[0];
    bool tipped = false;
    if (s.edge_rest_length(c.index) >= 2.0 * settings.min_spring_length_mm) {
      const double t = ev[0] == m ? settings.crack_fraction : 1.0 - settings.crack_fraction;
      const auto tip = s.split_edge(c, t);
      if (tip.status) {
        tipped = true;
        ++r.vertices_added;
        touched[static_cast<std::size_t>(3 + i)] = tip.vertex;
        const std::uint32_t e = s.find_edge(m, tip.vertex);
        if (e != kNone) open[static_cast<std::size_t>(nopen++)] = s.edge_id(e);
      }
    }
    if (!tipped) {
      open[static_cast<std::size_t>(nopen++)] = c;
      reached[static_cast<std::size_t>(i)] = opposite;
      touched[static_cast<std::size_t>(3 + i)] = opposite;
    }
  }
  for (int i = 0; i < nopen; ++i) {
    const EdgeId e = open[static_cast<std::size_t>(i)];
    if (s.is_current(e) && s.edge_triangles(e.index)[1] != kNone) (void)s.disconnect_edge(e);
  }
  if (quality == nullptr) {
    r.vertices_added += s.separate_vertex_fans(s.vertex_id(m));
    for (auto o : reached) {
      if (o != kNone) r.vertices_added += s.separate_vertex_fans(s.vertex_id(o));  // a bow-tie at a boundary
    }
  } else {
    auto& seeds = quality->seeds();
    seeds.clear();
    for (auto v : touched) {
      if (v != kNone) seeds.push_back(v);
    }
    r.vertices_added += s.separate_vertex_fans(s.vertex_id(m), &seeds);  // m's copies too
    for (auto o : reached) {
      if (o != kNone) r.vertices_added += s.separate_vertex_fans(s.vertex_id(o), &seeds);
    }
    const QualityResult q = quality->clean_around(seeds);
    r.collapsed = q.collapses;
    r.unresolved = q.unresolved;
    r.removed_mass_g = q.removed_mass_g;
  }
  return r;
}

std::uint32_t propagate_tears(Surface& s, double threshold, std::uint32_t max_tears, const TearSettings& settings,
                              MeshQuality* quality) {
  std::uint32_t torn = 0;
  while (torn < max_tears) {
    std::uint32_t best = kNone;
    double best_strain = threshold;
    for (std::uint32_t e = 0; e < s.edge_slots(); ++e) {
      if (!s.edge_alive(e) || s.edge_is_line(e) || s.edge_rest_length(e) < 2.0 * settings.min_spring_length_mm) continue;
      const double strain = s.edge_strain(e);
      if (strain > best_strain) {
        best_strain = strain;
        best = e;
      }
    }
    if (best == kNone) break;
    if (!tear_spring(s, s.edge_id(best), settings, quality).status) break;
    ++torn;
  }
  return torn;
}

}  // namespace vitreo::core
