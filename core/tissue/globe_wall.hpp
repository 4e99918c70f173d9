#pragma once
// The inner wall of the globe (the choroid), which tissue cannot cross.
//
// The thesis kept tissue inside a bounding sphere around the choroid; since the choroid is not a
// sphere, the retina poked through anteriorly (ch. 2.3.2). We use the wall's exact shape instead: the
// globe is star-shaped about its centre, so the wall is a radius R(θ) for each polar angle θ from the
// +z (anterior) axis, tabulated finely from the anatomical profile and interpolated in cos θ, which
// costs a square root and a table lookup per vertex.
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "core/common/types.hpp"
#include "core/geometry/revolved_mesh.hpp"

namespace vitreo::core {

class GlobeWall {
 public:
  // A spherical wall (tests, simple exercises).
  static GlobeWall sphere(const Vec3& center_mm, double radius_mm);
  // The wall traced by a meridional profile (z, rho) about the z axis through `center`, which must
  // be star-shaped as seen from the centre. Throws InvalidArgument otherwise.
  static GlobeWall from_profile(const Vec3& center_mm, const std::vector<ProfilePoint>& profile);

  const Vec3& center() const { return center_; }
  // Wall radius in the direction d (need not be normalised, must be non-zero).
  double radius_toward(const Vec3& d) const;
  // The same when |d| is already known (n = d.norm()).
  double radius_toward(const Vec3& d, double n) const {
    return spherical_ ? min_radius_ : radius_at_cos(n > 0.0 ? d.z() / n : 1.0);
  }
  // Signed distance along the ray from the centre: > 0 inside the wall.
  double clearance(const Vec3& p) const;
  // Moves p back onto the wall (minus `offset_mm`) along the ray from the centre if it lies beyond.
  // Returns true if p was moved.
  bool project_inside(Vec3& p, double offset_mm) const {  // inline: called per vertex and substep
    const Vec3 d = p - center_;
    const double n = std::sqrt(d.squaredNorm());
    if (!(n > 0.0)) return false;
    // Well inside (the interpolated radius is never below the smallest tabulated one): no lookup.
    if (n < min_radius_ - offset_mm) return false;
    const double limit = (spherical_ ? min_radius_ : radius_at_cos(d.z() / n)) - offset_mm;
    if (n <= limit) return false;
    p = center_ + d * (limit / n);
    return true;
  }

 private:
  static constexpr int kTableSize = 2049;
  // Inline: called per vertex and substep (the wall's contact and projection), where a call costs
  // as much as the lookup.
  double radius_at_cos(double c) const {
    const double s = (std::clamp(c, -1.0, 1.0) + 1.0) * 0.5 * (kTableSize - 1);
    const int i = std::min(static_cast<int>(s), kTableSize - 2);
    const double f = s - i;
    return radius_by_cos_[static_cast<std::size_t>(i)] * (1.0 - f) + radius_by_cos_[static_cast<std::size_t>(i) + 1] * f;
  }

  Vec3 center_ = Vec3::Zero();
  std::vector<double> radius_by_cos_;  // index i ↔ cos θ = -1 + 2i/(kTableSize-1)
  double min_radius_ = 0.0;            // smallest table radius: nothing nearer the centre is outside
  bool spherical_ = false;             // every radius is min_radius_ (no lookup needed)
};

}  // namespace vitreo::core
