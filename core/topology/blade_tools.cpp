#include "core/topology/blade_tools.hpp"

#include <cmath>

#include "core/common/validate.hpp"

namespace vitreo::core {

SidewaysBlade::SidewaysBlade(Cutter& cutter, double edge_length_mm, double stroke_length_mm)
    : incision_(cutter), edge_length_mm_(edge_length_mm), stroke_length_mm_(stroke_length_mm) {
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
  if (has_last_ && (cur_tip_ - last_tip_).norm() < stroke_length_mm_) return r;
  r = incision_.advance(edge_at(cur_tip_, cur_dir_));
  if (r.status) {
    has_last_ = true;
    last_tip_ = cur_tip_;
  }
  return r;
}

CutResult SidewaysBlade::end_stroke() {
  CutResult r;
  if (!has_last_) return r;
  if ((cur_tip_ - last_tip_).norm() > 0.0) r = incision_.advance(edge_at(cur_tip_, cur_dir_));
  r.add(incision_.end());
  has_last_ = false;
  return r;
}

CutResult SidewaysBlade::lift() {
  has_last_ = false;
  return incision_.end();
}

Scissors::Scissors(Cutter& cutter, double blade_length_mm) : upper_(cutter), lower_(cutter), blade_length_mm_(blade_length_mm) {
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
  const double half = 0.5 * opening;
  const bool closing = has_last_ && opening < last_opening_ - 1e-9;
  if (!closing) {
    // Opening, or moved without closing: what was cut stays cut; a new cut starts at this pose.
    r.add(upper_.end());
    r.add(lower_.end());
  }
  r.add(upper_.advance_pivot(pivot, tip(half)));
  r.add(lower_.advance_pivot(pivot, tip(-half)));
  if (opening <= 1e-9) {  // the blades have met: the cut between them is complete
    r.add(upper_.end());
    r.add(lower_.end());
  }
  has_last_ = true;
  last_opening_ = opening;
  return r;
}

Status Scissors::set_blade_length(double blade_length_mm) {
  if (!(blade_length_mm >= 1e-2 && blade_length_mm <= 20.0)) return Status::error("scissors: blade_length_mm outside [0.01, 20]");
  blade_length_mm_ = blade_length_mm;
  return Status::ok();
}

CutResult Scissors::release() {
  CutResult r = upper_.end();
  r.add(lower_.end());
  has_last_ = false;
  return r;
}

}  // namespace vitreo::core
