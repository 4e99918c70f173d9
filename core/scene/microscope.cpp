#include "core/scene/microscope.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/anatomy/eye_model.hpp"
#include "core/common/status.hpp"

namespace vitreo::core {

namespace {

void require(bool ok, const char* field, const char* why) {
  if (!ok) throw InvalidArgument(std::string("microscope: ") + field + " " + why);
}

// Moves `value` toward `target` by at most `step` (no overshoot).
double approach(double value, double target, double step) {
  if (value < target) return std::min(value + step, target);
  return std::max(value - step, target);
}

}  // namespace

void MicroscopeSettings::validate() const {
  require(std::isfinite(zoom_min) && zoom_min > 0.0, "zoom_min", "must be > 0");
  require(std::isfinite(zoom_max) && zoom_max >= zoom_min, "zoom_max", "must be >= zoom_min");
  require(std::isfinite(zoom_rate_per_s) && zoom_rate_per_s > 0.0, "zoom_rate_per_s", "must be > 0");
  require(std::isfinite(focus_range_mm) && focus_range_mm >= 0.0, "focus_range_mm", "must be >= 0");
  require(std::isfinite(focus_speed_mm_s) && focus_speed_mm_s > 0.0, "focus_speed_mm_s", "must be > 0");
  require(std::isfinite(pan_speed_mm_s) && pan_speed_mm_s > 0.0, "pan_speed_mm_s", "must be > 0");
  require(std::isfinite(pan_travel_mm) && pan_travel_mm > 0.0, "pan_travel_mm", "must be > 0");
  require(std::isfinite(field_deg) && field_deg > 0.0 && field_deg < 170.0, "field_deg", "must be in (0, 170)");
  require(std::isfinite(wide_field_deg) && wide_field_deg > 0.0 && wide_field_deg < 170.0, "wide_field_deg",
          "must be in (0, 170)");
  require(std::isfinite(numerical_aperture) && numerical_aperture > 0.0 && numerical_aperture < 1.0, "numerical_aperture",
          "must be in (0, 1)");
  require(std::isfinite(magnification_at_zoom_1) && magnification_at_zoom_1 > 0.0, "magnification_at_zoom_1", "must be > 0");
}

double depth_of_field_mm(const MicroscopeSettings& s, double zoom, bool wide_angle) {
  // Berek (1927), as microscope makers quote it for visual observation (e.g. Leica Microsystems,
  // "How sharp images are formed"): T = n·[λ/(2·NA²) + 340 µm/(NA·M_total)].
  constexpr double kWavelength_mm = 0.55e-3;  // white light
  constexpr double kVitreousIndex = 1.336;    // the vitreous cavity (gel or balanced salt solution)
  const double na = s.numerical_aperture;
  const double m_total = s.magnification_at_zoom_1 * zoom;
  const double in_air = kWavelength_mm / (2.0 * na * na) + 0.34 / (na * m_total);
  constexpr double kHalfDegRad = 3.14159265358979323846 / 360.0;
  const double lateral = wide_angle ? std::tan(s.field_deg * kHalfDegRad) / std::tan(s.wide_field_deg * kHalfDegRad) : 1.0;
  return kVitreousIndex * in_air / (lateral * lateral);
}

double MicroscopeView::field_radius(const Vec3& p) const {
  const Vec3 d = p - eye_point_mm;
  const double along = d.dot(axis);
  if (!(along > 0.0)) return std::numeric_limits<double>::infinity();
  return (d - along * axis).norm() / along / half_tan;
}

Microscope::Microscope(const MicroscopeSettings& settings, const Vec2& region_of_interest_mm, bool wide_angle)
    : settings_(settings), wide_angle_(wide_angle) {
  settings_.validate();
  roi_ = region_of_interest_mm.allFinite() ? region_of_interest_mm : Vec2::Zero();
  const double r = roi_.norm();
  if (r > settings_.pan_travel_mm) roi_ *= settings_.pan_travel_mm / r;
  center_ = center_target_ = roi_;
  zoom_ = zoom_target_ = settings_.zoom_min;
}

void Microscope::set_zoom(double zoom) {
  if (std::isfinite(zoom)) zoom_target_ = std::clamp(zoom, settings_.zoom_min, settings_.zoom_max);
}

void Microscope::set_focus(double focus_mm) {
  const double half = 0.5 * settings_.focus_range_mm;
  if (std::isfinite(focus_mm)) focus_target_ = std::clamp(focus_mm, -half, half);
}

void Microscope::pan_to(const Vec2& offset_mm) {
  if (!offset_mm.allFinite()) return;
  Vec2 c = roi_ + offset_mm;
  const double r = c.norm();
  if (r > settings_.pan_travel_mm) c *= settings_.pan_travel_mm / r;
  center_target_ = c;
}

void Microscope::step(double dt_s, const MicroscopeInput& input) {
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) return;
  // Zoom in log-magnification, so a doubling takes the same time at any magnification.
  const double lz = std::log(zoom_), lt = std::log(zoom_target_);
  const double zoom_step = settings_.zoom_rate_per_s * dt_s;
  zoom_ = std::abs(lt - lz) <= zoom_step ? zoom_target_ : std::exp(lz + (lt > lz ? zoom_step : -zoom_step));
  focus_ = approach(focus_, focus_target_, settings_.focus_speed_mm_s * dt_s);
  // The joystick moves the X–Y target (a held joystick keeps the head moving); the head follows at
  // the same speed limit, so a commanded move and a joystick move look alike.
  const double speed = settings_.pan_speed_mm_s / zoom_;
  if (input.pan.allFinite()) {
    const Vec2 p(std::clamp(input.pan.x(), -1.0, 1.0), std::clamp(input.pan.y(), -1.0, 1.0));
    if (p.squaredNorm() > 0.0) pan_to(center_ + speed * dt_s * p - roi_);
  }
  const Vec2 d = center_target_ - center_;
  const double dist = d.norm(), reach = speed * dt_s;
  center_ = dist <= reach ? center_target_ : Vec2(center_ + d * (reach / dist));
}

namespace {

// The wall point under a fundus-plane point (EyeModel::fundus_coords inverted on the wall).
Vec3 wall_at_fundus(const EyeModel& eye, const Vec2& f) {
  const double s = std::min(f.norm(), eye.fundus_extent_mm);
  return eye.wall_point(eye.polar_at_arc(s), std::atan2(f.y(), f.x()));
}

}  // namespace

MicroscopeView Microscope::view(const EyeModel& eye) const {
  MicroscopeView v;
  const EyeParameters& a = eye.parameters;
  v.eye_point_mm = Vec3(0.0, 0.0, eye.lens_center_z_mm - 0.5 * a.lens_thickness_mm - 0.5);  // just behind the lens
  const Vec3 wall = wall_at_fundus(eye, center_);
  v.target_mm = wall - a.retina_thickness_mm * wall.normalized();
  const Vec3 to_target = v.target_mm - v.eye_point_mm;
  const double distance = to_target.norm();
  v.axis = distance > 0.0 ? Vec3(to_target / distance) : Vec3(-Vec3::UnitZ());
  constexpr double kEps = 0.05;
  Vec3 up = wall_at_fundus(eye, center_ + Vec2(0.0, kEps)) - wall_at_fundus(eye, center_ - Vec2(0.0, kEps));
  up -= up.dot(v.axis) * v.axis;
  v.up = up.norm() > 1e-9 ? Vec3(up.normalized()) : Vec3(Vec3::UnitY());
  constexpr double kHalfDegRad = 3.14159265358979323846 / 360.0;
  v.half_tan = std::tan((wide_angle_ ? settings_.wide_field_deg : settings_.field_deg) * kHalfDegRad) / zoom_;
  v.focal_distance_mm = std::max(distance - focus_, 1.0);  // focus: + toward the microscope
  v.depth_of_field_mm = depth_of_field_mm();
  return v;
}

double Microscope::field_deg() const { return (wide_angle_ ? settings_.wide_field_deg : settings_.field_deg) / zoom_; }

void Microscope::hash_into(StateHasher& h) const {
  h.add_double(center_.x());
  h.add_double(center_.y());
  h.add_double(center_target_.x());
  h.add_double(center_target_.y());
  h.add_double(zoom_);
  h.add_double(zoom_target_);
  h.add_double(focus_);
  h.add_double(focus_target_);
  h.add_u64((wide_angle_ ? 1u : 0u) | (reinverter_ ? 2u : 0u));
}

}  // namespace vitreo::core
