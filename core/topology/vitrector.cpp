#include "core/topology/vitrector.hpp"

#include <algorithm>
#include <cmath>

#include "core/common/prefault.hpp"
#include "core/common/validate.hpp"

namespace vitreo::core {

void VitrectorSettings::validate() const {
  require_range(suction_pa, 0.0, 1e5, "vitrector: suction_pa");
  require_range(field_radius_mm, 0.01, 20.0, "vitrector: field_radius_mm");
  require_range(removal_radius_mm, 0.005, field_radius_mm, "vitrector: removal_radius_mm");
  require_range(gel_flow_mm3_per_s, 0.0, 1e4, "vitrector: gel_flow_mm3_per_s");
  require_range(max_cut_rate_cpm, 0.0, 1e5, "vitrector: max_cut_rate_cpm");
  require_range(cut_rate_cpm, 0.0, max_cut_rate_cpm, "vitrector: cut_rate_cpm");
  require_range(leaving_damping_per_s, 0.0, 1e4, "vitrector: leaving_damping_per_s");
  require_range(snap_fraction, 0.0, 0.25, "vitrector: snap_fraction");
  require_range(min_piece_mm, 0.0, 1.0, "vitrector: min_piece_mm");
  quality.validate();
}

Vitrector::Vitrector(Surface& surface, VitrectorSettings settings, RemovalModel model)
    : surface_(surface), settings_(settings), index_(surface), quality_(surface, settings.quality), model_(model) {
  settings_.validate();
  const std::size_t nv = surface.vertex_capacity(), ne = surface.edge_capacity();
  reserve_touched(samples_, nv);
  reserve_touched(inside_, nv);
  stamp_.assign(nv, 0);
  phi_.assign(nv, 0.0);
  reserve_touched(triangles_, ne);
  tri_stamp_.assign(ne, 0);
  reserve_touched(crossings_, ne);
  reserve_touched(candidates_, ne);
}

Status Vitrector::set_pose(const Vec3& port, const Vec3& direction) {
  if (!is_finite(port) || !is_finite(direction) || !(direction.norm() > 1e-12)) {
    return Status::error("vitrector: non-finite pose or zero suction direction");
  }
  port_ = port;
  dir_ = direction.normalized();
  posed_ = true;
  return Status::ok();
}

Status Vitrector::set_cut_rate(double cpm) {
  if (!std::isfinite(cpm) || cpm < 0.0 || cpm > settings_.max_cut_rate_cpm) {
    return Status::error("vitrector: cut rate must be finite and in [0, max_cut_rate_cpm]");
  }
  cut_rate_cpm_ = cpm;
  return Status::ok();
}

Status Vitrector::set_vacuum(double vacuum) {
  if (!std::isfinite(vacuum) || vacuum < 0.0 || vacuum > 1.0) return Status::error("vitrector: vacuum must be finite and in [0, 1]");
  vacuum_ = vacuum;
  return Status::ok();
}

double Vitrector::region(const Vec3& x) const {
  const Vec3 d = x - port_;
  return std::max(d.norm() - settings_.removal_radius_mm, -d.dot(dir_));
}

VitrectorStepResult Vitrector::apply(double dt) {
  VitrectorStepResult r;
  if (!std::isfinite(dt) || !(dt > 0.0) || dt > 0.02) {
    r.status = Status::error("vitrector: dt must be finite and in (0, 0.02] s");
    return r;
  }
  if (!posed_) {
    r.status = Status::error("vitrector: no pose set");
    return r;
  }
  Surface& s = surface_;
  const double R = settings_.field_radius_mm;
  const double k_leave = settings_.leaving_damping_per_s;
  samples_.clear();
  index_.for_each_in_box(Vec3(port_.array() - R), Vec3(port_.array() + R), [&](std::uint32_t v) {
    if (s.is_fixed(v)) return;
    const Vec3 d = s.position(v) - port_;
    const double dist2 = d.squaredNorm();
    if (dist2 >= R * R) return;
    const double dist = std::sqrt(dist2);
    const double along = d.dot(dir_);
    if (along <= 0.0 || !(dist > 1e-9)) return;  // behind the port, or at its centre
    if (!(s.mass(v) > 0.0)) return;
    const Vec3 toward = -d / dist;
    // Leaving the field: an opposing (implicit) damping of the outward speed. Every vertex in the
    // field gets a sample, damped or not: applying it wakes the vertex. (The zero carries the
    // direction's signs, as the removed attraction term's did, so recorded sessions replay bit for bit.)
    Vec3 a = toward * 0.0;
    const double outward = -s.velocity(v).dot(toward);
    if (outward > 0.0 && k_leave > 0.0) a += toward * (outward * k_leave / (1.0 + dt * k_leave));
    samples_.push_back({v, a});
  });
  r.in_field = static_cast<std::uint32_t>(samples_.size());
  if (k_leave > 0.0) r.status = apply_external_accelerations(s, samples_, dt);
  if (!r.status) return r;
  // The guillotine: cut_rate cuts per minute, each removing what has entered the port.
  if (cut_rate_cpm_ > 0.0) {
    cut_phase_ += dt * cut_rate_cpm_ / 60.0;
    if (cut_phase_ >= 1.0) {
      cut_phase_ -= std::floor(cut_phase_);
      if (model_ == RemovalModel::kAspirate) {
        aspirate(r, 60.0 / cut_rate_cpm_);
      } else {
        remove(r);
      }
    }
  }
  return r;
}

VitrectorStepResult Vitrector::cut_now() {
  VitrectorStepResult r;
  if (!posed_) {
    r.status = Status::error("vitrector: no pose set");
    return r;
  }
  if (model_ == RemovalModel::kAspirate) {
    aspirate(r, cut_rate_cpm_ > 0.0 ? 60.0 / cut_rate_cpm_ : 0.0);
  } else {
    remove(r);
  }
  return r;
}

void Vitrector::aspirate(VitrectorStepResult& r, double since_last_cut_s) {
  r.cut = true;
  Surface& s = surface_;
  const double field = std::max(settings_.field_radius_mm * vacuum_, settings_.removal_radius_mm);
  const double thickness = s.material().thickness_mm;
  ++round_;
  candidates_.clear();
  index_.for_each_in_box(Vec3(port_.array() - field), Vec3(port_.array() + field), [&](std::uint32_t v) {
    s.for_each_triangle_of(v, [&](std::uint32_t t, std::uint32_t) {
      if (tri_stamp_[t] == round_) return;
      tri_stamp_[t] = round_;
      const auto tv = s.triangle_vertices(t);
      const Vec3 d = (s.position(tv[0]) + s.position(tv[1]) + s.position(tv[2])) / 3.0 - port_;
      // In the field's hemisphere, whose flat side the port's opening (removal radius) reaches
      // around: a coarse shell curving away behind the port's plane is still drawn in.
      if (d.squaredNorm() > field * field || d.dot(dir_) < -settings_.removal_radius_mm) return;
      candidates_.push_back({d.squaredNorm(), t});
    });
  });
  if (candidates_.empty()) {
    aspirated_mm3_ = 0.0;  // no gel at the port: it draws fluid
    return;
  }
  // Room for the fans the removal may separate: at most one copy per corner.
  if (!s.has_room(3 * static_cast<std::uint32_t>(candidates_.size()) + 3, 0, 0)) {
    r.status = Status::error("vitrector: pools full (raise the surface capacity)");
    return;
  }
  aspirated_mm3_ += settings_.gel_flow_mm3_per_s * vacuum_ * since_last_cut_s;
  std::sort(candidates_.begin(), candidates_.end(), [](const Candidate& a, const Candidate& b) {
    return a.distance2 < b.distance2 || (a.distance2 == b.distance2 && a.triangle < b.triangle);
  });
  inside_.clear();
  for (const Candidate& c : candidates_) {
    if (!s.triangle_alive(c.triangle)) continue;
    const double volume = s.triangle_rest_area(c.triangle) * thickness;
    if (volume > aspirated_mm3_) break;  // nearest first: the next bite pays for it
    const auto tv = s.triangle_vertices(c.triangle);
    const auto removed = s.remove_triangle(s.triangle_id(c.triangle), false);
    if (!removed.status) continue;
    aspirated_mm3_ -= volume;
    ++r.triangles_removed;
    r.vertices_removed += removed.vertices_removed;
    r.removed_area_mm2 += removed.removed_area_mm2;
    r.removed_mass_g += removed.removed_mass_g;
    for (auto v : tv) {
      if (s.vertex_alive(v) && stamp_[v] != round_) {
        stamp_[v] = round_;
        inside_.push_back(v);
      }
    }
  }
  finish_removal(r);
}

void Vitrector::remove(VitrectorStepResult& r) {
  r.cut = true;
  Surface& s = surface_;
  const double rr = settings_.removal_radius_mm, snap = settings_.snap_fraction;
  ++round_;
  inside_.clear();
  // Vertices inside (or on) the removal hemisphere; their region value is kept in phi_.
  index_.for_each_in_box(Vec3(port_.array() - rr), Vec3(port_.array() + rr), [&](std::uint32_t v) {
    const Vec3 d = s.position(v) - port_;
    if (d.squaredNorm() > rr * rr) return;
    const double phi = region(s.position(v));
    if (phi > 0.0) return;
    stamp_[v] = round_;
    phi_[v] = phi;
    inside_.push_back(v);
  });
  if (inside_.empty()) return;
  auto phi_of = [&](std::uint32_t v) { return stamp_[v] == round_ ? phi_[v] : region(s.position(v)); };
  auto gather = [&] {
    triangles_.clear();
    for (auto v : inside_) {
      if (!s.vertex_alive(v)) continue;
      s.for_each_triangle_of(v, [&](std::uint32_t t, std::uint32_t) {
        if (tri_stamp_[t] == round_) return;
        tri_stamp_[t] = round_;
        triangles_.push_back(t);
      });
    }
  };
  // Clip: split springs crossing the boundary where they cross it.
  gather();
  crossings_.clear();
  for (auto t : triangles_) {
    const auto tv = s.triangle_vertices(t);
    for (std::uint32_t k = 0; k < 3; ++k) {
      const std::uint32_t e = s.triangle_edges(t)[k];
      const auto [a, b] = s.edge_vertices(e);
      // Visit each spring once: from the triangle that lists it first.
      if (s.edge_triangles(e)[0] != t) continue;
      (void)tv;
      const double fa = phi_of(a), fb = phi_of(b);
      if ((fa <= 0.0) == (fb <= 0.0)) continue;
      // Bisection for the crossing (the region function is not smooth at the hemisphere's rim).
      const Vec3 xa = s.position(a), xb = s.position(b);
      double lo = 0.0, hi = 1.0;
      const bool a_in = fa <= 0.0;
      for (int it = 0; it < 40; ++it) {
        const double mid = 0.5 * (lo + hi);
        const bool in = region(xa + mid * (xb - xa)) <= 0.0;
        if (in == a_in) {
          lo = mid;
        } else {
          hi = mid;
        }
      }
      const double t_cross = 0.5 * (lo + hi);
      const std::uint32_t outside_v = a_in ? b : a;
      const std::uint32_t inside_v = a_in ? a : b;
      const double t_out = a_in ? 1.0 - t_cross : t_cross;  // distance fraction to the outside end
      const double len = s.edge_rest_length(e);  // the floor on pieces is in the rest shape
      if (t_out < snap || t_out * len < settings_.min_piece_mm) {
        // The outside end is within the tolerance: it joins the removed region.
        if (stamp_[outside_v] != round_) inside_.push_back(outside_v);
        stamp_[outside_v] = round_;
        phi_[outside_v] = 0.0;
        continue;
      }
      if (1.0 - t_out < snap || (1.0 - t_out) * len < settings_.min_piece_mm) {
        phi_[inside_v] = 0.0;  // the inside end is on the boundary already
        continue;
      }
      crossings_.push_back({s.edge_id(e), t_cross});
    }
  }
  if (!s.has_room(static_cast<std::uint32_t>(2 * crossings_.size() + inside_.size()) + 3, 3 * static_cast<std::uint32_t>(crossings_.size()),
                  2 * static_cast<std::uint32_t>(crossings_.size()))) {
    r.status = Status::error("vitrector: pools full (raise the surface capacity)");
    return;
  }
  for (const auto& c : crossings_) {
    if (!s.is_current(c.edge)) continue;
    const auto [a, b] = s.edge_vertices(c.edge.index);
    auto in = [&](std::uint32_t v) { return stamp_[v] == round_; };
    auto on = [&](std::uint32_t v) { return in(v) && phi_[v] == 0.0; };
    if (in(a) == in(b) || on(a) || on(b)) continue;  // an end was snapped onto the boundary since
    const auto split = s.split_edge(c.edge, c.t);
    if (!split.status) continue;
    ++r.springs_split;
    stamp_[split.vertex] = round_;
    phi_[split.vertex] = 0.0;
    inside_.push_back(split.vertex);
  }
  // Remove the triangles lying inside (all corners inside or on the boundary, centroid inside).
  ++round_;
  // Keep the inside marks: re-stamp them for the new round.
  for (auto v : inside_) {
    if (s.vertex_alive(v)) stamp_[v] = round_;
  }
  gather();
  for (auto t : triangles_) {
    if (!s.triangle_alive(t)) continue;
    const auto tv = s.triangle_vertices(t);
    bool all_in = true;
    for (auto v : tv) all_in = all_in && stamp_[v] == round_;
    if (!all_in) continue;
    const Vec3 centroid = (s.position(tv[0]) + s.position(tv[1]) + s.position(tv[2])) / 3.0;
    if (region(centroid) > 0.0) continue;
    const auto removed = s.remove_triangle(s.triangle_id(t), false);
    if (!removed.status) continue;
    ++r.triangles_removed;
    r.vertices_removed += removed.vertices_removed;
    r.removed_area_mm2 += removed.removed_area_mm2;
    r.removed_mass_g += removed.removed_mass_g;
  }
  finish_removal(r);
}

void Vitrector::finish_removal(VitrectorStepResult& r) {
  Surface& s = surface_;
  // Bow-ties left by the removal: one vertex per fan (pools were checked for this above).
  const std::size_t n_inside = inside_.size();
  for (std::size_t i = 0; i < n_inside; ++i) {
    const std::uint32_t v = inside_[i];
    if (s.vertex_alive(v)) s.separate_vertex_fans(s.vertex_id(v), &inside_);  // copies join the list
  }
  // What is left of the inside vertices is the new boundary: every changed triangle touches it.
  const QualityResult q = quality_.clean_around(inside_);
  r.collapsed = q.collapses;
  r.unresolved = q.unresolved;
  r.removed_mass_g += q.removed_mass_g;  // lone sliver fragments left by the clipping
  removed_mass_g_ += r.removed_mass_g;
}

}  // namespace vitreo::core
