#include "core/scene/microscope.hpp"

#include <algorithm>
#include <cmath>
#include <string>

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
