// Low-level topology primitives of Surface: split a spring, split a triangle, disconnect a spring,
// separate fans, remove a triangle. core/topology composes cuts, tears and vitrector removal from
// these; each keeps the invariants listed in core/README.md on its own.
#include <algorithm>
#include <cmath>

#include "core/tissue/surface.hpp"

namespace vitreo::core {

bool Surface::has_room(std::uint32_t vertices, std::uint32_t edges, std::uint32_t triangles) const {
  auto room = [](std::size_t slots, std::size_t cap, std::size_t free) { return cap - slots + free; };
  return room(vertex_slots(), x_.capacity(), free_vertices_.size()) >= vertices &&
         room(edge_slots(), edge_v_.capacity(), free_edges_.size()) >= edges &&
         room(triangle_slots(), tri_v_.capacity(), free_triangles_.size()) >= triangles;
}

void Surface::refresh_around(std::uint32_t v) {
  update_vertex_mass(v);
  wake_vertex(v);
  for_each_triangle_of(v, [&](std::uint32_t t, std::uint32_t) {
    for (std::uint32_t k = 0; k < 3; ++k) {
      update_edge_stiffness(tri_e_[t][k]);
      update_vertex_mass(tri_v_[t][k]);
      wake_vertex(tri_v_[t][k]);
    }
  });
}

void Surface::free_vertex(std::uint32_t v) {
  ++topology_version_;
  wake_vertex(v);
  vertex_alive_[v] = 0;
  ++vertex_generation_[v];
  x_[v] = v_[v] = rest_[v] = Vec3::Zero();
  mass_[v] = inverse_mass_[v] = extra_mass_[v] = vertex_area_[v] = 0.0;
  fixed_[v] = 0;
  first_corner_[v] = kNone;
  free_vertices_.push_back(v);
  --live_vertices_;
}

Surface::SplitResult Surface::split_edge(EdgeId id, double t) {
  SplitResult r;
  if (!is_current(id)) {
    r.status = Status::error("split_edge: stale or invalid edge handle");
    return r;
  }
  if (!(t > 0.0 && t < 1.0)) {
    r.status = Status::error("split_edge: parameter must lie strictly between 0 and 1");
    return r;
  }
  const std::uint32_t e = id.index;
  if (edge_is_line_[e]) {
    r.status = Status::error("split_edge: line springs have no triangles to split");
    return r;
  }
  if (!has_room(1, 4, 2)) {
    r.status = Status::error("split_edge: pools full (raise the surface capacity)");
    return r;
  }
  const auto [a, b] = edge_v_[e];
  const Vec3 r_ab = base_rest_vec_[e];
  const double traction = edge_traction_[e];
  const auto tris = edge_t_[e];

  struct Side {
    std::uint32_t o = kNone, e_ao = kNone, e_bo = kNone;
    Vec3 r_a_o = Vec3::Zero();
    double area = 0.0, traction = 1.0;
    bool a_first = false;
  };
  std::array<Side, 2> sides{};
  int n = 0;
  for (auto tri : tris) {
    if (tri == kNone) continue;
    Side& s = sides[static_cast<std::size_t>(n++)];
    const auto tv = tri_v_[tri];
    for (std::uint32_t k = 0; k < 3; ++k) {
      if (tv[k] != a && tv[k] != b) s.o = tv[k];
      if (tv[k] == a && tv[(k + 1) % 3] == b) s.a_first = true;
    }
    for (auto te : tri_e_[tri]) {
      const auto ev = edge_v_[te];
      const bool has_o = ev[0] == s.o || ev[1] == s.o;
      if (has_o && (ev[0] == a || ev[1] == a)) s.e_ao = te;
      if (has_o && (ev[0] == b || ev[1] == b)) s.e_bo = te;
    }
    s.r_a_o = oriented_rest(s.e_ao, a);
    s.area = tri_rest_area_[tri];
    s.traction = 0.5 * (edge_traction_[s.e_ao] + edge_traction_[s.e_bo]);
  }
  // Refuse a split that would make a degenerate spring (a sliver whose opposite vertex rests on
  // the split point): nothing has changed yet.
  if (t * r_ab.norm() < kMinNewSpringRest_mm || (1.0 - t) * r_ab.norm() < kMinNewSpringRest_mm) {
    r.status = Status::error("split_edge: a piece would be shorter than the minimum spring rest length");
    return r;
  }
  for (int i = 0; i < n; ++i) {
    const Side& sd = sides[static_cast<std::size_t>(i)];
    if ((sd.r_a_o - t * r_ab).norm() < kMinNewSpringRest_mm) {
      r.status = Status::error("split_edge: the split point rests on an opposite vertex (degenerate spring)");
      return r;
    }
  }
  for (auto tri : tris) {
    if (tri != kNone) free_triangle(tri);
  }
  free_edge(e);

  const std::uint32_t m = allocate_vertex();
  x_[m] = (1.0 - t) * x_[a] + t * x_[b];
  v_[m] = (1.0 - t) * v_[a] + t * v_[b];
  rest_[m] = (1.0 - t) * rest_[a] + t * rest_[b];
  fixed_[m] = fixed_[a] && fixed_[b];

  const std::uint32_t e_am = add_edge(a, m, t * r_ab, traction);
  const std::uint32_t e_mb = add_edge(m, b, (1.0 - t) * r_ab, traction);
  auto make_triangle = [&](std::array<std::uint32_t, 3> v, std::array<std::uint32_t, 3> edges, double area) {
    const std::uint32_t tri = add_triangle(v, area);
    tri_e_[tri] = edges;
    for (auto e2 : edges) attach_triangle_to_edge(e2, tri);
  };
  for (int i = 0; i < n; ++i) {
    const Side& s = sides[static_cast<std::size_t>(i)];
    const std::uint32_t e_mo = add_edge(m, s.o, s.r_a_o - t * r_ab, s.traction);
    if (s.a_first) {  // (a, b, o) → (a, m, o) + (m, b, o)
      make_triangle({a, m, s.o}, {e_am, e_mo, s.e_ao}, t * s.area);
      make_triangle({m, b, s.o}, {e_mb, s.e_bo, e_mo}, (1.0 - t) * s.area);
    } else {  // (b, a, o) → (b, m, o) + (m, a, o)
      make_triangle({b, m, s.o}, {e_mb, e_mo, s.e_bo}, (1.0 - t) * s.area);
      make_triangle({m, a, s.o}, {e_am, s.e_ao, e_mo}, t * s.area);
    }
  }
  refresh_around(m);
  update_vertex_mass(a);  // a boundary spring with no triangle leaves a and b out of m's fan
  update_vertex_mass(b);
  r.vertex = m;
  return r;
}

Surface::SplitResult Surface::split_triangle(TriangleId id, const std::array<double, 3>& w) {
  SplitResult r;
  if (!(id.index < triangle_slots() && tri_alive_[id.index] && tri_generation_[id.index] == id.generation)) {
    r.status = Status::error("split_triangle: stale or invalid triangle handle");
    return r;
  }
  if (!(w[0] > 0.0 && w[1] > 0.0 && w[2] > 0.0) || std::abs(w[0] + w[1] + w[2] - 1.0) > 1e-9) {
    r.status = Status::error("split_triangle: barycentric coordinates must be positive and sum to 1");
    return r;
  }
  if (!has_room(1, 3, 2)) {
    r.status = Status::error("split_triangle: pools full (raise the surface capacity)");
    return r;
  }
  const std::uint32_t t = id.index;
  const auto [a, b, c] = tri_v_[t];
  const auto [e_ab, e_bc, e_ca] = tri_e_[t];
  const double area = tri_rest_area_[t];
  const Vec3 r_ab = oriented_rest(e_ab, a);
  const Vec3 r_ac = -oriented_rest(e_ca, c);
  const Vec3 r_ap = w[1] * r_ab + w[2] * r_ac;
  const double traction = (edge_traction_[e_ab] + edge_traction_[e_bc] + edge_traction_[e_ca]) / 3.0;
  if (r_ap.norm() < kMinNewSpringRest_mm || (r_ap - r_ab).norm() < kMinNewSpringRest_mm ||
      (r_ap - r_ac).norm() < kMinNewSpringRest_mm) {
    r.status = Status::error("split_triangle: the point rests on a corner (degenerate spring)");
    return r;
  }
  free_triangle(t);

  const std::uint32_t p = allocate_vertex();
  x_[p] = w[0] * x_[a] + w[1] * x_[b] + w[2] * x_[c];
  v_[p] = w[0] * v_[a] + w[1] * v_[b] + w[2] * v_[c];
  rest_[p] = w[0] * rest_[a] + w[1] * rest_[b] + w[2] * rest_[c];
  fixed_[p] = fixed_[a] && fixed_[b] && fixed_[c];
  const std::uint32_t e_ap = add_edge(a, p, r_ap, traction);
  const std::uint32_t e_bp = add_edge(b, p, r_ap - r_ab, traction);
  const std::uint32_t e_cp = add_edge(c, p, r_ap - r_ac, traction);
  auto make_triangle = [&](std::array<std::uint32_t, 3> v, std::array<std::uint32_t, 3> edges, double ar) {
    const std::uint32_t tri = add_triangle(v, ar);
    tri_e_[tri] = edges;
    for (auto e2 : edges) attach_triangle_to_edge(e2, tri);
  };
  make_triangle({a, b, p}, {e_ab, e_bp, e_ap}, w[2] * area);
  make_triangle({b, c, p}, {e_bc, e_cp, e_bp}, w[0] * area);
  make_triangle({c, a, p}, {e_ca, e_ap, e_cp}, w[1] * area);
  refresh_around(p);
  r.vertex = p;
  return r;
}

Surface::DisconnectResult Surface::disconnect_edge(EdgeId id) {
  DisconnectResult r;
  if (!is_current(id)) {
    r.status = Status::error("disconnect_edge: stale or invalid edge handle");
    return r;
  }
  const std::uint32_t e = id.index;
  if (edge_is_line_[e] || edge_t_[e][1] == kNone) {
    r.status = Status::error("disconnect_edge: only a spring shared by two triangles can be disconnected");
    return r;
  }
  if (!has_room(0, 1, 0)) {
    r.status = Status::error("disconnect_edge: spring pool full (raise the surface capacity)");
    return r;
  }
  const std::uint32_t t1 = edge_t_[e][1];
  const auto ev = edge_v_[e];
  const std::uint32_t copy = add_edge(ev[0], ev[1], base_rest_vec_[e], edge_traction_[e]);
  detach_triangle_from_edge(e, t1);
  for (auto& te : tri_e_[t1]) {
    if (te == e) te = copy;
  }
  attach_triangle_to_edge(copy, t1);
  update_edge_stiffness(e);
  update_edge_stiffness(copy);
  wake_vertex(ev[0]);
  wake_vertex(ev[1]);
  r.copy = copy;
  return r;
}

std::uint32_t Surface::separate_vertex_fans(VertexId id) {
  if (!is_current(id)) return 0;
  return separate_fans(id.index);
}

Surface::RemoveResult Surface::remove_triangle(TriangleId id, bool separate) {
  RemoveResult r;
  if (!(id.index < triangle_slots() && tri_alive_[id.index] && tri_generation_[id.index] == id.generation)) {
    r.status = Status::error("remove_triangle: stale or invalid triangle handle");
    return r;
  }
  const std::uint32_t t = id.index;
  // Separating fans afterwards may need up to one copy per corner.
  if (!has_room(3, 0, 0)) {
    r.status = Status::error("remove_triangle: vertex pool full (raise the surface capacity)");
    return r;
  }
  const auto tv = tri_v_[t];
  const auto te = tri_e_[t];
  r.removed_area_mm2 = tri_rest_area_[t];
  // Vertex mass is density × area / 3 + extra mass, so the removed mass is exactly the triangle's
  // density × area plus the extra mass of vertices that go with it.
  r.removed_mass_g = material_.areal_density_g_per_mm2() * r.removed_area_mm2;
  free_triangle(t);
  ++topology_version_;
  for (auto e : te) {
    if (edge_t_[e][0] == kNone && !edge_is_line_[e]) {
      free_edge(e);
    } else {
      update_edge_stiffness(e);
    }
  }
  for (auto v : tv) {
    wake_vertex(v);
    if (first_corner_[v] != kNone) {
      update_vertex_mass(v);
      continue;
    }
    // No triangle left: the vertex goes, with any line springs that still hang on it.
    if (line_springs_ > 0) {
      for (std::uint32_t e = 0; e < edge_slots(); ++e) {
        if (edge_alive_[e] && edge_is_line_[e] && (edge_v_[e][0] == v || edge_v_[e][1] == v)) {
          free_edge(e);
          --line_springs_;
        }
      }
    }
    r.removed_mass_g += extra_mass_[v];
    free_vertex(v);
    ++r.vertices_removed;
  }
  if (separate) {
    for (auto v : tv) {
      if (vertex_alive_[v]) separate_fans(v);
    }
  }
  return r;
}

}  // namespace vitreo::core
