#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace vitreo::core {

using Vec3 = Eigen::Vector3d;
using Vec2 = Eigen::Vector2d;
using Quat = Eigen::Quaterniond;

}  // namespace vitreo::core
