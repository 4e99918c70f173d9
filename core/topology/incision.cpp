// The incision's side of the Cutter: crack tips carried from sweep to sweep, the walk along the cut,
// what is inserted where (cut.hpp has the rules, incision.hpp the why).
#include "core/topology/incision.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/common/validate.hpp"
#include "core/topology/geometry.hpp"

namespace vitreo::core {

CutResult Incision::advance(const BladeEdge& edge) { return cutter_.advance(*this, edge); }
CutResult Incision::end() { return cutter_.finish(*this); }

namespace {

// A walk crosses one triangle a step; a cut across the 80k retina crosses a few thousand.
constexpr std::uint32_t kMaxWalkSteps = 1u << 15;

// Barycentric coordinates of x projected into the plane of (a, b, c); false for a degenerate triangle.
bool barycentric(const Vec3& x, const Vec3& a, const Vec3& b, const Vec3& c, std::array<double, 3>& w) {
  const Vec3 n = (b - a).cross(c - a);
  const double n2 = n.squaredNorm();
  if (!(n2 > 0.0)) return false;
  w[0] = n.dot((c - b).cross(x - b)) / n2;
  w[1] = n.dot((a - c).cross(x - c)) / n2;
  w[2] = 1.0 - w[0] - w[1];
  return true;
}

double wrap_angle(double a) {
  while (a > std::numbers::pi) a -= 2.0 * std::numbers::pi;
  while (a < -std::numbers::pi) a += 2.0 * std::numbers::pi;
  return a;
}

}  // namespace

// ---- Points on the tissue ------------------------------------------------------------------

Cutter::Spot Cutter::make_spot(std::uint32_t tri, std::array<double, 3> bary) const {
  const Surface& s = surface_;
  Spot sp;
  sp.tri = tri;
  sp.generation = s.triangle_id(tri).generation;
  const auto tv = s.triangle_vertices(tri);
  std::uint8_t kind = 0;
  classify(bary, tv, s.triangle_edges(tri), kind, sp.vertex, sp.edge);
  sp.kind = static_cast<Spot::Kind>(kind);
  sp.bary = bary;
  sp.x = sp.kind == Spot::kVertex ? s.position(sp.vertex)
                                  : Vec3(bary[0] * s.position(tv[0]) + bary[1] * s.position(tv[1]) + bary[2] * s.position(tv[2]));
  return sp;
}

Vec3 Cutter::position_of(const TissuePoint& p) const {
  const auto tv = surface_.triangle_vertices(p.triangle.index);
  return p.bary[0] * surface_.position(tv[0]) + p.bary[1] * surface_.position(tv[1]) + p.bary[2] * surface_.position(tv[2]);
}

Vec3 Cutter::rest_of(const Spot& sp) const {
  if (sp.kind == Spot::kVertex) return surface_.rest_position(sp.vertex);
  const auto tv = surface_.triangle_vertices(sp.tri);
  return sp.bary[0] * surface_.rest_position(tv[0]) + sp.bary[1] * surface_.rest_position(tv[1]) +
         sp.bary[2] * surface_.rest_position(tv[2]);
}

TissuePoint Cutter::anchor_of(const Spot& sp) const {
  TissuePoint p;
  p.triangle = surface_.triangle_id(sp.tri);
  p.bary = sp.bary;
  const auto tv = surface_.triangle_vertices(sp.tri);
  for (std::size_t k = 0; k < 3; ++k) p.corners[k] = surface_.vertex_id(tv[k]);
  p.rest = rest_of(sp);
  return p;
}

Cutter::Spot Cutter::spot_of(const TissuePoint& p) const { return make_spot(p.triangle.index, p.bary); }

// Finds p again by its rest position among the triangles around the given vertices (after the
// triangle it was in has been split or changed).
bool Cutter::locate(const TissuePoint& p, std::span<const std::uint32_t> around, TissuePoint& out, const CrackTip* prefer) const {
  const Surface& s = surface_;
  double best = -INFINITY;
  bool best_preferred = false;
  for (const std::uint32_t v : around) {
    if (v == kNone || !s.vertex_alive(v)) continue;
    s.for_each_triangle_of(v, [&](std::uint32_t t, std::uint32_t) {
      const auto tv = s.triangle_vertices(t);
      std::array<double, 3> w;
      if (!barycentric(p.rest, s.rest_position(tv[0]), s.rest_position(tv[1]), s.rest_position(tv[2]), w)) return;
      const double m = std::min({w[0], w[1], w[2]});
      // A point on the edge of several triangles goes in one around the tip's origin, if any.
      const bool preferred = prefer != nullptr && m >= -1e-9 && in_star(*prefer, t);
      if (best_preferred && !preferred) return;
      if (m <= best && !(preferred && !best_preferred)) return;
      best = m;
      best_preferred = preferred;
      out.triangle = s.triangle_id(t);
      out.bary = {std::max(w[0], 0.0), std::max(w[1], 0.0), std::max(w[2], 0.0)};
      const double sum = out.bary[0] + out.bary[1] + out.bary[2];
      for (auto& x : out.bary) x /= sum;
      for (std::size_t k = 0; k < 3; ++k) out.corners[k] = s.vertex_id(tv[k]);
      out.rest = p.rest;
    });
  }
  return best >= -1e-7;
}

// The same, among the triangles near where p was (its old corners' positions now): for a triangle
// changed beyond its corners' stars (a corner given a copy when its fans were separated).
bool Cutter::locate_near(const TissuePoint& p, TissuePoint& out) {
  const Surface& s = surface_;
  Vec3 x = Vec3::Zero();
  for (std::size_t k = 0; k < 3; ++k) {
    const VertexId c = p.corners[k];
    x += p.bary[k] * (c.index < s.vertex_slots() && s.vertex_alive(c.index) ? s.position(c.index) : p.rest);
  }
  const Vec3 reach = Vec3::Constant(margin_mm_);
  candidates_.clear();
  index_.for_each_in_box(x - reach, x + reach, [&](std::uint32_t v) { candidates_.push_back(v); });
  return locate(p, candidates_, out);
}

// c found again in the triangles around the tip's origin (a commit may have split its triangle).
Cutter::Spot Cutter::in_origin_star(const CrackTip& tip, const Spot& c) const {
  const Surface& s = surface_;
  double best = -INFINITY;
  Spot out = c;
  s.for_each_triangle_of(tip.origin.index, [&](std::uint32_t t, std::uint32_t) {
    const auto tv = s.triangle_vertices(t);
    std::array<double, 3> w;
    if (!barycentric(c.x, s.position(tv[0]), s.position(tv[1]), s.position(tv[2]), w)) return;
    const double m = std::min({w[0], w[1], w[2]});
    if (m <= best) return;
    best = m;
    out = make_spot(t, {std::max(w[0], 0.0), std::max(w[1], 0.0), std::max(w[2], 0.0)});
  });
  out.rim = c.rim;
  if (out.kind != Spot::kVertex) out.x = c.x;  // keep the point where the cut really is
  return out;
}

bool Cutter::in_star(const CrackTip& tip, std::uint32_t tri) const {
  const Surface& s = surface_;
  if (tip.origin_inserted) {
    const auto tv = s.triangle_vertices(tri);
    return tv[0] == tip.origin.index || tv[1] == tip.origin.index || tv[2] == tip.origin.index;
  }
  const TissuePoint& o = tip.origin_point;
  if (tri == o.triangle.index) return true;
  // A start on a spring: the triangle across it too.
  for (std::size_t j = 0; j < 3; ++j) {
    if (o.bary[j] != 0.0) continue;
    const std::uint32_t e = s.triangle_edges(o.triangle.index)[(j + 1) % 3];
    const auto et = s.edge_triangles(e);
    if (et[0] == tri || et[1] == tri) return true;
  }
  return false;
}

// ---- The bend test ---------------------------------------------------------------------------
// Samples are the points the blade went through since the tip's origin, in the rest shape projected
// on the tangent plane there. A chord from the origin keeps a sample at distance r within tol when
// its direction lies within asin(tol / r) of the sample's: the chords that keep all of them form an
// interval of directions [lo, hi], narrowed by each sample (and it must reach as far as they do).

void Cutter::reset_chord(CrackTip& tip) {
  tip.chord_constrained = false;
  tip.chord_frame = false;
  tip.r_max = 0.0;
}

namespace {
void chord_coordinates(const CrackTip& tip, const Vec3& rest, double& r, double& angle) {
  const Vec3 d = rest - tip.origin_rest;
  const double x = d.dot(tip.e1), y = d.dot(tip.e2);
  r = std::hypot(x, y);
  angle = std::atan2(y, x);
}
}  // namespace

bool Cutter::chord_accepts(CrackTip& tip, const Spot& p) {
  const Surface& s = surface_;
  if (!tip.chord_frame) {
    // The frame and the tolerance come from the triangle the first sample lies in.
    const auto tv = s.triangle_vertices(p.tri);
    const Vec3 &r0 = s.rest_position(tv[0]), &r1 = s.rest_position(tv[1]), &r2 = s.rest_position(tv[2]);
    Vec3 n = (r1 - r0).cross(r2 - r0);
    if (!(n.norm() > 0.0)) n = Vec3::UnitZ();
    n.normalize();
    tip.e1 = n.unitOrthogonal();
    tip.e2 = n.cross(tip.e1);
    double mean = 0.0;
    for (auto e : s.triangle_edges(p.tri)) mean += s.edge_rest_length(e) / 3.0;
    tip.tol_mm = settings_.kink_fraction * mean;
    tip.chord_frame = true;
  }
  double r, angle;
  chord_coordinates(tip, rest_of(p), r, angle);
  if (r < tip.r_max - tip.tol_mm) return false;  // the path came back toward the origin
  if (r <= tip.tol_mm || !tip.chord_constrained) return true;
  const double rel = wrap_angle(angle - tip.ref);
  return rel >= tip.lo && rel <= tip.hi;
}

// Whether p lies back along the chord, nearer the origin than where the blade already was: the
// blade turned back along its own cut (sawing), not a bend of the path.
bool Cutter::turned_back(const CrackTip& tip, const Spot& p) const {
  if (!tip.chord_frame || !tip.chord_constrained) return false;
  double r, angle;
  chord_coordinates(tip, rest_of(p), r, angle);
  if (!(r < tip.r_max - tip.tol_mm)) return false;
  const double rel = wrap_angle(angle - tip.ref);
  return rel >= tip.lo - 0.35 && rel <= tip.hi + 0.35;
}

void Cutter::note_sample(CrackTip& tip, const Spot& p) {
  double r, angle;
  chord_coordinates(tip, rest_of(p), r, angle);
  tip.r_max = std::max(tip.r_max, r);
  if (r <= tip.tol_mm) return;
  const double half = std::asin(tip.tol_mm / r);
  if (!tip.chord_constrained) {
    tip.chord_constrained = true;
    tip.ref = angle;
    tip.lo = -half;
    tip.hi = half;
    return;
  }
  const double rel = wrap_angle(angle - tip.ref);
  tip.lo = std::max(tip.lo, rel - half);
  tip.hi = std::min(tip.hi, rel + half);
}

// ---- Inserting points --------------------------------------------------------------------------

// Whether splitting spring e at t (from edge_vertices(e)[0]) would make a triangle with a rest angle
// below 1.5 × the cleanup's limit.
bool Cutter::splits_into_sliver(std::uint32_t e, double t) const {
  const Surface& s = surface_;
  const double limit = 1.5 * settings_.quality.min_angle_deg * std::numbers::pi / 180.0;
  if (!(limit > 0.0)) return false;
  const auto [a, b] = s.edge_vertices(e);
  const Vec3 ra = s.rest_position(a), rb = s.rest_position(b), rm = (1.0 - t) * ra + t * rb;
  auto min_angle = [](const Vec3& p, const Vec3& q, const Vec3& r) {
    auto ang = [](const Vec3& u, const Vec3& w) { return std::atan2(u.cross(w).norm(), u.dot(w)); };
    return std::min({ang(q - p, r - p), ang(p - q, r - q), ang(p - r, q - r)});
  };
  for (const auto tri : s.edge_triangles(e)) {
    if (tri == kNone) continue;
    std::uint32_t o = kNone;
    for (auto v : s.triangle_vertices(tri)) {
      if (v != a && v != b) o = v;
    }
    const Vec3 ro = s.rest_position(o);
    if (min_angle(ra, rm, ro) < limit || min_angle(rm, rb, ro) < limit) return true;
  }
  return false;
}

// Inserts y (snapping as documented in cut.hpp) and returns its vertex, or kNone.
std::uint32_t Cutter::insert_spot(const Spot& y, CutResult& r, bool end, std::uint32_t from) {
  Surface& s = surface_;
  if (y.kind == Spot::kVertex) return y.vertex;
  if (!s.triangle_alive(y.tri) || s.triangle_id(y.tri).generation != y.generation) return kNone;
  // A crack's start (from == kNone) moves by the floor only, not by snap_fraction: a path that comes
  // back to where it started ends on it exactly (and joins it there), whatever the mesh around.
  const double snap = from == kNone && end ? 0.0 : settings_.snap_fraction;
  const double floor_mm = settings_.min_piece_mm, band = settings_.band_mm;
  const auto tv = s.triangle_vertices(y.tri);
  const auto te = s.triangle_edges(y.tri);
  auto onto_edge = [&](std::uint32_t e, double t) -> std::uint32_t {
    // t from edge_vertices(e)[0]; a piece shorter than the tolerance goes onto the end.
    const auto ev = s.edge_vertices(e);
    const double rest = s.edge_rest_length(e), len = (s.position(ev[1]) - s.position(ev[0])).norm();
    bool near0 = t < snap || t * rest <= floor_mm || t * len <= band;
    bool near1 = 1.0 - t < snap || (1.0 - t) * rest <= floor_mm || (1.0 - t) * len <= band;
    // A split that would leave a sliver (a rest angle below 1.5 × the cleanup's limit; existing
    // thin triangles of a jittered mesh do) goes onto the nearer end when that is within twice the
    // snapping distance: the cleanup would otherwise dissolve the sliver, opening the tissue along
    // its long springs, far from the cut.
    // (Within twice the snap fraction of the spring and of the mean spring around it: a long spring
    // of a thin triangle would move the cut too far.)
    double sum = 0.0;
    int springs = 0;
    for (auto tri : s.edge_triangles(e)) {
      if (tri == kNone) continue;
      for (auto f : s.triangle_edges(tri)) {
        sum += s.edge_rest_length(f);
        ++springs;
      }
    }
    const double reach = 2.0 * settings_.snap_fraction * std::min(rest, sum / std::max(springs, 1));
    if (!near0 && !near1 && (t * rest <= reach || (1.0 - t) * rest <= reach) && splits_into_sliver(e, t)) {
      near0 = t * rest <= reach;
      near1 = !near0;
    }
    if (near0 || near1) {
      ++r.snapped;
      return near0 && (!near1 || t <= 0.5) ? ev[0] : ev[1];
    }
    const auto split = s.split_edge(s.edge_id(e), t);
    if (!split.status) {
      ++r.snapped;
      return t <= 0.5 ? ev[0] : ev[1];
    }
    ++r.springs_split;
    ++r.vertices_added;
    return split.vertex;
  };
  std::array<double, 3> w = y.bary;
  // A crack end goes onto a corner within snap_fraction of the triangle's mean spring (or
  // min_piece_mm): where a cut stops at a point of an earlier one (a closed path back at its
  // start) it joins it, even when that point had itself snapped onto a spring.
  if (end && from != kNone) {
    const Vec3 at = rest_of(y);
    double mean = 0.0;
    for (auto e : te) mean += s.edge_rest_length(e) / 3.0;
    const double reach = std::max(floor_mm, settings_.snap_fraction * mean);
    std::uint32_t nearest = kNone;
    double best = reach;
    for (std::size_t k = 0; k < 3; ++k) {
      if (tv[k] == from) continue;  // the crack's own tip: the end joins something else or nothing
      const double d = (s.rest_position(tv[k]) - at).norm();
      if (d <= best) {
        best = d;
        nearest = tv[k];
      }
    }
    if (nearest != kNone) {
      ++r.snapped;
      return nearest;
    }
  }
  if (y.kind == Spot::kEdge) {
    const auto ev = s.edge_vertices(y.edge);
    double t = 0.0;
    for (std::size_t k = 0; k < 3; ++k) {
      if (tv[k] == ev[1]) t = w[k];
    }
    return onto_edge(y.edge, t);
  }
  // Inside: onto a spring (or corner) when nearer than the tolerance, measured in the rest shape.
  const double area = s.triangle_rest_area(y.tri);
  int zeros = 0, zero_at = 0;
  double nearest_edge = INFINITY;
  for (int j = 0; j < 3; ++j) {
    const auto uj = static_cast<std::size_t>(j);
    const double opposite = s.edge_rest_length(te[static_cast<std::size_t>((j + 1) % 3)]);
    const double dist = w[uj] * 2.0 * area / std::max(opposite, 1e-300);
    if (w[uj] < snap || dist <= floor_mm) {
      ++zeros;
      if (dist < nearest_edge) {
        nearest_edge = dist;
        zero_at = j;
      }
    }
  }
  const auto corner = static_cast<std::size_t>(std::max_element(w.begin(), w.end()) - w.begin());
  if (zeros >= 2) {
    // Near two springs is near their corner only where they meet at a fair angle: in a thin
    // triangle a point can be near both and far from the corner. Then it goes onto the nearer one.
    double mean = 0.0;
    for (auto e : te) mean += s.edge_rest_length(e) / 3.0;
    if ((s.rest_position(tv[corner]) - rest_of(y)).norm() <= std::max(floor_mm, settings_.snap_fraction * mean)) {
      ++r.snapped;
      return tv[corner];
    }
    zeros = 1;
  }
  if (zeros == 1) {
    const auto j1 = static_cast<std::size_t>((zero_at + 1) % 3), j2 = static_cast<std::size_t>((zero_at + 2) % 3);
    const std::uint32_t e = te[j1];  // joins corners j1 and j2
    const double along = w[j2] / (w[j1] + w[j2]);
    return onto_edge(e, s.edge_vertices(e)[0] == tv[j1] ? along : 1.0 - along);
  }
  const auto split = s.split_triangle(s.triangle_id(y.tri), w);
  if (!split.status) {
    ++r.snapped;
    return tv[corner];
  }
  ++r.vertices_added;
  return split.vertex;
}

void Cutter::insert_origin(CrackTip& tip, CutResult& r) {
  Surface& s = surface_;
  TissuePoint o = tip.origin_point;
  if (!(s.triangle_alive(o.triangle.index) && s.triangle_id(o.triangle.index) == o.triangle)) {
    std::array<std::uint32_t, 3> around{o.corners[0].index, o.corners[1].index, o.corners[2].index};
    for (std::size_t k = 0; k < 3; ++k) {
      if (!s.is_current(o.corners[k])) around[k] = kNone;
    }
    TissuePoint found;
    if (locate(o, around, found)) o = found;
  }
  std::uint32_t m = kNone;
  const Spot start = spot_of(o);
  if (s.triangle_alive(o.triangle.index)) m = insert_spot(start, r, true, kNone);
  if (m == kNone) {
    ++r.gaps;
    m = s.triangle_vertices(o.triangle.index)[0];
  }
  if (start.kind == Spot::kInside) ++r.end_points;
  tip.origin_inserted = true;
  tip.origin = s.vertex_id(m);
  tip.origin_rest = s.rest_position(m);
  mark(m);
}

// Inserts y and joins it to the tip's origin with a spring to open; y becomes the origin.
void Cutter::commit(CrackTip& tip, const Spot& y, CutResult& r, bool crack_end) {
  Surface& s = surface_;
  if (!tip.origin_inserted) insert_origin(tip, r);
  Spot at = y;
  if (at.kind != Spot::kVertex) {
    const bool current = s.triangle_alive(at.tri) && s.triangle_id(at.tri).generation == at.generation && in_star(tip, at.tri);
    if (!current) at = in_origin_star(tip, y);
  }
  const std::uint32_t m = insert_spot(at, r, crack_end, tip.origin.index);
  if (m == kNone) {
    ++r.gaps;
    return;
  }
  if (crack_end && y.kind == Spot::kInside) ++r.end_points;
  const std::uint32_t o = tip.origin.index;
  if (m != o) {
    if (s.find_edge(o, m) != kNone) {
      if (to_open_.size() < to_open_.capacity()) to_open_.push_back({tip.origin, s.vertex_id(m)});
    } else {
      ++r.gaps;  // no spring joins them: the tip's star changed under it
    }
    mark(o);
    mark(m);
  }
  tip.origin = s.vertex_id(m);
  tip.origin_rest = s.rest_position(m);
  tip.has_pending = false;
  reset_chord(tip);
  vertex_[m].walked = stamp_;
}

// ---- The walk ----------------------------------------------------------------------------------

// The triangle holding c (one of those around it) where the cut goes on from c, and the point it
// reaches there: the end of that triangle's piece ahead of c.
bool Cutter::next_piece(const CrackTip& tip, const Spot& c, const Spot* back, std::uint32_t& tri, Spot& e) {
  const Surface& s = surface_;
  star_.clear();
  if (c.kind == Spot::kInside) {
    // A point that is all but on a spring or at a corner (the blade's point from the last sweep,
    // where the cut runs nearly along a spring): the triangles there too, since the plane's band
    // may put the cut's piece on the other side.
    star_.push_back(c.tri);
    constexpr double kNear = 1e-6;
    const auto tv = s.triangle_vertices(c.tri);
    const auto te = s.triangle_edges(c.tri);
    for (std::size_t j = 0; j < 3; ++j) {
      if (c.bary[j] >= kNear) continue;
      for (auto t : s.edge_triangles(te[(j + 1) % 3])) {
        if (t != kNone && t != c.tri && star_.size() < star_.capacity()) star_.push_back(t);
      }
      if (c.bary[(j + 1) % 3] < kNear || c.bary[(j + 2) % 3] < kNear) {
        const std::uint32_t corner = c.bary[(j + 1) % 3] < kNear ? tv[(j + 2) % 3] : tv[(j + 1) % 3];
        s.for_each_triangle_of(corner, [&](std::uint32_t t, std::uint32_t) {
          if (t != c.tri && star_.size() < star_.capacity()) star_.push_back(t);
        });
      }
    }
  } else if (c.kind == Spot::kEdge) {
    for (auto t : s.edge_triangles(c.edge)) {
      if (t != kNone) star_.push_back(t);
    }
    // A point on a spring all but at one of its ends (the blade's point where its plane runs
    // along a row of springs, through their vertices): the triangles round that end too.
    constexpr double kNear = 1e-6;
    const auto tv = s.triangle_vertices(c.tri);
    for (std::size_t j = 0; j < 3; ++j) {
      if (!(c.bary[j] > 1.0 - kNear)) continue;
      s.for_each_triangle_of(tv[j], [&](std::uint32_t t, std::uint32_t) {
        if (std::find(star_.begin(), star_.end(), t) == star_.end() && star_.size() < star_.capacity()) star_.push_back(t);
      });
    }
  } else {
    s.for_each_triangle_of(c.vertex, [&](std::uint32_t t, std::uint32_t) {
      if (star_.size() < star_.capacity()) star_.push_back(t);
    });
  }
  bool found = false;
  double best = -INFINITY;
  for (const std::uint32_t t : star_) {
    Spot f;
    if (!forward_from(t, c, back, f)) continue;
    // The most progress; on a tie, a triangle around the tip (no insertion needed yet).
    const double score = progress(f.x) + (in_star(tip, t) ? 1e-12 : 0.0);
    if (score > best) {
      best = score;
      tri = t;
      e = f;
      found = true;
    }
  }
  return found;
}

bool Cutter::on_boundary(const Spot& c) const {
  if (c.kind == Spot::kEdge) return surface_.edge_triangles(c.edge)[1] == kNone;
  if (c.kind == Spot::kVertex) return surface_.is_boundary_vertex(c.vertex);
  return false;
}

// The piece c → e ends where the polygon, grown by the band, clips it beyond the blade's last
// pose: the blade itself is where the piece crosses that pose's line (the next sweep starts there,
// exactly: at a vertex or on a spring when it passes through one).
Cutter::Spot Cutter::blade_point(std::uint32_t tri, const Spot& c, const Spot& e) const {
  const Vec3 centre = 0.25 * (poly_[0] + poly_[1] + poly_[2] + poly_[3]);
  Vec3 m = swept_n_.cross(rim_[1][1] - rim_[1][0]);
  if (!(m.norm() > 0.0)) return e;
  m.normalize();
  if (m.dot(centre - rim_[1][0]) < 0.0) m = -m;  // toward the polygon
  const double dc = m.dot(c.x - rim_[1][0]), de = m.dot(e.x - rim_[1][0]);
  // Only a piece that goes on beyond the line (not one along it: a blade lying in the tissue,
  // clipped at the blade's end); from c on the line (a vertex or spring the blade stopped at), c.
  if (!(de < -0.5 * settings_.band_mm)) return e;
  const double lambda = dc <= 0.0 ? 0.0 : std::clamp(dc / (dc - de), 0.0, 1.0);
  const Vec3 x = c.x + lambda * (e.x - c.x);
  const Surface& s = surface_;
  const auto tv = s.triangle_vertices(tri);
  std::array<double, 3> w;
  if (!barycentric(x, s.position(tv[0]), s.position(tv[1]), s.position(tv[2]), w)) return e;
  Spot b = make_spot(tri, {std::max(w[0], 0.0), std::max(w[1], 0.0), std::max(w[2], 0.0)});
  b.rim = e.rim;
  return b;
}

void Cutter::set_pending(CrackTip& tip, const Spot& c) {
  tip.pending = anchor_of(c);
  tip.has_pending = true;
}

Cutter::Walk Cutter::walk(CrackTip& tip, Spot c, bool fresh, CutResult& r) {
  Spot back;
  bool has_back = false;
  Vec3 last_commit = Vec3::Constant(INFINITY);
  bool jumped = false;
  const Surface& s = surface_;
  for (std::uint32_t step = 0; step < kMaxWalkSteps; ++step) {
    const Spot* bk = has_back ? &back : nullptr;
    std::uint32_t tri = kNone;
    Spot e;
    if (!next_piece(tip, c, bk, tri, e)) {
      if (!has_back) return fresh ? Walk::kEnded : Walk::kStuck;  // nothing goes on from here
      if (on_boundary(c) && !(tip.origin_inserted && c.kind == Spot::kVertex && c.vertex == tip.origin.index)) {
        commit(tip, c, r, true);  // the cut reached the tissue's boundary
        return Walk::kEnded;
      }
      set_pending(tip, c);  // the cut stops here (the blade's last pose passes through c)
      return Walk::kGoesOn;
    }
    // The cut passing its own tip: it meets the tip's cut (a spring at the tip, now a boundary)
    // within snapping distance of the tip. It goes on from the tip, on the other side.
    if (tip.origin_inserted && e.kind == Spot::kEdge && s.edge_triangles(e.edge)[1] == kNone && !jumped) {
      const auto ev = s.edge_vertices(e.edge);
      const double near = std::max(settings_.min_piece_mm, settings_.band_mm);
      if ((ev[0] == tip.origin.index || ev[1] == tip.origin.index) && (s.position(tip.origin.index) - e.x).norm() <= near) {
        jumped = true;
        back = c;
        has_back = true;
        std::uint32_t any = kNone;
        s.for_each_triangle_of(tip.origin.index, [&](std::uint32_t t, std::uint32_t) {
          if (any == kNone) any = t;
        });
        c = vertex_spot(tip.origin.index, any);
        continue;
      }
    }
    jumped = false;
    if (along_boundary(tri, c, e, tip.origin_inserted ? tip.origin.index : kNone)) {
      // The blade runs along the tissue's edge (back along its own cut, sawing): nothing is cut
      // there; the crack ends where it met it.
      if (fresh && (!tip.origin_inserted || (c.kind == Spot::kVertex && c.vertex == tip.origin.index))) return Walk::kEnded;
      commit(tip, c, r, true);
      return Walk::kEnded;
    }
    const bool leaves_star = !in_star(tip, tri);
    const bool bends = !leaves_star && !chord_accepts(tip, e);
    if (bends && turned_back(tip, e)) {  // the crack ends where the blade turned; a new one may start there
      commit(tip, c, r, true);
      return Walk::kEnded;
    }
    if (leaves_star || bends) {
      // c is inserted and becomes the tip: the cut leaves the triangles around the tip there, or
      // the chord from the tip to e would pass too far from where the blade went.
      if ((c.x - last_commit).norm() <= 1e-12) {  // nothing changed since the last time: give up here
        ++r.gaps;
        set_pending(tip, c);
        return Walk::kGoesOn;
      }
      last_commit = c.x;
      walked_[tri] = stamp_;
      const std::uint32_t before = tip.origin_inserted ? tip.origin.index : kNone;
      commit(tip, c, r, false);
      if (bends && tip.origin.index != before && c.kind == Spot::kInside) ++r.bends;
      c = in_origin_star(tip, c);
      continue;
    }
    walked_[tri] = stamp_;
    note_sample(tip, e);
    if (e.rim != 0) {  // where the piece leaves the polygon
      if (e.rim & kRimTrailing) {  // where the blade now is: the crack goes on from here next sweep
        set_pending(tip, blade_point(tri, c, e));
        return Walk::kGoesOn;
      }
      commit(tip, e, r, true);  // the blade's end left the tissue, or a pivot: the cut ends here
      return Walk::kEnded;
    }
    if (e.kind == Spot::kVertex) vertex_[e.vertex].walked = stamp_;
    back = c;
    has_back = true;
    c = e;
  }
  ++r.gaps;
  set_pending(tip, c);
  return Walk::kGoesOn;
}

// Whether the piece c → e in triangle tri runs along one of its boundary springs: both ends within
// snapping distance of it, and the piece long enough to tell and within 20° of it.
bool Cutter::along_boundary(std::uint32_t tri, const Spot& c, const Spot& e, std::uint32_t origin) {
  const Surface& s = surface_;
  // Judged on the plane's whole segment across the triangle (a sweep's piece may be a few µm).
  Vec3 u = c.x, v = e.x;
  {
    const auto tv = s.triangle_vertices(tri);
    std::array<Vec3, 3> p{};
    int n = 0;
    for (std::size_t k = 0; k < 3 && n < 2; ++k) {
      const std::size_t j = (k + 1) % 3;
      const double dk = side(tv[k]), dj = side(tv[j]);
      if (std::abs(dk) <= kOnPlane) {
        p[static_cast<std::size_t>(n++)] = s.position(tv[k]);
      } else if (std::abs(dj) > kOnPlane && dk * dj < 0.0) {
        const double t = dk / (dk - dj);
        p[static_cast<std::size_t>(n++)] = (1.0 - t) * s.position(tv[k]) + t * s.position(tv[j]);
      }
    }
    if (n == 2) {
      u = p[0];
      v = p[1];
    }
  }
  const Vec3 d = v - u;
  const double len = d.norm();
  for (const auto f : s.triangle_edges(tri)) {
    if (s.edge_triangles(f)[1] != kNone) continue;
    const auto [a, b] = s.edge_vertices(f);
    if (a == origin || b == origin) continue;  // the crack's own cut, just behind its tip
    // Within twice the snapping distance: an earlier cut lies that far off the path it followed.
    const double near = std::max(settings_.min_piece_mm, 2.0 * settings_.snap_fraction * s.edge_rest_length(f));
    if (len < 2.0 * near) continue;
    const Vec3 &xa = s.position(a), &xb = s.position(b);
    if (topology::distance_to_segment(u, xa, xb) > near || topology::distance_to_segment(v, xa, xb) > near) continue;
    const Vec3 fd = xb - xa;
    if (std::abs(d.dot(fd)) >= std::cos(20.0 * std::numbers::pi / 180.0) * len * fd.norm()) return true;
  }
  return false;
}

// ---- Sweeps ------------------------------------------------------------------------------------

Cutter::Spot Cutter::tip_spot(const CrackTip& tip) const {
  if (tip.has_pending) return spot_of(tip.pending);
  if (!tip.origin_inserted) return spot_of(tip.origin_point);
  std::uint32_t tri = kNone;
  surface_.for_each_triangle_of(tip.origin.index, [&](std::uint32_t t, std::uint32_t) {
    if (tri == kNone) tri = t;
  });
  return vertex_spot(tip.origin.index, tri);
}

Vec3 Cutter::tip_position(const CrackTip& tip) const { return tip_spot(tip).x; }

CrackTip Cutter::new_tip(const Spot& at) const {
  CrackTip tip;
  if (at.kind == Spot::kVertex) {
    tip.origin_inserted = true;
    tip.origin = surface_.vertex_id(at.vertex);
    tip.origin_rest = surface_.rest_position(at.vertex);
  } else {
    tip.origin_inserted = false;
    tip.origin_point = anchor_of(at);
    tip.origin_rest = tip.origin_point.rest;
  }
  return tip;
}

// Marks what a live crack tip holds (the triangles around its origin and its blade point): a
// start found there is the tip's own (the blade at its first pose passes through the tip's point).
void Cutter::hold(const CrackTip& tip) {
  const Surface& s = surface_;
  if (tip.origin_inserted) {
    vertex_[tip.origin.index].walked = stamp_;
    s.for_each_triangle_of(tip.origin.index, [&](std::uint32_t t, std::uint32_t) { held_[t] = stamp_; });
  } else {
    held_[tip.origin_point.triangle.index] = stamp_;
  }
  if (tip.has_pending) held_[tip.pending.triangle.index] = stamp_;
}

bool Cutter::taken(const Spot& at) const {
  // Its triangle changed since the scan: a walk passed there (and inserted what it crossed).
  if (!surface_.triangle_alive(at.tri) || surface_.triangle_id(at.tri).generation != at.generation) return true;
  if (at.kind == Spot::kVertex) return vertex_[at.vertex].walked == stamp_ || walked_[at.tri] == stamp_;
  // Where the polygon enters the tissue across a boundary spring, a crack starts unless a walk
  // ended there: a crack tip's triangles may lie on both sides of its own cut, and a path that
  // crosses that cut goes on beyond it.
  const bool boundary = at.kind == Spot::kEdge && surface_.edge_triangles(at.edge)[1] == kNone;
  if (walked_[at.tri] == stamp_ || (!boundary && held_[at.tri] == stamp_)) return true;
  if (boundary) {
    // Where the polygon passes through a crack tip (its plane through the blade's point there),
    // the tip's own cut crosses it right at the tip: that is the tip, not a crack of its own.
    for (const auto v : surface_.edge_vertices(at.edge)) {
      const double near = std::max(settings_.min_piece_mm, settings_.band_mm);
      if (vertex_[v].walked == stamp_ && (surface_.position(v) - at.x).norm() <= near) return true;
    }
  }
  if (at.kind == Spot::kEdge) {
    for (auto t : surface_.edge_triangles(at.edge)) {
      if (t != kNone && (walked_[t] == stamp_ || (!boundary && held_[t] == stamp_))) return true;
    }
  }
  return false;
}

bool Cutter::reanchor(CrackTip& tip) {
  Surface& s = surface_;
  auto current = [&](const TissuePoint& p) {
    return s.triangle_alive(p.triangle.index) && s.triangle_id(p.triangle.index) == p.triangle;
  };
  auto around_of = [&](const TissuePoint& p, std::array<std::uint32_t, 4>& around) {
    for (std::size_t k = 0; k < 3; ++k) around[k] = s.is_current(p.corners[k]) ? p.corners[k].index : kNone;
  };
  // A tip that cannot go on from its origin starts again where the blade is.
  auto restart_at_pending = [&]() {
    if (!tip.has_pending) return false;
    tip.origin_inserted = false;
    tip.origin_point = tip.pending;
    tip.origin_rest = tip.pending.rest;
    tip.has_pending = false;
    reset_chord(tip);
    return true;
  };
  std::array<std::uint32_t, 4> around{kNone, kNone, kNone, kNone};
  if (!tip.origin_inserted) {
    if (!current(tip.origin_point)) {
      around_of(tip.origin_point, around);
      TissuePoint found;
      if (!locate(tip.origin_point, around, found) && !locate_near(tip.origin_point, found)) return false;
      tip.origin_point = found;
    }
  } else if (!s.is_current(tip.origin)) {
    // The cleanup merged the tip away: a live vertex at its rest position among the blade point's
    // corners takes its place.
    std::uint32_t found = kNone;
    if (tip.has_pending) {
      for (const auto& c : tip.pending.corners) {
        if (s.is_current(c) && (s.rest_position(c.index) - tip.origin_rest).norm() <= 1e-9) found = c.index;
      }
    }
    if (found == kNone) {
      if (!restart_at_pending()) return false;
      return reanchor(tip);
    }
    tip.origin = s.vertex_id(found);
  }
  if (!tip.has_pending) return true;
  if (current(tip.pending) && in_star(tip, tip.pending.triangle.index)) return true;
  around_of(tip.pending, around);
  around[3] = tip.origin_inserted ? tip.origin.index : kNone;
  TissuePoint found;
  if (!locate(tip.pending, around, found, &tip) && !locate_near(tip.pending, found)) {
    if (!current(tip.pending)) return false;
    found = tip.pending;
  }
  tip.pending = found;
  if (in_star(tip, found.triangle.index)) return true;
  // The origin may have been given a copy (its fans separated): the blade point's triangle has it.
  if (tip.origin_inserted) {
    for (const auto& c : found.corners) {
      if ((s.rest_position(c.index) - tip.origin_rest).norm() <= 1e-9) {
        tip.origin = c;
        return true;
      }
    }
  }
  return restart_at_pending();
}

// Whether a crack's walk stopped at p this sweep (its blade point lies within the band of it). The
// walk's last piece and p can lie in different triangles round the vertex the blade is passing (its
// plane running along a row of springs), so `taken` does not see it; without this a second crack
// started there, and the two met further on (core/tissue/MEASUREMENTS.md, 2026-11-28).
bool Cutter::at_crack_point(const Incision& inc, const Spot& p) const {
  const Surface& s = surface_;
  for (std::uint32_t i = 0; i < inc.ntips_; ++i) {
    const CrackTip& t = inc.tips_[i];
    if (!t.has_pending || !s.triangle_alive(t.pending.triangle.index) || s.triangle_id(t.pending.triangle.index) != t.pending.triangle) {
      continue;
    }
    if ((spot_of(t.pending).x - p.x).norm() <= settings_.band_mm) return true;
  }
  return false;
}

void Cutter::reanchor_tips(Incision& inc, CutResult& r) {
  std::uint32_t kept = 0;
  for (std::uint32_t i = 0; i < inc.ntips_; ++i) {
    CrackTip& tip = inc.tips_[i];
    const bool had_origin = tip.origin_inserted;
    if (!reanchor(tip)) {
      ++r.gaps;
      continue;
    }
    if (had_origin && !tip.origin_inserted) ++r.gaps;  // restarted at the blade point: the piece from the old origin is lost
    inc.tips_[kept++] = tip;
  }
  inc.ntips_ = kept;
}

CutResult Cutter::advance(Incision& inc, const BladeEdge& to) {
  CutResult r;
  if (!is_finite(to.a_mm) || !is_finite(to.b_mm)) {
    r.status = Status::error("incision: non-finite blade pose");
    return r;
  }
  if ((to.b_mm - to.a_mm).norm() < settings_.min_blade_length_mm) {
    r.status = Status::error("incision: degenerate blade (cutting edge shorter than min_blade_length_mm)");
    return r;
  }
  auto record_pose = [&] {
    inc.pose_ = to;
    inc.has_pose_ = true;
    inc.pose_anchored_ = inc.ntips_ > 0;
    if (inc.pose_anchored_) inc.pose_anchor_ = tip_position(inc.tips_[0]);
  };
  if (!inc.has_pose_) {
    record_pose();
    return r;
  }
  reanchor_tips(inc, r);
  // The blade's previous pose, carried with the tissue under the first crack tip since then (the
  // solver moved it): the sweep starts where the blade was in the tissue.
  BladeEdge from = inc.pose_;
  if (inc.pose_anchored_ && inc.ntips_ > 0) {
    const Vec3 shift = tip_position(inc.tips_[0]) - inc.pose_anchor_;
    from.a_mm += shift;
    from.b_mm += shift;
  }
  const Vec3 &p0 = from.a_mm, &q0 = from.b_mm, &p1 = to.a_mm, &q1 = to.b_mm;
  const Vec3 n0 = (q0 - p0).cross(q1 - p0), n1 = (q1 - p0).cross(p1 - p0);
  const double area = 0.5 * (n0.norm() + n1.norm());
  if (!(area > settings_.min_swept_area_mm2)) {  // at rest, or moved along its own edge: nothing swept
    record_pose();
    return r;
  }
  // An edge that turned out of the plane of its two poses sweeps a twisted quad: cut it as two
  // planar sweeps, pivoting about p0 to (p0, q1) and then about q1.
  const BladeEdge mid{p0, q1};
  const bool twisted = n0.norm() > 1e-14 && n1.norm() > 1e-14 &&
                       std::abs(n0.normalized().dot(p1 - p0)) > 0.25 * settings_.band_mm &&
                       (q1 - p0).norm() >= settings_.min_blade_length_mm;
  if (twisted) {
    sweep_once(inc, from, mid, r);
    if (r.status) sweep_once(inc, mid, to, r);
  } else {
    sweep_once(inc, from, to, r);
  }
  if (r.status) record_pose();
  return r;
}

void Cutter::sweep_once(Incision& inc, const BladeEdge& from, const BladeEdge& to, CutResult& r) {
  Surface& s = surface_;
  if (!set_swept(from, to)) return;
  ++stamp_;
  on_cut_.clear();
  to_open_.clear();
  gather_candidates();
  gather_edges();
  find_starts();
  // Each crossing or vertex on the cut: a split and a copy; each crack: its two ends and a bend or two.
  const std::uint32_t k = count_crossings() + 2 * static_cast<std::uint32_t>(starts_.size() + trailing_.size() + inc.ntips_) + 2;
  if (!s.has_room(3 * k, 6 * k, 3 * k)) {
    r.status = Status::error("cut: pools full (raise the surface capacity)");
    return;
  }
  if (inc.ntips_ == 0 && starts_.empty() && trailing_.empty()) return;  // the blade missed the tissue
  for (std::uint32_t i = 0; i < inc.ntips_; ++i) hold(inc.tips_[i]);
  {
    const Surface::EditBatch batch(s);
    std::uint32_t kept = 0;
    for (std::uint32_t i = 0; i < inc.ntips_; ++i) {
      CrackTip tip = inc.tips_[i];
      Walk w = walk(tip, tip_spot(tip), false, r);
      if (w == Walk::kStuck) {
        // Nothing goes on from the blade's point of the last sweep (the tissue moved under the
        // blade, or the blade turned at a corner of the mesh): where the blade's first pose
        // passes through the triangles around the tip, the crack goes on from there.
        for (const Start& st : starts_) {
          if (st.priority != 0 || !s.triangle_alive(st.at.tri) || s.triangle_id(st.at.tri).generation != st.at.generation ||
              !in_star(tip, st.at.tri)) {
            continue;
          }
          w = walk(tip, st.at, false, r);
          if (w != Walk::kStuck) break;
        }
      }
      if (w != Walk::kEnded) inc.tips_[kept++] = tip;
    }
    inc.ntips_ = kept;
    for (const Start& st : starts_) {
      if (taken(st.at)) continue;
      // A start at a vertex is found in each of its triangles: one crack.
      walked_[st.at.tri] = stamp_;
      if (st.at.kind == Spot::kVertex) vertex_[st.at.vertex].walked = stamp_;
      CrackTip tip = new_tip(st.at);
      if (walk(tip, st.at, true, r) != Walk::kGoesOn) continue;
      if (inc.ntips_ < Incision::kMaxCrackTips) {
        inc.tips_[inc.ntips_++] = tip;
      } else {
        ++r.gaps;
      }
    }
    // Where the blade now is in the tissue but no walk led (the tissue moved onto it): a crack starts.
    for (const Spot& p : trailing_) {
      if (taken(p) || at_crack_point(inc, p)) continue;
      if (inc.ntips_ >= Incision::kMaxCrackTips) {
        ++r.gaps;
        continue;
      }
      const CrackTip tip = new_tip(p);
      hold(tip);
      inc.tips_[inc.ntips_++] = tip;
    }
    open_cut(r, std::span<CrackTip>(inc.tips_.data(), inc.ntips_));
  }
  clean(r);
  reanchor_tips(inc, r);
}

CutResult Cutter::finish(Incision& inc) {
  CutResult r;
  Surface& s = surface_;
  reanchor_tips(inc, r);
  if (inc.ntips_ > 0) {
    const std::uint32_t k = 4 * inc.ntips_ + 4;
    if (!s.has_room(3 * k, 6 * k, 3 * k)) {
      r.status = Status::error("cut: pools full (raise the surface capacity)");
      return r;
    }
    ++stamp_;
    on_cut_.clear();
    to_open_.clear();
    {
      const Surface::EditBatch batch(s);
      for (std::uint32_t i = 0; i < inc.ntips_; ++i) {
        CrackTip& tip = inc.tips_[i];
        if (tip.has_pending) commit(tip, spot_of(tip.pending), r, true);
        if (tip.deferred_inserted && to_open_.size() < to_open_.capacity()) to_open_.push_back(tip.deferred);
        tip.deferred_inserted = false;
      }
      open_cut(r, {});
    }
    clean(r);
  }
  inc.ntips_ = 0;
  inc.has_pose_ = false;
  inc.pose_anchored_ = false;
  return r;
}

}  // namespace vitreo::core
