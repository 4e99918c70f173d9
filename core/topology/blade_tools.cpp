#include "core/topology/blade_tools.hpp"

#include <cmath>

#include "core/common/validate.hpp"

namespace vitreo::core {

SidewaysBlade::SidewaysBlade(Cutter& cutter, double edge_length_mm, double stroke_length_mm)
    : cutter_(cutter), edge_length_mm_(edge_length_mm), stroke_length_mm_(stroke_length_mm) {
  require_range(edge_length_mm, 1e-3, 10.0, "sideways blade: edge_length_mm");
  require_range(stroke_length_mm, 1e-3, 10.0, "sideways blade: stroke_length_mm");
}

BladeEdge SidewaysBlade::edge_at(const Vec3& tip, const Vec3& direction) const {
  return {tip, tip + edge_length_mm_ * direction};
}

CutResult SidewaysBlade::move_to(const Vec3& tip, const Vec3& direction) {
  CutResult r;
  if (!is_finite(tip) || !is_finite(direction) || !(direction.norm() > 1e-9)) {
    r.status = Status::error("sideways blade: non-finite pose or zero edge direction");
    return r;
  }
  cur_tip_ = tip;
  cur_dir_ = direction.normalized();
  if (!has_last_) {
    has_last_ = true;
    last_tip_ = cur_tip_;
    last_dir_ = cur_dir_;
    return r;
  }
  if ((cur_tip_ - last_tip_).norm() < stroke_length_mm_) return r;
  return end_stroke();
}

CutResult SidewaysBlade::end_stroke() {
  CutResult r;
  if (!has_last_ || (cur_tip_ - last_tip_).norm() < 1e-9) return r;
  r = cutter_.sweep(edge_at(last_tip_, last_dir_), edge_at(cur_tip_, cur_dir_));
  if (r.status) {
    last_tip_ = cur_tip_;
    last_dir_ = cur_dir_;
  }
  return r;
}

Scissors::Scissors(Cutter& cutter, double blade_length_mm) : cutter_(cutter), blade_length_mm_(blade_length_mm) {
  require_range(blade_length_mm, 1e-2, 20.0, "scissors: blade_length_mm");
}

CutResult Scissors::set_pose(const Vec3& pivot, const Vec3& bisector, const Vec3& plane_normal, double opening) {
  CutResult r;
  if (!is_finite(pivot) || !is_finite(bisector) || !is_finite(plane_normal) || !std::isfinite(opening) ||
      opening < 0.0 || opening > 3.0) {
    r.status = Status::error("scissors: non-finite pose or opening outside [0, 3] rad");
    return r;
  }
  const Vec3 n = plane_normal.normalized();
  const Vec3 u = (bisector - bisector.dot(n) * n);
  if (!(u.norm() > 1e-9) || !(plane_normal.norm() > 1e-9)) {
    r.status = Status::error("scissors: bisector must not be parallel to the plane normal");
    return r;
  }
  const Vec3 ux = u.normalized(), w = n.cross(ux);
  auto tip = [&](double angle) { return Vec3(pivot + blade_length_mm_ * (std::cos(angle) * ux + std::sin(angle) * w)); };
  if (has_last_ && opening < last_opening_ - 1e-9) {
    const double a0 = 0.5 * last_opening_, a1 = 0.5 * opening;
    r = cutter_.sweep_pivot(pivot, tip(a0), tip(a1));
    if (r.status) {
      const CutResult r2 = cutter_.sweep_pivot(pivot, tip(-a0), tip(-a1));
      if (!r2.status) return r2;
      r.end_points += r2.end_points;
      r.springs_split += r2.springs_split;
      r.springs_opened += r2.springs_opened;
      r.vertices_added += r2.vertices_added;
      r.snapped += r2.snapped;
      r.collapsed += r2.collapsed;
      r.unresolved += r2.unresolved;
      r.removed_mass_g += r2.removed_mass_g;
    }
  }
  has_last_ = true;
  last_opening_ = opening;
  return r;
}

}  // namespace vitreo::core
