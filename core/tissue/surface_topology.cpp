// Low-level topology primitives of Surface: split a spring, split a triangle, disconnect a spring,
// separate fans, remove a triangle. core/topology composes cuts, tears and vitrector removal from
// these; each keeps the invariants listed in core/README.md on its own.
#include <algorithm>
#include <array>
#include <cmath>

#include "core/tissue/surface.hpp"

namespace vitreo::core {

bool Surface::has_room(std::uint32_t vertices, std::uint32_t edges, std::uint32_t triangles) const {
  auto room = [](std::size_t slots, std::size_t cap, std::size_t free) { return cap - slots + free; };
  return room(vertex_slots(), x_.capacity(), free_vertices_.size()) >= vertices &&
         room(edge_slots(), edge_v_.capacity(), free_edges_.size()) >= edges &&
         room(triangle_slots(), tri_v_.capacity(), free_triangles_.size()) >= triangles;
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
    std::uint32_t tri = kNone, o = kNone, e_ao = kNone, e_bo = kNone;
    Vec3 r_a_o = Vec3::Zero();
    double area = 0.0, traction = 1.0;
    bool a_first = false;
  };
  std::array<Side, 2> sides{};
  int n = 0;
  for (auto tri : tris) {
    if (tri == kNone) continue;
    Side& s = sides[static_cast<std::size_t>(n++)];
    s.tri = tri;
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
  const EditBatch edit(*this);
  ++topology_version_;
  const std::uint32_t m = allocate_vertex();
  x_[m] = (1.0 - t) * x_[a] + t * x_[b];
  v_[m] = (1.0 - t) * v_[a] + t * v_[b];
  rest_[m] = (1.0 - t) * rest_[a] + t * rest_[b];
  fixed_[m] = fixed_[a] && fixed_[b];

  // In place, as if the spring and its triangles were removed and four triangles added, without
  // unlinking and relinking what stays: the spring's slot becomes a–m and each triangle's slot
  // keeps a and o, with m in b's corner. Their generations move on, so handles to the spring
  // a–b and to the triangles a–b–o go stale as they would have.
  ++edge_generation_[e];
  edge_v_[e] = {a, m};
  base_rest_vec_[e] = t * r_ab;
  refresh_rest(e);
  log_spring(e);
  note_edge(e);
  wake_vertex(a);
  wake_vertex(b);
  const std::uint32_t e_mb = add_edge(m, b, (1.0 - t) * r_ab, traction);
  for (int i = 0; i < n; ++i) {
    const Side& s = sides[static_cast<std::size_t>(i)];
    const std::uint32_t tri = s.tri;
    const std::uint32_t e_mo = add_edge(m, s.o, s.r_a_o - t * r_ab, s.traction);
    for (std::uint32_t k = 0; k < 3; ++k) {
      if (tri_v_[tri][k] == b) {
        unlink_corner(tri, k);
        tri_v_[tri][k] = m;
        link_corner(tri, k);
      }
      if (tri_e_[tri][k] == s.e_bo) tri_e_[tri][k] = e_mo;
    }
    detach_triangle_from_edge(s.e_bo, tri);
    attach_triangle_to_edge(e_mo, tri);
    tri_rest_area_[tri] = t * s.area;
    ++tri_generation_[tri];
    note_triangle_area(tri);
    // The other part, (m, b, o) in the triangle's orientation.
    const std::uint32_t part = s.a_first ? add_triangle({m, b, s.o}, (1.0 - t) * s.area)
                                         : add_triangle({b, m, s.o}, (1.0 - t) * s.area);
    tri_e_[part] = s.a_first ? std::array<std::uint32_t, 3>{e_mb, s.e_bo, e_mo}
                             : std::array<std::uint32_t, 3>{e_mb, e_mo, s.e_bo};
    for (auto e2 : tri_e_[part]) attach_triangle_to_edge(e2, part);
  }
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
  const EditBatch edit(*this);
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
  const EditBatch edit(*this);
  const std::uint32_t t1 = edge_t_[e][1];
  const auto ev = edge_v_[e];
  const std::uint32_t copy = add_edge(ev[0], ev[1], base_rest_vec_[e], edge_traction_[e]);
  detach_triangle_from_edge(e, t1);
  for (auto& te : tri_e_[t1]) {
    if (te == e) te = copy;
  }
  attach_triangle_to_edge(copy, t1);
  wake_vertex(ev[0]);
  wake_vertex(ev[1]);
  r.copy = copy;
  return r;
}

std::uint32_t Surface::separate_vertex_fans(VertexId id, std::vector<std::uint32_t>* copies) {
  if (!is_current(id)) return 0;
  const EditBatch edit(*this);
  return separate_fans(id.index, copies);
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
  const EditBatch edit(*this);
  free_triangle(t);
  ++topology_version_;
  for (auto e : te) {
    if (edge_t_[e][0] == kNone && !edge_is_line_[e]) free_edge(e);
  }
  for (auto v : tv) {
    wake_vertex(v);
    if (first_corner_[v] != kNone) continue;
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


namespace {
// Smallest corner angle of a triangle given its three edge vectors d0 = v0→v1, d1 = v1→v2, d2 = v2→v0.
double min_angle(const Vec3& d0, const Vec3& d1, const Vec3& d2) {
  return std::min({angle_between(d0, -d2), angle_between(d1, -d0), angle_between(d2, -d1)});
}
}  // namespace

Status Surface::dissolve_triangle(TriangleId id, TriangleId into) {
  auto current = [&](TriangleId h) {
    return h.index < triangle_slots() && tri_alive_[h.index] && tri_generation_[h.index] == h.generation;
  };
  if (!current(id) || !current(into) || id.index == into.index) {
    return Status::error("dissolve_triangle: stale or invalid triangle handle");
  }
  const std::uint32_t t = id.index, u = into.index;
  bool adjacent = false;
  for (auto e : tri_e_[t]) adjacent = adjacent || edge_t_[e][0] == u || edge_t_[e][1] == u;
  if (!adjacent) return Status::error("dissolve_triangle: the triangles share no spring");
  for (auto v : tri_v_[t]) {
    std::uint32_t n = 0;
    for_each_triangle_of(v, [&](std::uint32_t, std::uint32_t) { ++n; });
    // A corner with no other triangle goes with t; its area share moves with t's area, so only
    // extra mass or an anchor would be lost.
    if (n < 2 && (extra_mass_[v] != 0.0 || fixed_[v])) {
      return Status::error("dissolve_triangle: a corner with extra mass or fixed has no other triangle");
    }
  }
  if (!has_room(3, 0, 0)) return Status::error("dissolve_triangle: vertex pool full (raise the surface capacity)");
  const EditBatch edit(*this);
  tri_rest_area_[u] += tri_rest_area_[t];
  note_triangle_area(u);
  const auto removed = remove_triangle(id, true);
  if (!removed.status) {  // cannot happen after the checks above; undo the transfer regardless
    tri_rest_area_[u] -= tri_rest_area_[t];
    return removed.status;
  }
  return Status::ok();
}

double Surface::triangle_min_rest_angle(std::uint32_t t) const {
  const auto tv = tri_v_[t];
  const auto te = tri_e_[t];
  std::array<Vec3, 3> d;
  for (std::uint32_t k = 0; k < 3; ++k) d[k] = edge_v_[te[k]][0] == tv[k] ? rest_vec_[te[k]] : Vec3(-rest_vec_[te[k]]);
  return min_angle(d[0], d[1], d[2]);
}

bool Surface::is_boundary_vertex(std::uint32_t v) const {
  bool boundary = false;
  for_each_triangle_of(v, [&](std::uint32_t t, std::uint32_t) {
    for (auto e : tri_e_[t]) {
      if ((edge_v_[e][0] == v || edge_v_[e][1] == v) && edge_t_[e][1] == kNone) boundary = true;
    }
  });
  return boundary;
}

Surface::CollapseResult Surface::collapse_edge(EdgeId id, std::uint32_t k, double min_result_angle, bool allow_pinch,
                                               double min_result_spring_mm) {
  CollapseResult res;
  auto refuse = [&](const char* why) {
    res.status = Status::error(why);
    return res;
  };
  if (!is_current(id)) return refuse("collapse_edge: stale or invalid edge handle");
  const std::uint32_t e = id.index;
  const auto ev = edge_v_[e];
  if (k != ev[0] && k != ev[1]) return refuse("collapse_edge: keep is not an end of the spring");
  if (edge_is_line_[e] || edge_t_[e][0] == kNone) return refuse("collapse_edge: only a triangle spring can be collapsed");
  const std::uint32_t r = k == ev[0] ? ev[1] : ev[0];
  if (fixed_[r] && !fixed_[k]) return refuse("collapse_edge: the removed vertex is fixed and the kept one is not");
  const bool k_boundary = is_boundary_vertex(k), r_boundary = is_boundary_vertex(r);
  if (r_boundary && !k_boundary) return refuse("collapse_edge: the removed vertex is on the boundary and the kept one is not");
  const bool pinch = edge_t_[e][1] != kNone && k_boundary && r_boundary;
  if (pinch && !allow_pinch) return refuse("collapse_edge: an interior spring between two boundary vertices (the surface would pinch)");
  if (pinch && !has_room(2, 0, 0)) return refuse("collapse_edge: vertex pool full (raise the surface capacity)");
  // The triangles on e, with their opposite vertex and the springs to it.
  struct Wing {
    std::uint32_t t = kNone, o = kNone, e_ko = kNone, e_ro = kNone, receiver = kNone;
  };
  std::array<Wing, 2> wings{};
  std::uint32_t nwings = 0;
  for (auto t : edge_t_[e]) {
    if (t == kNone) continue;
    Wing w;
    w.t = t;
    for (auto v : tri_v_[t]) {
      if (v != k && v != r) w.o = v;
    }
    for (auto te : tri_e_[t]) {
      const auto tv = edge_v_[te];
      if (te == e) continue;
      if (tv[0] == k || tv[1] == k) w.e_ko = te;
      if (tv[0] == r || tv[1] == r) w.e_ro = te;
    }
    if (w.o == kNone || w.e_ko == kNone || w.e_ro == kNone) return refuse("collapse_edge: degenerate triangle on the spring");
    nwings++;
    wings[nwings - 1] = w;
  }
  auto other_triangle = [&](std::uint32_t edge, std::uint32_t t) {
    const auto et = edge_t_[edge];
    return et[0] == t ? et[1] : et[0];
  };
  for (std::uint32_t i = 0; i < nwings; ++i) {
    Wing& w = wings[i];
    const std::uint32_t across_r = other_triangle(w.e_ro, w.t), across_k = other_triangle(w.e_ko, w.t);
    w.receiver = across_r != kNone ? across_r : across_k;
    if (w.receiver == kNone) return refuse("collapse_edge: the triangle has no neighbour to take its area");
    if (w.receiver == wings[0].t || w.receiver == wings[1].t) return refuse("collapse_edge: degenerate fan");
  }
  if (nwings == 2 && wings[0].o == wings[1].o) return refuse("collapse_edge: degenerate fan");
  // The removed vertex's triangles (other than the wings) and its neighbours.
  std::array<std::uint32_t, 64> fan{};
  std::uint32_t nfan = 0;
  bool overflow = false;
  for_each_triangle_of(r, [&](std::uint32_t t, std::uint32_t) {
    if (t == wings[0].t || t == wings[1].t) return;
    if (nfan < fan.size()) {
      fan[nfan++] = t;
    } else {
      overflow = true;
    }
  });
  if (overflow) return refuse("collapse_edge: vertex of too high valence");
  auto is_opposite = [&](std::uint32_t v) {
    for (std::uint32_t i = 0; i < nwings; ++i) {
      if (wings[i].o == v) return true;
    }
    return false;
  };
  // Link condition: a vertex adjacent to both ends must be an opposite vertex of e.
  for (std::uint32_t i = 0; i < nfan; ++i) {
    for (auto w : tri_v_[fan[i]]) {
      if (w == k) return refuse("collapse_edge: a triangle other than the spring's joins both ends");
      if (w == r || is_opposite(w)) continue;
      if (find_edge(k, w) != kNone) return refuse("collapse_edge: link condition fails (the result would not be manifold)");
    }
  }
  if (line_springs_ > 0) {
    for (std::uint32_t f = 0; f < edge_slots(); ++f) {
      if (!edge_alive_[f] || !edge_is_line_[f]) continue;
      const auto fv = edge_v_[f];
      if ((fv[0] == r && fv[1] == k) || (fv[0] == k && fv[1] == r)) return refuse("collapse_edge: a line spring joins both ends");
    }
  }
  const Vec3 r_kr = oriented_rest(e, k);  // base rest vector from k to r
  // Post-collapse rest vector (traction-scaled, as the solver sees it) of spring f from `from`.
  auto scaled = [&](std::uint32_t f, const Vec3& base) { return Vec3(base * (surface_traction_ * edge_traction_[f])); };
  auto merged_into = [&](std::uint32_t f) {
    for (std::uint32_t i = 0; i < nwings; ++i) {
      if (wings[i].e_ro == f) return wings[i].e_ko;
    }
    return kNone;
  };
  auto new_vector = [&](std::uint32_t f, std::uint32_t from) -> Vec3 {
    const std::uint32_t m = merged_into(f);
    if (m != kNone) {  // becomes keep's spring to the opposite vertex
      const Vec3 ko = scaled(m, oriented_rest(m, k));
      return from == r ? ko : Vec3(-ko);
    }
    const auto fv = edge_v_[f];
    if (fv[0] != r && fv[1] != r) return scaled(f, oriented_rest(f, from));
    const std::uint32_t w = fv[0] == r ? fv[1] : fv[0];
    const Vec3 kw = scaled(f, r_kr + oriented_rest(f, r));
    return from == w ? Vec3(-kw) : kw;
  };
  // No triangle of the fan may flip or degenerate, in the rest shape or the current one.
  for (std::uint32_t i = 0; i < nfan; ++i) {
    const std::uint32_t t = fan[i];
    const auto tv = tri_v_[t];
    const auto te = tri_e_[t];
    std::array<Vec3, 3> d_old, d_new;
    std::array<Vec3, 3> x_new;
    for (std::uint32_t c = 0; c < 3; ++c) {
      d_old[c] = edge_v_[te[c]][0] == tv[c] ? rest_vec_[te[c]] : Vec3(-rest_vec_[te[c]]);
      d_new[c] = new_vector(te[c], tv[c]);
      x_new[c] = tv[c] == r ? x_[k] : x_[tv[c]];
    }
    const Vec3 n_old = d_old[0].cross(-d_old[2]), n_new = d_new[0].cross(-d_new[2]);
    if (!(n_old.dot(n_new) > 0.0)) return refuse("collapse_edge: a triangle would flip in the rest shape");
    if (min_angle(d_new[0], d_new[1], d_new[2]) < min_result_angle) {
      return refuse("collapse_edge: a triangle would get a rest angle below the limit");
    }
    for (std::uint32_t c = 0; c < 3; ++c) {
      const auto fv = edge_v_[te[c]];
      const bool moved = (fv[0] == r || fv[1] == r) && merged_into(te[c]) == kNone;
      if (moved && d_new[c].norm() < min_result_spring_mm) {
        return refuse("collapse_edge: a spring moved to the kept vertex would be shorter than the limit");
      }
    }
    const Vec3 c_old = (x_[tv[1]] - x_[tv[0]]).cross(x_[tv[2]] - x_[tv[0]]);
    const Vec3 c_new = (x_new[1] - x_new[0]).cross(x_new[2] - x_new[0]);
    if (!(c_old.dot(c_new) > 0.0)) return refuse("collapse_edge: a triangle would flip in the current shape");
  }

  // ---- Apply (nothing below can fail) ----
  const EditBatch edit(*this);
  refresh_noted();  // the momentum below needs current masses, also inside a caller's batch
  ++topology_version_;
  const double m_k = mass_[k], m_r = mass_[r];
  if (m_k + m_r > 0.0) v_[k] = (m_k * v_[k] + m_r * v_[r]) / (m_k + m_r);
  extra_mass_[k] += extra_mass_[r];
  note_vertex(k);
  for (std::uint32_t i = 0; i < nwings; ++i) {
    const Wing& w = wings[i];
    tri_rest_area_[w.receiver] += tri_rest_area_[w.t];
    note_triangle_area(w.receiver);
    free_triangle(w.t);
    ++res.triangles_removed;
  }
  free_edge(e);
  for (std::uint32_t i = 0; i < nwings; ++i) {
    const Wing& w = wings[i];
    // The triangle still on e_ro (at most one) moves to e_ko.
    for (auto t : edge_t_[w.e_ro]) {
      if (t == kNone) continue;
      for (auto& te : tri_e_[t]) {
        if (te == w.e_ro) te = w.e_ko;
      }
      attach_triangle_to_edge(w.e_ko, t);
    }
    free_edge(w.e_ro);
  }
  // Re-home the rest of r's fan and its springs onto k.
  for (std::uint32_t i = 0; i < nfan; ++i) {
    const std::uint32_t t = fan[i];
    for (std::uint32_t c = 0; c < 3; ++c) {
      if (tri_v_[t][c] != r) continue;
      unlink_corner(t, c);
      tri_v_[t][c] = k;
      link_corner(t, c);
    }
    for (auto f : tri_e_[t]) {
      auto& fv = edge_v_[f];
      if (fv[0] == r) {
        fv[0] = k;
        log_spring(f);
        base_rest_vec_[f] = r_kr + base_rest_vec_[f];
        refresh_rest(f);
        note_edge(f);
      } else if (fv[1] == r) {
        fv[1] = k;
        log_spring(f);
        base_rest_vec_[f] = base_rest_vec_[f] - r_kr;
        refresh_rest(f);
        note_edge(f);
      }
    }
  }
  if (line_springs_ > 0) {
    for (std::uint32_t f = 0; f < edge_slots(); ++f) {
      if (!edge_alive_[f] || !edge_is_line_[f]) continue;
      auto& fv = edge_v_[f];
      if (fv[0] == r) {
        fv[0] = k;
        log_spring(f);
        base_rest_vec_[f] = r_kr + base_rest_vec_[f];
        refresh_rest(f);
        note_edge(f);
      } else if (fv[1] == r) {
        fv[1] = k;
        log_spring(f);
        base_rest_vec_[f] = base_rest_vec_[f] - r_kr;
        refresh_rest(f);
        note_edge(f);
      }
    }
  }
  first_corner_[r] = kNone;
  free_vertex(r);
  if (pinch) separate_fans(k);
  res.removed_vertex = r;
  return res;
}

}  // namespace vitreo::core
