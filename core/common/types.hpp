#pragma once
#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace vitreo::core {

using Vec3 = Eigen::Vector3d;
using Vec2 = Eigen::Vector2d;
using Quat = Eigen::Quaterniond;

// The angle between two vectors in radians, accurate near 0 and π (unlike acos of the dot product).
inline double angle_between(const Vec3& a, const Vec3& b) { return std::atan2(a.cross(b).norm(), a.dot(b)); }

}  // namespace vitreo::core
