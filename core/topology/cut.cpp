#include "core/topology/cut.hpp"

#include <algorithm>
#include <cmath>

#include "core/common/prefault.hpp"
#include "core/common/validate.hpp"
#include "core/topology/geometry.hpp"
#include "core/topology/incision.hpp"

namespace vitreo::core {

using topology::closest_point_on_triangle;
using topology::segment_triangle;

void CutSettings::validate() const {
  require_range(band_mm, 0.0, 1.0, "cut: band_mm");
  require_range(snap_fraction, 0.0, 0.25, "cut: snap_fraction");
  require_range(min_piece_mm, 0.0, 1.0, "cut: min_piece_mm");
  require_range(kink_fraction, 1e-4, 0.25, "cut: kink_fraction");
  require_range(min_blade_length_mm, 1e-9, 10.0, "cut: min_blade_length_mm");
  require_range(min_swept_area_mm2, 0.0, 10.0, "cut: min_swept_area_mm2");
  quality.validate();
}

void CutResult::add(const CutResult& o) {
  if (status && !o.status) status = o.status;
  end_points += o.end_points;
  springs_split += o.springs_split;
  springs_opened += o.springs_opened;
  vertices_added += o.vertices_added;
  snapped += o.snapped;
  bends += o.bends;
  collapsed += o.collapsed;
  dissolved += o.dissolved;
  unresolved += o.unresolved;
  gaps += o.gaps;
  removed_mass_g += o.removed_mass_g;
}

Cutter::Cutter(Surface& surface, CutSettings settings)
    : surface_(surface), settings_(settings), index_(surface), quality_(surface, settings.quality) {
  settings_.validate();
  const std::size_t nv = surface.vertex_capacity(), ne = surface.edge_capacity();
  const std::size_t nt = ne;  // triangle capacity is below the spring capacity
  vertex_.assign(nv, VertexScratch{});
  edge_stamp_.assign(ne, 0);
  triangle_stamp_.assign(nt, 0);
  walked_.assign(nt, 0);
  held_.assign(nt, 0);
  // Scratch sized for the worst case and touched now, so no sweep allocates or takes a page fault.
  reserve_touched(candidates_, nv);
  reserve_touched(on_cut_, nv);
  reserve_touched(triangles_, nt);
  reserve_touched(edges_, ne);
  reserve_touched(star_, 256);
  reserve_touched(starts_, 256);
  reserve_touched(trailing_, 64);
  reserve_touched(to_open_, ne);
  reserve_touched(opening_, ne);
  double longest = 0.0;
  for (std::uint32_t e = 0; e < surface.edge_slots(); ++e) {
    if (surface.edge_alive(e)) longest = std::max(longest, surface.edge_rest_length(e));
  }
  // How far from the swept polygon a vertex can matter, for springs no longer than L (a spring may
  // be stretched up to its tear strain; L = twice the longest rest length covers every material's):
  //  - a spring crossing the polygon at y has |a − y| + |y − b| = L, so one end lies within L/2;
  //  - a point inside a triangle lies within L/√3 of its nearest corner (the worst point is the
  //    centre of an equilateral triangle), so a triangle the polygon's rim passes through has a
  //    corner within L/√3 (+ the band) of the rim.
  margin_mm_ = 2.0 * longest / std::sqrt(3.0) + settings_.band_mm;
}

// ---- The swept polygon ----------------------------------------------------------------------

bool Cutter::set_swept(const BladeEdge& from, const BladeEdge& to) {
  const Vec3 &p0 = from.a_mm, &q0 = from.b_mm, &p1 = to.a_mm, &q1 = to.b_mm;
  poly_ = {p0, q0, q1, p1};
  swept_tri_[0] = {p0, q0, q1};
  swept_tri_[1] = {p0, q1, p1};
  double best = 0.0;
  for (std::size_t k = 0; k < 2; ++k) {
    const Vec3 n = (swept_tri_[k][1] - swept_tri_[k][0]).cross(swept_tri_[k][2] - swept_tri_[k][0]);
    const double a = 0.5 * n.norm();
    swept_tri_valid_[k] = a > 1e-14;
    if (a > best) {
      best = a;
      swept_n_ = n / n.norm();
    }
  }
  if (!(best > 1e-14)) return false;
  swept_o_ = p0;
  // Both triangles must turn the same way about the plane's normal for the half-plane tests.
  for (std::size_t k = 0; k < 2; ++k) {
    if (!swept_tri_valid_[k]) continue;
    const Vec3 n = (swept_tri_[k][1] - swept_tri_[k][0]).cross(swept_tri_[k][2] - swept_tri_[k][0]);
    if (n.dot(swept_n_) < 0.0) std::swap(swept_tri_[k][1], swept_tri_[k][2]);
  }
  rim_ = {{{p0, q0}, {p1, q1}, {p0, p1}, {q0, q1}}};
  pivot_a_ = (p1 - p0).squaredNorm() <= 1e-24;
  pivot_b_ = (q1 - q0).squaredNorm() <= 1e-24;
  box_lo_ = p0.cwiseMin(q0).cwiseMin(p1).cwiseMin(q1).array() - margin_mm_;
  box_hi_ = p0.cwiseMax(q0).cwiseMax(p1).cwiseMax(q1).array() + margin_mm_;
  return true;
}

std::uint8_t Cutter::rim_bits(const Vec3& x) const {
  // The polygon is grown by the band, so a point where it clips a piece lies up to the band (√2
  // of it at a corner) outside a rim.
  const double tol = 1.5 * settings_.band_mm + 1e-9;
  // A pivot (an end of the edge that did not move) is a fixed end of the cut, not the blade's
  // moving front: a point there ends the cut.
  if ((pivot_a_ && (x - rim_[2][0]).norm() <= tol) || (pivot_b_ && (x - rim_[3][0]).norm() <= tol)) return kRimPath;
  std::array<double, 4> d{};
  for (std::size_t k = 0; k < 4; ++k) {
    const bool degenerate = (k == 2 && pivot_a_) || (k == 3 && pivot_b_);
    d[k] = degenerate ? INFINITY : topology::distance_to_segment(x, rim_[k][0], rim_[k][1]);
  }
  std::uint8_t bits = 0;
  if (d[0] <= tol) bits |= kRimLeading;
  if (d[1] <= tol) bits |= kRimTrailing;
  if (d[2] <= tol || d[3] <= tol) bits |= kRimPath;
  return bits;
}

std::uint8_t Cutter::nearest_rim(const Vec3& x) const {
  const std::uint8_t bits = rim_bits(x);
  if (bits != 0) return bits;
  std::array<double, 4> d{};
  for (std::size_t k = 0; k < 4; ++k) d[k] = topology::distance_to_segment(x, rim_[k][0], rim_[k][1]);
  const auto k = std::min_element(d.begin(), d.end()) - d.begin();
  return k == 0 ? kRimLeading : (k == 1 ? kRimTrailing : kRimPath);
}

double Cutter::progress(const Vec3& x) const {
  // Signed distances (in the plane) to the lines of the blade at its two poses, each positive
  // toward the polygon: their ratio runs from 0 on the first pose to 1 on the last, for a
  // translation (parallel lines) and a pivot (lines through the pivot) alike.
  const Vec3 centre = 0.25 * (poly_[0] + poly_[1] + poly_[2] + poly_[3]);
  auto signed_distance = [&](const Vec3& a, const Vec3& b) {
    Vec3 m = swept_n_.cross(b - a);
    const double len = m.norm();
    if (!(len > 0.0)) return 0.0;
    m /= len;
    const double d = m.dot(x - a);
    return m.dot(centre - a) < 0.0 ? -d : d;
  };
  const double sl = signed_distance(rim_[0][0], rim_[0][1]), st = signed_distance(rim_[1][0], rim_[1][1]);
  const double sum = sl + st;
  return std::abs(sum) > 1e-15 ? sl / sum : 0.5;
}

// ---- Candidates ------------------------------------------------------------------------------

void Cutter::gather_candidates() {
  candidates_.clear();
  const Surface& s = surface_;
  const double band = settings_.band_mm;
  const auto wanted = [&](std::uint32_t v) {
    const Vec3& x = s.position(v);
    const double plane = plane_distance(x);
    if (std::abs(plane) > margin_mm_) return;
    double d2 = INFINITY;
    for (std::size_t k = 0; k < 2; ++k) {
      if (!swept_tri_valid_[k]) continue;
      const auto& t = swept_tri_[k];
      d2 = std::min(d2, (x - closest_point_on_triangle(x, t[0], t[1], t[2])).squaredNorm());
    }
    if (d2 > margin_mm_ * margin_mm_) return;
    candidates_.push_back(v);
    VertexScratch& vs = vertex_[v];
    vs.side_stamp = stamp_;  // for the pieces of the triangles around it
    vs.side = plane;
    vs.on_surface = std::abs(plane) <= kOnPlane && d2 <= band * band ? 1 : 0;
    std::uint8_t mask = 0;
    for (std::size_t k = 0; k < rim_.size(); ++k) {
      if (topology::distance_to_segment(x, rim_[k][0], rim_[k][1]) <= margin_mm_) mask |= static_cast<std::uint8_t>(1u << k);
    }
    vs.rim = mask;
    vs.walked = 0;
  };
  // A block can hold a candidate only if its box comes within the margin of the polygon's plane
  // (a point near the polygon is near its plane): the box's extent along the normal is its
  // centre's distance ± the half-sizes projected on |n|.
  const auto block_near_plane = [&](const Vec3& lo, const Vec3& hi) {
    const Vec3 centre = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
    const double reach = swept_n_.cwiseAbs().dot(half) + margin_mm_;
    return std::abs(plane_distance(centre)) <= reach;
  };
  index_.for_each_in_box(box_lo_, box_hi_, wanted, block_near_plane);
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

// ---- Pieces of cut ---------------------------------------------------------------------------

Cutter::Spot Cutter::vertex_spot(std::uint32_t v, std::uint32_t tri) const {
  Spot sp;
  sp.kind = Spot::kVertex;
  sp.vertex = v;
  sp.tri = tri;
  sp.generation = surface_.triangle_id(tri).generation;
  sp.x = surface_.position(v);
  const auto tv = surface_.triangle_vertices(tri);
  for (std::size_t k = 0; k < 3; ++k) sp.bary[k] = tv[k] == v ? 1.0 : 0.0;
  return sp;
}

void Cutter::classify(std::array<double, 3>& w, const std::array<std::uint32_t, 3>& tv, const std::array<std::uint32_t, 3>& te,
                      std::uint8_t& kind, std::uint32_t& vertex, std::uint32_t& edge) {
  constexpr double kZero = 1e-12;
  int zeros = 0, zero_at = 0;
  for (int j = 0; j < 3; ++j) {
    if (w[static_cast<std::size_t>(j)] <= kZero) {
      w[static_cast<std::size_t>(j)] = 0.0;
      ++zeros;
      zero_at = j;
    }
  }
  const double sum = w[0] + w[1] + w[2];
  for (auto& x : w) x /= sum;
  if (zeros >= 2) {
    const auto k = static_cast<std::size_t>(std::max_element(w.begin(), w.end()) - w.begin());
    kind = 2;
    vertex = tv[k];
    w = {0.0, 0.0, 0.0};
    w[k] = 1.0;
  } else if (zeros == 1) {
    kind = 1;
    edge = te[static_cast<std::size_t>((zero_at + 1) % 3)];  // joins the other two corners
  } else {
    kind = 0;
  }
}

bool Cutter::piece(std::uint32_t t, Spot& a, Spot& b) {
  const Surface& s = surface_;
  const auto tv = s.triangle_vertices(t);
  const auto te = s.triangle_edges(t);
  const double band = settings_.band_mm;
  // Which side of the plane each corner is on decides the piece's ends; only a corner on the plane
  // to within rounding counts as on it. (A band here made a corner 0.4 µm from the plane the piece's
  // only point where the plane really crossed the triangle 14 µm from it, along a spring it nearly
  // ran along: the blade's point from the last sweep was then in no piece.) Tiny pieces near a
  // corner are fine: what is inserted snaps (cut.hpp).
  std::array<double, 3> d{};
  std::array<bool, 3> z{};
  int nz = 0;
  for (std::size_t k = 0; k < 3; ++k) {
    d[k] = side(tv[k]);
    z[k] = std::abs(d[k]) <= kOnPlane;
    nz += z[k] ? 1 : 0;
  }
  if (nz == 3) return false;  // the triangle lies in the polygon's plane: a blade flat on the tissue cuts nothing
  // The triangle's segment on the plane: its vertices on it and the crossings of its springs.
  std::array<Spot, 2> p;
  int n = 0;
  for (std::size_t k = 0; k < 3; ++k) {
    if (z[k] && n < 2) p[static_cast<std::size_t>(n++)] = vertex_spot(tv[k], t);
  }
  for (std::size_t k = 0; k < 3 && n < 2; ++k) {
    const std::size_t i = k, j = (k + 1) % 3;
    if (z[i] || z[j] || !(d[i] * d[j] < 0.0)) continue;
    // The crossing from the spring's own first end, so both its triangles compute the same point.
    const std::uint32_t e = te[k];
    const auto ev = s.edge_vertices(e);
    const double da = side(ev[0]), db = side(ev[1]);
    const double te_ = da / (da - db);
    Spot& sp = p[static_cast<std::size_t>(n++)];
    sp = Spot{};
    sp.kind = Spot::kEdge;
    sp.tri = t;
    sp.edge = e;
    const double toward_j = ev[0] == tv[i] ? te_ : 1.0 - te_;
    sp.bary[i] = 1.0 - toward_j;
    sp.bary[j] = toward_j;
    sp.x = (1.0 - te_) * s.position(ev[0]) + te_ * s.position(ev[1]);
  }
  if (n != 2) return false;
  // Clip it to the polygon (each valid triangle of it, grown by the band), in the plane.
  const Vec3 u = p[0].x, dv = p[1].x - p[0].x;
  double lo = 1.0, hi = 0.0;
  for (std::size_t k = 0; k < 2; ++k) {
    if (!swept_tri_valid_[k]) continue;
    const auto& q = swept_tri_[k];
    double l = 0.0, h = 1.0;
    for (std::size_t m = 0; m < 3 && l <= h; ++m) {
      const Vec3& qa = q[m];
      const Vec3& qb = q[(m + 1) % 3];
      const Vec3 inward = swept_n_.cross(qb - qa);
      const double len = inward.norm();
      if (!(len > 0.0)) continue;
      // inward · (u + λ dv − qa) ≥ −band |inward|
      const double f0 = inward.dot(u - qa) + band * len, f1 = inward.dot(dv);
      if (std::abs(f1) <= 1e-300) {
        if (f0 < 0.0) h = -1.0;
      } else if (f1 > 0.0) {
        l = std::max(l, -f0 / f1);
      } else {
        h = std::min(h, -f0 / f1);
      }
    }
    if (l <= h) {
      lo = std::min(lo, l);
      hi = std::max(hi, h);
    }
  }
  if (!(hi >= lo) || (hi - lo) * dv.norm() <= 1e-12) return false;
  auto end_at = [&](double lambda, Spot& out) {
    if (lambda <= 1e-12) {
      out = p[0];
      return;
    }
    if (lambda >= 1.0 - 1e-12) {
      out = p[1];
      return;
    }
    // Clipped by the polygon's rim: a point inside the triangle (or on a spring of it).
    out = Spot{};
    out.tri = t;
    for (std::size_t k = 0; k < 3; ++k) out.bary[k] = (1.0 - lambda) * p[0].bary[k] + lambda * p[1].bary[k];
    out.x = u + lambda * dv;
    std::uint8_t kind = 0;
    classify(out.bary, tv, te, kind, out.vertex, out.edge);
    out.kind = static_cast<Spot::Kind>(kind);
    if (out.kind == Spot::kVertex) out.x = s.position(out.vertex);
    out.rim = nearest_rim(out.x);  // clipped, so on a rim
  };
  end_at(lo, a);
  end_at(hi, b);
  return true;
}

bool Cutter::forward_from(std::uint32_t t, const Spot& c, const Spot* back, Spot& e) {
  Spot a, b;
  if (!piece(t, a, b)) return false;
  constexpr double kTol = 1e-9;
  const bool near_a = (a.x - c.x).norm() <= kTol, near_b = (b.x - c.x).norm() <= kTol;
  if (near_a && near_b) return false;
  if (near_a) {
    e = b;
  } else if (near_b) {
    e = a;
  } else {
    // c lies inside the piece (the blade's point from the last sweep, or a point snapped to a
    // vertex): the piece must hold it, and the end ahead is the one the blade moved toward.
    const auto tv = surface_.triangle_vertices(t);
    const Surface& s = surface_;
    const Vec3 &x0 = s.position(tv[0]), &x1 = s.position(tv[1]), &x2 = s.position(tv[2]);
    const Vec3 n = (x1 - x0).cross(x2 - x0);
    const double n2 = n.squaredNorm();
    if (!(n2 > 0.0)) return false;
    const double w0 = n.dot((x2 - x1).cross(c.x - x1)) / n2, w1 = n.dot((x0 - x2).cross(c.x - x2)) / n2;
    if (w0 < -1e-9 || w1 < -1e-9 || 1.0 - w0 - w1 < -1e-9) return false;
    const double pa = progress(a.x), pb = progress(b.x);
    if (std::abs(pa - pb) > 1e-9) {
      e = pa > pb ? a : b;
    } else if (back != nullptr) {
      e = (a.x - back->x).squaredNorm() > (b.x - back->x).squaredNorm() ? a : b;
    } else {
      e = b;
    }
  }
  if ((e.x - c.x).norm() <= kTol) return false;
  if (back != nullptr && (e.x - back->x).norm() <= kTol) return false;
  // It must not run back toward where the blade was: progress grows along a cut (for a cut along
  // the polygon's rim, where progress is the same everywhere, it must move away from `back`).
  const double dp = progress(e.x) - progress(c.x);
  if (dp < -1e-9) return false;
  if (dp <= 1e-9 && back != nullptr && (e.x - back->x).norm() <= (c.x - back->x).norm()) return false;
  return true;
}

// ---- Where new cracks start --------------------------------------------------------------------

void Cutter::find_starts() {
  starts_.clear();
  trailing_.clear();
  const Surface& s = surface_;
  const double band = settings_.band_mm;
  auto push_start = [&](const Spot& sp, std::uint8_t priority) {
    if (starts_.size() < starts_.capacity()) starts_.push_back({sp, priority});
  };
  auto rim_mask = [&](std::uint32_t v) { return vertex_[v].side_stamp == stamp_ ? vertex_[v].rim : std::uint8_t{0}; };
  // Where the rims pass through triangles: the blade at its first pose (a crack that is not one
  // of the incision's yet), at its last (where the blade now is), and the paths of its ends
  // (an end dipping into the tissue or leaving it).
  for (auto t : triangles_) {
    const auto tv = s.triangle_vertices(t);
    const std::uint8_t any = rim_mask(tv[0]) | rim_mask(tv[1]) | rim_mask(tv[2]);
    if (any == 0) continue;
    // The rims lie in the plane: a triangle wholly on one side of it (beyond the band) meets none.
    const double d0 = side(tv[0]), d1 = side(tv[1]), d2 = side(tv[2]);
    if ((d0 > band && d1 > band && d2 > band) || (d0 < -band && d1 < -band && d2 < -band)) continue;
    for (std::size_t k = 0; k < rim_.size(); ++k) {
      if (!(any & (1u << k))) continue;
      const auto& seg = rim_[k];
      if ((seg[1] - seg[0]).squaredNorm() < 1e-24) continue;
      double sp;
      std::array<double, 3> bary;
      if (!segment_triangle(seg[0], seg[1], s.position(tv[0]), s.position(tv[1]), s.position(tv[2]), sp, bary)) continue;
      Spot spot;
      spot.tri = t;
      spot.generation = s.triangle_id(t).generation;
      spot.bary = {std::max(bary[0], 0.0), std::max(bary[1], 0.0), std::max(bary[2], 0.0)};
      std::uint8_t kind = 0;
      classify(spot.bary, tv, s.triangle_edges(t), kind, spot.vertex, spot.edge);
      spot.kind = static_cast<Spot::Kind>(kind);
      spot.x = spot.kind == Spot::kVertex ? s.position(spot.vertex) : Vec3(seg[0] + sp * (seg[1] - seg[0]));
      spot.rim = rim_bits(spot.x);
      // Which rim found it says what it is (a short sweep puts a point within the band of both
      // poses); a blade end's path meets the last pose at the blade's end: that is where it is now.
      if (k == 1 || (k >= 2 && (spot.rim & kRimTrailing))) {
        if (trailing_.size() < trailing_.capacity()) trailing_.push_back(spot);
      } else {
        push_start(spot, k == 0 ? 0 : 1);
      }
    }
  }
  // Where the polygon enters the tissue across its boundary: boundary springs crossing it, and
  // boundary vertices on it.
  auto inside_polygon = [&](const Vec3& x) {
    for (std::size_t k = 0; k < 2; ++k) {
      if (!swept_tri_valid_[k]) continue;
      const auto& q = swept_tri_[k];
      if ((x - closest_point_on_triangle(x, q[0], q[1], q[2])).squaredNorm() <= band * band + 1e-24) return true;
    }
    return false;
  };
  // Only where the blade goes from its first pose to before its last: the band around the polygon
  // reaches behind the first pose, into the last sweep's ground (and a crossing on the last pose
  // is met by both sweeps: the first finds nothing beyond it).
  auto ahead = [&](const Vec3& x) {
    const double p = progress(x);
    return p >= 0.0 && p <= 1.0 + 1e-9;
  };
  // A boundary spring lying along the polygon (both ends within snapping distance of its plane: the
  // blade moving along a cut made before, sawing) is no place where a cut starts: what lies
  // between it and the plane is thinner than anything a cut may leave.
  auto grazing = [&](std::uint32_t e) {
    const auto ev = s.edge_vertices(e);
    const double near = std::max(settings_.min_piece_mm, settings_.snap_fraction * s.edge_rest_length(e));
    return std::abs(side(ev[0])) <= near && std::abs(side(ev[1])) <= near;
  };
  for (auto e : edges_) {
    if (s.edge_triangles(e)[1] != kNone || s.edge_is_line(e) || grazing(e)) continue;
    const auto ev = s.edge_vertices(e);
    const double da = side(ev[0]), db = side(ev[1]);
    if (std::abs(da) <= kOnPlane || std::abs(db) <= kOnPlane || !(da * db < 0.0)) continue;
    const double t = da / (da - db);
    const Vec3 x = (1.0 - t) * s.position(ev[0]) + t * s.position(ev[1]);
    if (!inside_polygon(x) || !ahead(x)) continue;
    const std::uint32_t tri = s.edge_triangles(e)[0];
    Spot spot;
    spot.kind = Spot::kEdge;
    spot.tri = tri;
    spot.generation = s.triangle_id(tri).generation;
    spot.edge = e;
    spot.x = x;
    const auto tv = s.triangle_vertices(tri);
    for (std::size_t k = 0; k < 3; ++k) spot.bary[k] = tv[k] == ev[0] ? 1.0 - t : (tv[k] == ev[1] ? t : 0.0);
    push_start(spot, 2);
  }
  for (auto v : candidates_) {
    if (!vertex_[v].on_surface || !ahead(s.position(v)) || !s.is_boundary_vertex(v)) continue;
    bool along = true;  // every boundary spring at it grazing: the polygon runs along the boundary
    s.for_each_triangle_of(v, [&](std::uint32_t t, std::uint32_t) {
      for (auto e : s.triangle_edges(t)) {
        const auto ev = s.edge_vertices(e);
        if ((ev[0] == v || ev[1] == v) && s.edge_triangles(e)[1] == kNone && !grazing(e)) along = false;
      }
    });
    if (along) continue;
    std::uint32_t tri = kNone;
    s.for_each_triangle_of(v, [&](std::uint32_t t, std::uint32_t) {
      if (tri == kNone) tri = t;
    });
    if (tri != kNone) push_start(vertex_spot(v, tri), 2);
  }
  // In priority order, stably (an insertion sort: std::stable_sort allocates a buffer; starts are few).
  for (std::size_t i = 1; i < starts_.size(); ++i) {
    for (std::size_t j = i; j > 0 && starts_[j].priority < starts_[j - 1].priority; --j) std::swap(starts_[j], starts_[j - 1]);
  }
}

// Springs crossing the polygon and vertices on it: what a sweep can split or separate (for the
// room check; bends and crack ends come on top).
std::uint32_t Cutter::count_crossings() {
  const Surface& s = surface_;
  const double band = settings_.band_mm;
  std::uint32_t n = 0;
  for (auto e : edges_) {
    const auto ev = s.edge_vertices(e);
    const double da = side(ev[0]), db = side(ev[1]);
    if (!(da * db < 0.0)) continue;
    const double t = da / (da - db);
    const Vec3 x = (1.0 - t) * s.position(ev[0]) + t * s.position(ev[1]);
    for (std::size_t k = 0; k < 2; ++k) {
      if (!swept_tri_valid_[k]) continue;
      const auto& q = swept_tri_[k];
      if ((x - closest_point_on_triangle(x, q[0], q[1], q[2])).squaredNorm() <= band * band + 1e-24) {
        ++n;
        break;
      }
    }
  }
  for (auto v : candidates_) n += vertex_[v].on_surface;
  return n;
}

// ---- Opening ---------------------------------------------------------------------------------

void Cutter::mark(std::uint32_t v) {
  if (vertex_[v].cut == stamp_) return;
  vertex_[v].cut = stamp_;
  vertex_[v].cut_degree = 0;
  if (on_cut_.size() < on_cut_.capacity()) on_cut_.push_back(v);
}

// Opens the springs the walks inserted (each from a crack tip to the point it reached), as one
// batch: the springs are disconnected and every vertex on them is separated into one copy per fan.
void Cutter::open_cut(CutResult& r, std::span<CrackTip> live) {
  Surface& s = surface_;
  ++edge_round_;
  opening_.clear();
  // A crack's last spring that would open as a slit of one spring (it needs a middle vertex to
  // open: neither end would have two fans) waits while the crack goes on: it opens with the next
  // one, as it would have had the blade moved on in the same sweep (a middle vertex made for a
  // few micrometres of slit only made slivers).
  for (CrackTip& tip : live) {
    if (tip.deferred_inserted && to_open_.size() < to_open_.capacity()) to_open_.push_back(tip.deferred);
    tip.deferred_inserted = false;
  }
  auto add = [&](std::uint32_t e) {
    if (edge_stamp_[e] == edge_round_) return;
    edge_stamp_[e] = edge_round_;
    if (s.edge_triangles(e)[1] == kNone) return;  // already on a boundary: nothing to open
    opening_.push_back(s.edge_id(e));
    const auto [a, b] = s.edge_vertices(e);
    mark(a);
    mark(b);
    if (vertex_[a].cut_degree < 255) ++vertex_[a].cut_degree;
    if (vertex_[b].cut_degree < 255) ++vertex_[b].cut_degree;
  };
  for (const auto& [a, b] : to_open_) {
    if (!s.is_current(a) || !s.is_current(b)) {
      ++r.gaps;
      continue;
    }
    const std::uint32_t e = s.find_edge(a.index, b.index);
    if (e != kNone) {
      add(e);
      continue;
    }
    // A later point of the same sweep split the spring: open its two parts (the vertex between
    // lies on the segment in the rest shape).
    const Vec3 ra = s.rest_position(a.index), rb = s.rest_position(b.index);
    std::uint32_t mid = kNone;
    s.for_each_triangle_of(a.index, [&](std::uint32_t t, std::uint32_t) {
      for (auto w : s.triangle_vertices(t)) {
        if (mid != kNone || w == a.index || w == b.index) continue;
        if (topology::distance_to_segment(s.rest_position(w), ra, rb) <= 1e-9 && s.find_edge(w, b.index) != kNone) mid = w;
      }
    });
    if (mid == kNone) {
      ++r.gaps;
      continue;
    }
    add(s.find_edge(a.index, mid));
    add(s.find_edge(mid, b.index));
  }
  auto interior = [&](std::uint32_t v) {
    bool in = true;
    s.for_each_triangle_of(v, [&](std::uint32_t t, std::uint32_t) {
      for (auto e : s.triangle_edges(t)) in = in && s.edge_triangles(e)[1] != kNone;
    });
    return in;
  };
  const std::size_t nopen = opening_.size();
  for (std::size_t i = 0; i < nopen; ++i) {
    const EdgeId id = opening_[i];
    const auto [a, b] = s.edge_vertices(id.index);
    if (vertex_[a].cut_degree != 1 || vertex_[b].cut_degree != 1 || !interior(a) || !interior(b)) continue;
    CrackTip* waiting = nullptr;
    for (CrackTip& tip : live) {
      if (tip.origin_inserted && (tip.origin.index == a || tip.origin.index == b)) waiting = &tip;
    }
    if (waiting != nullptr) {
      waiting->deferred = {s.vertex_id(a), s.vertex_id(b)};
      waiting->deferred_inserted = true;
      opening_[i] = EdgeId{};  // not opened now
      continue;
    }
    // A slit of one spring could not open (neither end would have two fans): give it a middle vertex.
    const auto split = s.split_edge(id, 0.5);
    if (!split.status) continue;
    const std::uint32_t m = split.vertex;
    mark(m);
    vertex_[m].cut_degree = 2;
    opening_[i] = s.edge_id(s.find_edge(a, m));
    opening_.push_back(s.edge_id(s.find_edge(m, b)));
    ++r.springs_split;
    ++r.vertices_added;
  }
  for (const auto& id : opening_) {
    if (id.index == kNone || !s.is_current(id) || s.edge_triangles(id.index)[1] == kNone) continue;
    if (s.disconnect_edge(id).status) ++r.springs_opened;
  }
  for (const auto& id : opening_) {
    if (id.index == kNone || !s.is_current(id)) continue;
    for (auto v : s.edge_vertices(id.index)) {
      if (!s.vertex_alive(v) || vertex_[v].separated == stamp_) continue;  // once per vertex
      vertex_[v].separated = stamp_;
      const std::size_t before = on_cut_.size();
      r.vertices_added += s.separate_vertex_fans(s.vertex_id(v), &on_cut_);  // copies join the cut
      // A copy takes one fan whole: there is nothing to separate at it.
      for (std::size_t i = before; i < on_cut_.size(); ++i) {
        vertex_[on_cut_[i]].separated = stamp_;
        vertex_[on_cut_[i]].cut = stamp_;
      }
    }
  }
  to_open_.clear();
}

void Cutter::clean(CutResult& r) {
  Surface& s = surface_;
  for (auto v : on_cut_) {
    if (s.vertex_alive(v)) s.wake_vertex(v);
  }
  // Every triangle the cut made or changed has a vertex on the cut (or a copy of one).
  const QualityResult q = quality_.clean_around(on_cut_);
  r.collapsed += q.collapses;
  r.dissolved += q.dissolved;
  r.unresolved += q.unresolved;
  r.removed_mass_g += q.removed_mass_g;
}

// ---- One-shot sweeps ---------------------------------------------------------------------------

CutResult Cutter::sweep(const BladeEdge& from, const BladeEdge& to) {
  CutResult r;
  if (!is_finite(from.a_mm) || !is_finite(from.b_mm) || !is_finite(to.a_mm) || !is_finite(to.b_mm)) {
    r.status = Status::error("cut: non-finite blade pose");
    return r;
  }
  if ((from.b_mm - from.a_mm).norm() < settings_.min_blade_length_mm ||
      (to.b_mm - to.a_mm).norm() < settings_.min_blade_length_mm) {
    r.status = Status::error("cut: degenerate blade (cutting edge shorter than min_blade_length_mm)");
    return r;
  }
  const double area = 0.5 * ((from.b_mm - from.a_mm).cross(to.b_mm - from.a_mm).norm() +
                             (to.b_mm - from.a_mm).cross(to.a_mm - from.a_mm).norm());
  if (!(area > settings_.min_swept_area_mm2)) {
    r.status = Status::error("cut: degenerate sweep (the blade did not sweep any area)");
    return r;
  }
  Incision incision(*this);
  r = incision.advance(from);
  if (r.status) r.add(incision.advance(to));
  if (r.status) r.add(incision.end());
  return r;
}

}  // namespace vitreo::core
