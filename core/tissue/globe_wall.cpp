#include "core/tissue/globe_wall.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/common/validate.hpp"

namespace vitreo::core {

GlobeWall GlobeWall::sphere(const Vec3& center, double radius_mm) {
  require_finite(center, "globe wall centre");
  require_positive(radius_mm, "globe wall radius");
  GlobeWall w;
  w.center_ = center;
  w.radius_by_cos_.assign(kTableSize, radius_mm);
  w.min_radius_ = radius_mm;
  w.spherical_ = true;
  return w;
}

GlobeWall GlobeWall::from_profile(const Vec3& center, const std::vector<ProfilePoint>& profile) {
  require_finite(center, "globe wall centre");
  if (profile.size() < 2) throw InvalidArgument("globe wall profile needs at least two points");
  // Polar coordinates of the profile about the centre, in the meridional plane.
  std::vector<std::pair<double, double>> polar;  // (cos θ from +z, radius)
  for (const auto& p : profile) {
    require_finite(p.z_mm, "globe wall profile z");
    require_non_negative(p.rho_mm, "globe wall profile rho");
    const double dz = p.z_mm - center.z();
    const double r = std::hypot(dz, p.rho_mm);
    if (!(r > 1e-6)) throw InvalidArgument("globe wall profile passes through the centre");
    polar.emplace_back(dz / r, r);
  }
  std::sort(polar.begin(), polar.end());
  for (std::size_t i = 1; i < polar.size(); ++i) {
    if (polar[i].first - polar[i - 1].first < 1e-12) {
      throw InvalidArgument("globe wall profile is not star-shaped about the centre (two radii at one angle)");
    }
  }
  if (polar.front().first > -1.0 + 1e-6 || polar.back().first < 1.0 - 1e-6) {
    throw InvalidArgument("globe wall profile must run from pole to pole (rho = 0 at both ends)");
  }
  GlobeWall w;
  w.center_ = center;
  w.radius_by_cos_.resize(kTableSize);
  // Interpolate linearly in θ between profile points (the profile is a polyline in the plane, and
  // for a fine profile linear-in-θ radius is within its own discretisation error).
  std::size_t j = 0;
  for (int i = 0; i < kTableSize; ++i) {
    const double c = std::clamp(-1.0 + 2.0 * i / (kTableSize - 1), -1.0, 1.0);
    while (j + 2 < polar.size() && polar[j + 1].first < c) ++j;
    const double t0 = std::acos(std::clamp(polar[j].first, -1.0, 1.0));
    const double t1 = std::acos(std::clamp(polar[j + 1].first, -1.0, 1.0));
    const double t = std::acos(c);
    const double u = std::abs(t1 - t0) > 1e-15 ? std::clamp((t - t0) / (t1 - t0), 0.0, 1.0) : 0.0;
    w.radius_by_cos_[static_cast<std::size_t>(i)] = polar[j].second + u * (polar[j + 1].second - polar[j].second);
  }
  w.min_radius_ = *std::min_element(w.radius_by_cos_.begin(), w.radius_by_cos_.end());
  return w;
}

double GlobeWall::radius_toward(const Vec3& d) const {
  return radius_toward(d, d.norm());
}

double GlobeWall::clearance(const Vec3& p) const {
  const Vec3 d = p - center_;
  return radius_toward(d) - d.norm();
}

}  // namespace vitreo::core
