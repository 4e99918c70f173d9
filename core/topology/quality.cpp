#include "core/topology/quality.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "core/common/prefault.hpp"
#include "core/common/validate.hpp"

namespace vitreo::core {

double QualitySettings::min_area_mm2() const {
  return 0.5 * min_spring_mm * min_spring_mm * std::sin(min_angle_deg * std::numbers::pi / 180.0);
}

void QualitySettings::validate() const {
  require_range(min_spring_mm, 0.0, 1.0, "quality: min_spring_mm");
  require_range(min_angle_deg, 0.0, 20.0, "quality: min_angle_deg");
  if (max_passes < 1 || max_passes > 64) throw InvalidArgument("quality: max_passes must be in [1, 64]");
}

namespace {

double sin2_of_degrees(double deg) {
  const double s = std::sin(deg * std::numbers::pi / 180.0);
  return s * s;
}

// is_poor_triangle with the angle limit as sin² (0: no angle limit), computed once by the caller.
bool poor_triangle(const Surface& s, std::uint32_t t, double min_spring_mm, double min_angle_sin2) {
  const auto tv = s.triangle_vertices(t);
  const auto te = s.triangle_edges(t);
  std::array<Vec3, 3> d;  // d[k]: from corner k to corner k + 1 (rest vectors)
  for (std::uint32_t k = 0; k < 3; ++k) {
    if (s.edge_rest_length(te[k]) < min_spring_mm) return true;
    d[k] = s.edge_vertices(te[k])[0] == tv[k] ? s.edge_rest_vector(te[k]) : Vec3(-s.edge_rest_vector(te[k]));
  }
  if (!(min_angle_sin2 > 0.0)) return false;
  // Angle at corner k between d[k] and −d[k−1] below θ ⇔ acute with sin² below sin²θ (no atan2:
  // this runs on every triangle around a cut).
  const double sin2 = min_angle_sin2;
  for (std::uint32_t k = 0; k < 3; ++k) {
    const Vec3& u = d[k];
    const Vec3 w = -d[(k + 2) % 3];
    const double dot = u.dot(w);
    if (dot > 0.0 && u.cross(w).squaredNorm() < sin2 * u.squaredNorm() * w.squaredNorm()) return true;
  }
  return false;
}

}  // namespace

bool is_poor_triangle(const Surface& s, std::uint32_t t, const QualitySettings& q) {
  return poor_triangle(s, t, q.min_spring_mm, q.min_angle_deg > 0.0 ? sin2_of_degrees(q.min_angle_deg) : 0.0);
}

MeshQuality::MeshQuality(Surface& surface, QualitySettings settings) : surface_(surface), settings_(settings) {
  settings_.validate();
  min_angle_sin2_ = settings_.min_angle_deg > 0.0 ? sin2_of_degrees(settings_.min_angle_deg) : 0.0;
  reserve_touched(work_, surface.vertex_capacity());
  reserve_touched(next_, surface.vertex_capacity());
  reserve_touched(seeds_, surface.vertex_capacity());
  tri_stamp_.assign(surface.edge_capacity(), 0);  // triangle capacity is below the spring capacity
}

bool MeshQuality::try_fix(std::uint32_t t) {
  Surface& s = surface_;
  const auto te = s.triangle_edges(t);
  std::array<std::uint32_t, 3> order{te[0], te[1], te[2]};
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    const double la = s.edge_rest_length(a), lb = s.edge_rest_length(b);
    return la != lb ? la < lb : a < b;
  });
  const double limit = settings_.min_angle_deg * std::numbers::pi / 180.0;
  // A collapse must not make another poor triangle (that would chain through the mesh).
  const double min_result = limit;
  auto rank = [&](std::uint32_t v) {
    if (s.is_fixed(v) || s.extra_mass(v) > 0.0) return 2;
    return s.is_boundary_vertex(v) ? 1 : 0;
  };
  for (auto e : order) {
    const auto [a, b] = s.edge_vertices(e);
    const int ra = rank(a), rb = rank(b);
    // The more constrained end stays; on a tie, the lower slot first, then the other.
    std::array<std::uint32_t, 2> keeps{a, b};
    if (rb > ra || (rb == ra && b < a)) keeps = {b, a};
    const int tries = ra == rb ? 2 : 1;
    for (int i = 0; i < tries; ++i) {
      const std::uint32_t keep = keeps[static_cast<std::size_t>(i)];
      // A spring below the minimum between two boundary vertices is a neck narrower than it:
      // the surface parts there (Surface::collapse_edge, allow_pinch).
      const bool neck = s.edge_rest_length(e) < settings_.min_spring_mm;
      const auto r = s.collapse_edge(s.edge_id(e), keep, min_result, neck, settings_.min_spring_mm);
      if (r.status) {
        ++result_.collapses;
        if (next_.size() < next_.capacity()) next_.push_back(keep);
        return true;
      }
    }
  }
  // A cap (an apex lying almost on the opposite, longest spring, every spring long enough to
  // keep): split the longest spring at the apex's foot and collapse the short spring that makes
  // from the foot to the apex — an edge flip built from the two primitives, which keeps the rest
  // vectors (vector addition) and the mass exact.
  const std::uint32_t longest = order[2];
  const auto tv = s.triangle_vertices(t);
  const auto [la, lb] = s.edge_vertices(longest);
  std::uint32_t apex = kNone;
  for (auto v : tv) {
    if (v != la && v != lb) apex = v;
  }
  const std::uint32_t e_a_apex = s.find_edge(la, apex);
  if (apex == kNone || e_a_apex == kNone) return false;
  const Vec3 ab = s.edge_rest_vector(longest);  // from la to lb
  const Vec3 a_apex = s.edge_vertices(e_a_apex)[0] == la ? s.edge_rest_vector(e_a_apex) : Vec3(-s.edge_rest_vector(e_a_apex));
  const double foot = a_apex.dot(ab) / ab.squaredNorm();
  // Only where the flip is an improvement: the two triangles it makes (with the vertex x across
  // the longest spring) must both be above the limit, or flips could undo each other.
  bool flip_ok = false;
  const auto lt = s.edge_triangles(longest);
  const std::uint32_t across_longest = lt[0] == t ? lt[1] : lt[0];
  if (across_longest != kNone) {
    std::uint32_t x = kNone;
    for (auto v : s.triangle_vertices(across_longest)) {
      if (v != la && v != lb) x = v;
    }
    const std::uint32_t e_ax = x == kNone ? kNone : s.find_edge(la, x);
    if (e_ax != kNone && s.find_edge(apex, x) == kNone) {
      const Vec3 a_x = s.edge_vertices(e_ax)[0] == la ? s.edge_rest_vector(e_ax) : Vec3(-s.edge_rest_vector(e_ax));
      auto angle_ok = [&](const Vec3& p, const Vec3& q, const Vec3& r) {
        const Vec3 d0 = q - p, d1 = r - q, d2 = p - r;
        auto ang = [](const Vec3& u, const Vec3& w) { return std::atan2(u.cross(w).norm(), u.dot(w)); };
        return std::min({ang(d0, -d2), ang(d1, -d0), ang(d2, -d1)}) >= limit;
      };
      const Vec3 zero = Vec3::Zero();
      flip_ok = angle_ok(zero, a_apex, a_x) && angle_ok(a_apex, ab, a_x);
    }
  }
  // A needle (a spring below the minimum that no collapse could remove) is no cap: flipping it
  // only moves the short spring on, flip after flip, until the passes run out (seen 2026-11-25 on
  // a sheet pulled out of shape, where every collapse would flip a triangle in the current shape);
  // it goes to the last resort.
  const bool needle = s.edge_rest_length(order[0]) < settings_.min_spring_mm;
  if (!needle && flip_ok && foot > 0.05 && foot < 0.95 && budget_ > 0 && s.has_room(1, 4, 2)) {
    --budget_;
    const auto split = s.split_edge(s.edge_id(longest), foot);
    if (split.status) {
      const std::uint32_t m = split.vertex, spoke = s.find_edge(m, apex);
      if (spoke != kNone) {
        const bool neck = s.edge_rest_length(spoke) < settings_.min_spring_mm;
        if (s.collapse_edge(s.edge_id(spoke), apex, limit, neck, settings_.min_spring_mm).status) {
          ++result_.collapses;
          if (next_.size() < next_.capacity()) next_.push_back(apex);
          return true;
        }
      }
      // The split stays (a valid mesh; the sliver is now two, with a shorter spring between
      // them, which the next attempt collapses or dissolves).
      if (next_.size() < next_.capacity()) next_.push_back(m);
      return true;
    }
  }
  // Last resort: merge the sliver into the neighbour across its longest spring (or another one).
  std::uint32_t receiver = kNone;
  for (auto e : order) {
    const auto et = s.edge_triangles(e);
    const std::uint32_t across = et[0] == t ? et[1] : et[0];
    if (across != kNone) receiver = across;  // the last assigned is across the longest
  }
  if (receiver == kNone) {
    // A fragment of one sliver triangle, joined to nothing: it is removed as material, its mass
    // reported (removed_mass_g), unless a corner is anchored.
    const auto tv2 = s.triangle_vertices(t);
    for (auto v : tv2) {
      if (s.is_fixed(v)) return false;
    }
    const auto removed = s.remove_triangle(s.triangle_id(t), true);
    if (!removed.status) return false;
    result_.removed_mass_g += removed.removed_mass_g;
    ++result_.fragments_removed;
    return true;
  }
  if (!s.dissolve_triangle(s.triangle_id(t), s.triangle_id(receiver))) return false;
  ++result_.dissolved;
  for (auto v : tv) {
    if (next_.size() < next_.capacity() && s.vertex_alive(v)) next_.push_back(v);
  }
  return true;
}

QualityResult MeshQuality::clean_around(std::span<const std::uint32_t> vertices) {
  Surface& s = surface_;
  result_ = {};
  work_.clear();
  for (auto v : vertices) {
    if (work_.size() < work_.capacity()) work_.push_back(v);
  }
  // Every fix removes a vertex or a triangle (so they cannot go on for ever), or splits a cap once
  // (a flip, which removes nothing): the budget bounds those, so a call always ends. It bounded
  // every attempt before 2026-11-25, and a cascade of collapses through a shredded sheet (42 from
  // one tear) could spend it and leave a sliver the next attempt would have collapsed.
  budget_ = 4 * static_cast<std::uint64_t>(work_.size()) + 64;
  std::uint32_t unresolved_in_pass = 0;
  bool pending = false;  // the last pass changed the mesh: work_ holds where to look again
  for (std::uint32_t pass = 0; pass < settings_.max_passes && !work_.empty(); ++pass) {
    ++round_;
    next_.clear();
    unresolved_in_pass = 0;
    bool progress_in_pass = false;
    for (std::size_t i = 0; i < work_.size(); ++i) {
      const std::uint32_t v = work_[i];
      if (!s.vertex_alive(v)) continue;
      // The fan changes when a collapse succeeds: restart the walk over v's triangles then.
      while (s.vertex_alive(v)) {
        std::uint32_t poor = kNone;
        s.for_each_triangle_of(v, [&](std::uint32_t t, std::uint32_t) {
          if (poor != kNone || tri_stamp_[t] == round_) return;
          if (poor_triangle(s, t, settings_.min_spring_mm, min_angle_sin2_)) {
            poor = t;
          } else {
            tri_stamp_[t] = round_;  // checked and fine in this pass
          }
        });
        if (poor == kNone) break;
        if (!try_fix(poor)) {
          tri_stamp_[poor] = round_;
          ++unresolved_in_pass;
          // Try again next pass: a fix next to it may make it fixable.
          for (auto u : s.triangle_vertices(poor)) {
            if (next_.size() < next_.capacity()) next_.push_back(u);
          }
        } else {
          progress_in_pass = true;
        }
      }
    }
    pending = progress_in_pass;
    if (!progress_in_pass) break;  // nothing changed: another pass would find the same
    work_.swap(next_);
  }
  if (pending) {
    // Out of passes with fixes still under way: what is poor where the next pass would have
    // looked is left as it is, and said so.
    ++round_;
    for (const std::uint32_t v : work_) {
      if (!s.vertex_alive(v)) continue;
      s.for_each_triangle_of(v, [&](std::uint32_t t, std::uint32_t) {
        if (tri_stamp_[t] == round_) return;
        tri_stamp_[t] = round_;
        if (poor_triangle(s, t, settings_.min_spring_mm, min_angle_sin2_)) ++unresolved_in_pass;
      });
    }
  }
  result_.unresolved = unresolved_in_pass;
  total_removed_mass_g_ += result_.removed_mass_g;
  return result_;
}

QualityResult MeshQuality::clean_all() {
  Surface& s = surface_;
  next_.clear();
  std::vector<std::uint32_t> all;
  all.reserve(s.vertex_slots());
  for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) {
    if (s.vertex_alive(v)) all.push_back(v);
  }
  return clean_around(all);
}

}  // namespace vitreo::core
