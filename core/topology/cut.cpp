#include "core/topology/cut.hpp"

#include <algorithm>
#include <cmath>

#include "core/common/prefault.hpp"
#include "core/common/validate.hpp"
#include "core/topology/geometry.hpp"

namespace vitreo::core {

using topology::closest_point_on_triangle;
using topology::segment_triangle;

void CutSettings::validate() const {
  require_range(band_mm, 0.0, 1.0, "cut: band_mm");
  require_range(snap_fraction, 0.0, 0.25, "cut: snap_fraction");
  require_range(min_piece_mm, 0.0, 1.0, "cut: min_piece_mm");
  require_range(min_blade_length_mm, 1e-9, 10.0, "cut: min_blade_length_mm");
  require_range(min_swept_area_mm2, 0.0, 10.0, "cut: min_swept_area_mm2");
  quality.validate();
}

Cutter::Cutter(Surface& surface, CutSettings settings)
    : surface_(surface), settings_(settings), index_(surface), quality_(surface, settings.quality) {
  settings_.validate();
  const std::size_t nv = surface.vertex_capacity(), ne = surface.edge_capacity();
  const std::size_t nt = ne;  // triangle capacity is below the spring capacity
  vertex_.assign(nv, VertexScratch{});
  edge_stamp_.assign(ne, 0);
  triangle_stamp_.assign(nt, 0);
  // Scratch sized for the worst case and touched now, so no stroke allocates or takes a page fault.
  reserve_touched(candidates_, nv);
  reserve_touched(on_cut_, nv);
  reserve_touched(triangles_, nt);
  reserve_touched(edges_, ne);
  reserve_touched(crossings_, ne);
  reserve_touched(to_open_, ne);
  double longest = 0.0;
  for (std::uint32_t e = 0; e < surface.edge_slots(); ++e) {
    if (surface.edge_alive(e)) longest = std::max(longest, surface.edge_rest_length(e));
  }
  // How far from the swept quad a vertex can matter, for springs no longer than L (a spring may be
  // stretched up to its tear strain; L = twice the longest rest length covers every material's):
  //  - a spring crossing the quad at y has |a − y| + |y − b| = L, so one end lies within L/2;
  //  - a point inside a triangle lies within L/√3 of its nearest corner (the worst point is the
  //    centre of an equilateral triangle), so a triangle the quad's rim passes through, or a quad
  //    corner rests on, has a corner within L/√3 (+ the band) of the rim.
  // L/√3 + band covers both: vertices beyond it are never candidates (half the old 2L margin's
  // strip, hence half the vertices, triangles and springs each stroke visits).
  margin_mm_ = 2.0 * longest / std::sqrt(3.0) + settings_.band_mm;
}

bool Cutter::near_swept(const Vec3& p, double tolerance) const {
  for (int k = 0; k < 2; ++k) {
    if (!swept_valid_[static_cast<std::size_t>(k)]) continue;
    const auto& s = swept_[static_cast<std::size_t>(k)];
    // The distance to the plane bounds the distance to the triangle: a cheap rejection first.
    if (std::abs(swept_normal_[static_cast<std::size_t>(k)].dot(p - s[0])) > tolerance) continue;
    if ((p - closest_point_on_triangle(p, s[0], s[1], s[2])).squaredNorm() <= tolerance * tolerance) return true;
  }
  return false;
}

std::array<double, 2> Cutter::plane_distances(const Vec3& x) const {
  std::array<double, 2> d{};
  for (std::size_t k = 0; k < 2; ++k) d[k] = swept_valid_[k] ? swept_normal_[k].dot(x - swept_[k][0]) : 0.0;
  return d;
}

void Cutter::find_crossings(std::span<const std::uint32_t> springs) {
  const Surface& s = surface_;
  const double band2 = settings_.band_mm * settings_.band_mm + 1e-24;
  for (const std::uint32_t e : springs) {
    const auto [a, b] = s.edge_vertices(e);
    const std::array<double, 2> da = side(a), db = side(b);
    for (std::size_t k = 0; k < 2; ++k) {
      // A spring crosses plane k where its ends' signed distances differ in sign (a degenerate
      // triangle has distance 0 everywhere, so never); it crosses the swept surface if the
      // crossing lies on triangle k (within the band).
      if (!(da[k] * db[k] < 0.0)) continue;
      const Vec3 &xa = s.position(a), &xb = s.position(b);
      const double t = da[k] / (da[k] - db[k]);
      const Vec3 x = xa + t * (xb - xa);
      if ((x - closest_point_on_triangle(x, swept_[k][0], swept_[k][1], swept_[k][2])).squaredNorm() > band2) continue;
      if (crossings_.size() < crossings_.capacity()) crossings_.push_back({s.edge_id(e), t});
      break;
    }
  }
}

void Cutter::mark(std::uint32_t v) {
  if (vertex_[v].cut == stamp_) return;
  vertex_[v].cut = stamp_;
  on_cut_.push_back(v);
}

void Cutter::gather_candidates() {
  candidates_.clear();
  const Surface& s = surface_;
  const double band = settings_.band_mm;
  const auto wanted = [&](std::uint32_t v) {
    const Vec3& x = s.position(v);
    const std::array<double, 2> d = plane_distances(x);
    // near_swept(x, margin) and near_swept(x, band) at once, each exact distance at most once.
    bool candidate = false, on_surface = false;
    for (std::size_t k = 0; k < 2; ++k) {
      if (!swept_valid_[k]) continue;
      const double plane = std::abs(d[k]);
      if (plane > margin_mm_ || (candidate && (on_surface || plane > band))) continue;
      const double d2 = (x - closest_point_on_triangle(x, swept_[k][0], swept_[k][1], swept_[k][2])).squaredNorm();
      candidate = candidate || d2 <= margin_mm_ * margin_mm_;
      on_surface = on_surface || (plane <= band && d2 <= band * band);
    }
    if (!candidate) return;
    candidates_.push_back(v);
    vertex_[v].side_stamp = stamp_;  // for the crossing tests of the springs around it
    vertex_[v].side = d;
    if (on_surface) mark(v);  // the vertex and grazing cases
    std::uint8_t mask = 0;
    for (std::size_t k = 0; k < rim_.size(); ++k) {
      if (topology::distance_to_segment(x, rim_[k][0], rim_[k][1]) <= margin_mm_) mask |= static_cast<std::uint8_t>(1u << k);
      if ((x - corners_[k]).squaredNorm() <= margin_mm_ * margin_mm_) mask |= static_cast<std::uint8_t>(16u << k);
    }
    if (mask != 0) {
      vertex_[v].rim = stamp_;
      vertex_[v].rim_mask = mask;
    }
  };
  // A block can hold a candidate only if its box comes within the margin of the plane of one of
  // the swept triangles (a point near a triangle is near its plane): the box's extent along the
  // normal is its centre's distance ± the half-sizes projected on |n|.
  const auto block_near_quad = [&](const Vec3& lo, const Vec3& hi) {
    const Vec3 centre = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
    for (std::size_t k = 0; k < 2; ++k) {
      if (!swept_valid_[k]) continue;
      const Vec3& n = swept_normal_[k];
      const double reach = n.cwiseAbs().dot(half) + margin_mm_;
      if (std::abs(n.dot(centre - swept_[k][0])) <= reach) return true;
    }
    return false;
  };
  index_.for_each_in_box(box_lo_, box_hi_, wanted, block_near_quad);
}

// Triangles and springs around the candidate vertices (deduplicated, in a fixed order).
void Cutter::gather_edges() {
  ++edge_round_;
  triangles_.clear();
  edges_.clear();
  const Surface& s = surface_;
  for (auto v : candidates_) {
    if (!s.vertex_alive(v)) continue;
    s.for_each_triangle_of(v, [&](std::uint32_t t, std::uint32_t) {
      if (triangle_stamp_[t] == edge_round_) return;
      triangle_stamp_[t] = edge_round_;
      triangles_.push_back(t);
      for (auto e : s.triangle_edges(t)) {
        if (edge_stamp_[e] == edge_round_) continue;
        edge_stamp_[e] = edge_round_;
        edges_.push_back(e);
      }
    });
  }
}

CutResult Cutter::sweep(const BladeEdge& from, const BladeEdge& to) {
  CutResult r;
  Surface& s = surface_;
  if (!is_finite(from.a_mm) || !is_finite(from.b_mm) || !is_finite(to.a_mm) || !is_finite(to.b_mm)) {
    r.status = Status::error("cut: non-finite blade pose");
    return r;
  }
  if ((from.b_mm - from.a_mm).norm() < settings_.min_blade_length_mm ||
      (to.b_mm - to.a_mm).norm() < settings_.min_blade_length_mm) {
    r.status = Status::error("cut: degenerate blade (cutting edge shorter than min_blade_length_mm)");
    return r;
  }
  const Vec3 &p0 = from.a_mm, &q0 = from.b_mm, &p1 = to.a_mm, &q1 = to.b_mm;
  swept_[0] = {p0, q0, q1};
  swept_[1] = {p0, q1, p1};
  double area = 0.0;
  for (std::size_t k = 0; k < 2; ++k) {
    const Vec3 n = (swept_[k][1] - swept_[k][0]).cross(swept_[k][2] - swept_[k][0]);
    const double a = 0.5 * n.norm();
    area += a;
    swept_valid_[k] = a > 1e-14;
    swept_normal_[k] = swept_valid_[k] ? Vec3(n.normalized()) : Vec3::Zero();
  }
  if (!(area > settings_.min_swept_area_mm2) || (!swept_valid_[0] && !swept_valid_[1])) {
    r.status = Status::error("cut: degenerate sweep (the blade did not sweep any area)");
    return r;
  }
  const double band = settings_.band_mm;
  box_lo_ = p0.cwiseMin(q0).cwiseMin(p1).cwiseMin(q1).array() - margin_mm_;
  box_hi_ = p0.cwiseMax(q0).cwiseMax(p1).cwiseMax(q1).array() + margin_mm_;

  ++stamp_;
  on_cut_.clear();
  rim_ = {{{p0, q0}, {p1, q1}, {p0, p1}, {q0, q1}}};
  corners_ = {p0, q0, p1, q1};
  gather_candidates();  // also marks the vertices on the swept surface
  gather_edges();

  // Ends: the quad's boundary passing through the surface.
  const auto& boundary = rim_;
  Ends ends;
  auto add_end = [&](const Vec3& y, std::uint32_t t) {
    bool known = false;
    for (std::uint32_t i = 0; i < ends.count; ++i) known = known || (ends.at[i] - y).norm() <= std::max(band, 1e-9);
    if (!known && ends.count < ends.at.size()) {
      ends.triangle[ends.count] = s.triangle_id(t);
      ends.at[ends.count++] = y;
    }
  };
  auto rim_bits = [&](std::uint32_t v) { return vertex_[v].rim == stamp_ ? vertex_[v].rim_mask : std::uint8_t{0}; };
  // The swept triangle whose plane holds each rim segment (p0q0 and q0q1 lie in (p0, q0, q1),
  // p1q1 and p0p1 in (p0, q1, p1)).
  constexpr std::array<std::size_t, 4> kRimPlane{0, 1, 1, 0};
  for (auto t : triangles_) {
    const auto tv = s.triangle_vertices(t);
    // Only triangles near the quad's boundary can hold an end: a rim segment passing through a
    // triangle passes within the margin of one of its corners (see the constructor), and so
    // does a quad corner resting on it (bits 4–7).
    const std::uint8_t any = rim_bits(tv[0]) | rim_bits(tv[1]) | rim_bits(tv[2]);
    if (any == 0) continue;
    for (std::size_t k = 0; k < boundary.size(); ++k) {
      if (!(any & (1u << k))) continue;
      const auto& seg = boundary[k];
      if ((seg[1] - seg[0]).squaredNorm() < 1e-24) continue;
      // The segment lies in the plane of a swept triangle: a triangle wholly on one side of that
      // plane (beyond the band) cannot meet it.
      const std::size_t plane = kRimPlane[k];
      if (swept_valid_[plane]) {
        const double d0 = side(tv[0])[plane], d1 = side(tv[1])[plane], d2 = side(tv[2])[plane];
        if ((d0 > band && d1 > band && d2 > band) || (d0 < -band && d1 < -band && d2 < -band)) continue;
      }
      double sp;
      std::array<double, 3> bary;
      if (!segment_triangle(seg[0], seg[1], s.position(tv[0]), s.position(tv[1]), s.position(tv[2]), sp, bary)) continue;
      add_end(seg[0] + sp * (seg[1] - seg[0]), t);
    }
    // A corner of the quad resting on the triangle (within the band) ends the cut there too.
    for (std::size_t k = 0; k < 4; ++k) {
      if (!(any & (16u << k))) continue;
      const Vec3& c = corners_[k];
      const Vec3 y = closest_point_on_triangle(c, s.position(tv[0]), s.position(tv[1]), s.position(tv[2]));
      if ((y - c).norm() <= band) add_end(y, t);
    }
  }

  // Crossings of the springs found so far (inserting the ends below only adds springs around the
  // new end vertices; the others keep their crossings, as nothing moves).
  crossings_.clear();
  find_crossings(edges_);
  const auto ncross = static_cast<std::uint32_t>(crossings_.size());
  const std::uint32_t k = ends.count + ncross + static_cast<std::uint32_t>(on_cut_.size()) + 2;
  if (!s.has_room(3 * k, 6 * k, 3 * k)) {
    r.status = Status::error("cut: pools full (raise the surface capacity)");
    return r;
  }
  if (ends.count == 0 && ncross == 0 && on_cut_.empty()) return r;  // the blade missed the tissue
  insert_cut(r, ends);
  for (auto v : on_cut_) {
    if (s.vertex_alive(v)) s.wake_vertex(v);
  }
  // Every triangle the cut made or changed has a vertex on the cut (or a copy of one).
  const QualityResult q = quality_.clean_around(on_cut_);
  r.collapsed = q.collapses;
  r.unresolved = q.unresolved;
  r.removed_mass_g = q.removed_mass_g;
  return r;
}

// Steps 1–3 of the header: the ends, the crossings and the opening, as one batch of edits
// (Surface::EditBatch: the masses and stiffnesses around the cut are recomputed once, at its end).
void Cutter::insert_cut(CutResult& r, const Ends& ends) {
  Surface& s = surface_;
  const Surface::EditBatch batch(s);
  const double band = settings_.band_mm, snap = settings_.snap_fraction;
  // 1. Insert the ends.
  std::array<std::uint32_t, 32> created{};  // end vertices made by splitting
  std::array<std::uint32_t, 32> end_vertices{};  // those and the ones snapped onto
  std::uint32_t ncreated = 0, nend_vertices = 0;
  const auto& end_triangle = ends.triangle;
  for (std::uint32_t i = 0; i < ends.count; ++i) {
    const Vec3& y = ends.at[i];
    std::uint32_t best = kNone;
    double best_d2 = 1e-12;
    // Usually the triangle it was found in is still there; otherwise (an earlier end split it)
    // search the triangles near the cut, which include the pieces.
    if (s.triangle_alive(end_triangle[i].index) && s.triangle_id(end_triangle[i].index) == end_triangle[i]) {
      const auto tv = s.triangle_vertices(end_triangle[i].index);
      const double d2 = (y - closest_point_on_triangle(y, s.position(tv[0]), s.position(tv[1]), s.position(tv[2]))).squaredNorm();
      if (d2 < best_d2) best = end_triangle[i].index;
    }
    for (auto t : triangles_) {
      if (best != kNone) break;
      if (!s.triangle_alive(t)) continue;
      const auto tv = s.triangle_vertices(t);
      const double d2 = (y - closest_point_on_triangle(y, s.position(tv[0]), s.position(tv[1]), s.position(tv[2]))).squaredNorm();
      if (d2 < best_d2) {
        best_d2 = d2;
        best = t;
      }
    }
    if (best == kNone) continue;
    const auto tv = s.triangle_vertices(best);
    const Vec3 &a = s.position(tv[0]), &b = s.position(tv[1]), &c = s.position(tv[2]);
    const Vec3 n = (b - a).cross(c - a);
    const double n2 = n.squaredNorm();
    std::array<double, 3> w{n.dot((c - b).cross(y - b)) / n2, n.dot((a - c).cross(y - c)) / n2, 0.0};
    w[2] = 1.0 - w[0] - w[1];
    int zeros = 0, zero_at = 0;
    const double double_area = std::sqrt(n2);
    for (int j = 0; j < 3; ++j) {
      auto& wj = w[static_cast<std::size_t>(j)];
      // Distance to the edge opposite corner j: w_j × 2A / |edge|.
      const Vec3& e0 = s.position(tv[static_cast<std::size_t>((j + 1) % 3)]);
      const Vec3& e1 = s.position(tv[static_cast<std::size_t>((j + 2) % 3)]);
      const double dist = wj * double_area / std::max((e1 - e0).norm(), 1e-300);
      if (wj < snap || wj <= 1e-9 || dist <= settings_.min_piece_mm) {
        wj = 0.0;
        ++zeros;
        zero_at = j;
      }
    }
    std::uint32_t nv = kNone;
    if (zeros >= 2) {
      nv = tv[static_cast<std::size_t>(std::max_element(w.begin(), w.end()) - w.begin())];
      if (vertex_[nv].cut != stamp_) ++r.snapped;
    } else if (zeros == 1) {
      const auto j1 = static_cast<std::size_t>((zero_at + 1) % 3), j2 = static_cast<std::size_t>((zero_at + 2) % 3);
      const std::uint32_t e = s.triangle_edges(best)[j1];  // joins corners j1 and j2
      const double along = w[j2] / (w[j1] + w[j2]);
      const double t = s.edge_vertices(e)[0] == tv[j1] ? along : 1.0 - along;
      const auto split = s.split_edge(s.edge_id(e), t);
      if (!split.status) continue;
      nv = split.vertex;
      created[ncreated++] = nv;
      ++r.springs_split;
    } else {
      const double sum = w[0] + w[1] + w[2];
      for (auto& wj : w) wj /= sum;
      const auto split = s.split_triangle(s.triangle_id(best), w);
      if (!split.status) continue;
      nv = split.vertex;
      created[ncreated++] = nv;
    }
    if (nv != kNone && vertex_[nv].cut != stamp_) {
      mark(nv);
      candidates_.push_back(nv);
      end_vertices[nend_vertices++] = nv;
      ++r.end_points;
      // The triangles made by the split, for the next end's search.
      s.for_each_triangle_of(nv, [&](std::uint32_t t, std::uint32_t) {
        if (triangles_.size() < triangles_.capacity()) triangles_.push_back(t);
      });
    }
  }

  // 2. Crossings: snap onto a vertex within the tolerance, otherwise split the spring there.
  // The springs around the end vertices join the search: those the ends added (each joins a
  // created end vertex: split_edge and split_triangle only add springs to their new vertex), and
  // old ones no candidate reached before.
  const std::uint32_t first_round = edge_round_;
  ++edge_round_;
  auto is_created = [&](std::uint32_t v) {
    for (std::uint32_t i = 0; i < ncreated; ++i) {
      if (created[i] == v) return true;
    }
    return false;
  };
  edges_.clear();  // the first search's springs have their crossings; now the new ones
  for (std::uint32_t i = 0; i < nend_vertices; ++i) {
    if (!s.vertex_alive(end_vertices[i])) continue;
    s.for_each_triangle_of(end_vertices[i], [&](std::uint32_t tri, std::uint32_t) {
      for (auto e : s.triangle_edges(tri)) {
        const bool seen_before = edge_stamp_[e] == first_round;
        if (edge_stamp_[e] == edge_round_) continue;
        edge_stamp_[e] = edge_round_;
        const auto [a, b] = s.edge_vertices(e);
        if (!is_created(a) && !is_created(b) && seen_before) continue;  // in the first search
        edges_.push_back(e);
      }
    });
  }
  find_crossings(edges_);
  // Snap the crossings near a vertex (in order; a snapped vertex settles its other springs).
  std::size_t kept = 0;
  for (std::size_t i = 0; i < crossings_.size(); ++i) {
    const Crossing c = crossings_[i];
    if (!s.is_current(c.edge)) continue;  // split by an end
    const double t = c.t;
    const auto [a, b] = s.edge_vertices(c.edge.index);
    if (vertex_[a].cut == stamp_ || vertex_[b].cut == stamp_) continue;
    // Band in the current shape, the floor on pieces in the rest shape (what the springs keep).
    const double len = (s.position(b) - s.position(a)).norm(), rest = s.edge_rest_length(c.edge.index);
    const double floor_mm = settings_.min_piece_mm;
    if (t < snap || t * len <= band || t * rest <= floor_mm) {
      mark(a);
      ++r.snapped;
    } else if (t > 1.0 - snap || (1.0 - t) * len <= band || (1.0 - t) * rest <= floor_mm) {
      mark(b);
      ++r.snapped;
    } else {
      crossings_[kept++] = c;
    }
  }
  crossings_.resize(kept);
  for (const auto& c : crossings_) {
    const auto [a, b] = s.edge_vertices(c.edge.index);
    if (!s.is_current(c.edge) || vertex_[a].cut == stamp_ || vertex_[b].cut == stamp_) continue;
    const auto split = s.split_edge(c.edge, c.t);
    if (!split.status) continue;
    mark(split.vertex);
    ++r.springs_split;
  }

  // 3. Springs along the cut.
  ++edge_round_;
  to_open_.clear();
  auto on_cut = [&](std::uint32_t v) { return vertex_[v].cut == stamp_; };
  for (auto v : on_cut_) vertex_[v].cut_degree = 0;
  for (std::size_t i = 0; i < on_cut_.size(); ++i) {
    const std::uint32_t v = on_cut_[i];
    s.for_each_triangle_of(v, [&](std::uint32_t t, std::uint32_t) {
      for (auto e : s.triangle_edges(t)) {
        if (edge_stamp_[e] == edge_round_) continue;
        edge_stamp_[e] = edge_round_;
        const auto [a, b] = s.edge_vertices(e);
        if (!on_cut(a) || !on_cut(b) || s.edge_triangles(e)[1] == kNone) continue;
        const Vec3 mid = 0.5 * (s.position(a) + s.position(b));
        const double len = (s.position(b) - s.position(a)).norm();
        if (!near_swept(mid, band + snap * len)) continue;
        to_open_.push_back(s.edge_id(e));
        if (vertex_[a].cut_degree < 255) ++vertex_[a].cut_degree;
        if (vertex_[b].cut_degree < 255) ++vertex_[b].cut_degree;
      }
    });
  }
  auto interior = [&](std::uint32_t v) {
    bool in = true;
    s.for_each_triangle_of(v, [&](std::uint32_t t, std::uint32_t) {
      for (auto e : s.triangle_edges(t)) in = in && s.edge_triangles(e)[1] != kNone;
    });
    return in;
  };
  const std::size_t nopen = to_open_.size();
  for (std::size_t i = 0; i < nopen; ++i) {
    const EdgeId id = to_open_[i];
    if (s.edge_triangles(id.index)[1] == kNone) continue;  // already a boundary: nothing to open
    const auto [a, b] = s.edge_vertices(id.index);
    if (vertex_[a].cut_degree != 1 || vertex_[b].cut_degree != 1 || !interior(a) || !interior(b)) continue;
    // A slit of one spring could not open: give it a middle vertex.
    const auto split = s.split_edge(id, 0.5);
    if (!split.status) continue;
    const std::uint32_t m = split.vertex;
    mark(m);
    vertex_[m].cut_degree = 2;
    to_open_[i] = s.edge_id(s.find_edge(a, m));
    to_open_.push_back(s.edge_id(s.find_edge(m, b)));
    ++r.springs_split;
  }
  for (const auto& id : to_open_) {
    if (!s.is_current(id) || s.edge_triangles(id.index)[1] == kNone) continue;
    if (s.disconnect_edge(id).status) ++r.springs_opened;
  }
  for (const auto& id : to_open_) {
    if (!s.is_current(id)) continue;
    for (auto v : s.edge_vertices(id.index)) {
      if (!s.vertex_alive(v) || vertex_[v].separated == stamp_) continue;  // once per vertex
      vertex_[v].separated = stamp_;
      const std::size_t before = on_cut_.size();
      r.vertices_added += s.separate_vertex_fans(s.vertex_id(v), &on_cut_);  // copies join the cut
      // A copy takes one fan whole: there is nothing to separate at it (the opened springs now
      // name it, so without this each would be visited again).
      for (std::size_t i = before; i < on_cut_.size(); ++i) vertex_[on_cut_[i]].separated = stamp_;
    }
  }
  r.vertices_added += r.end_points + r.springs_split;
}

}  // namespace vitreo::core
