#pragma once
// Synthetic measurements for the calibration tests: a seeded generator, Gaussian noise and random
// rotations, so every test states its injected truth and noise and nothing else.
#include <cmath>
#include <numbers>
#include <random>

#include "core/common/types.hpp"

namespace vitreo::rig::calibration::testing {

inline constexpr double kNoiseMm = 0.05;  // the issue's: 0.05 mm (1 σ per axis)

struct Synth {
  std::mt19937_64 rng{12345};
  double gauss(double sigma) { return std::normal_distribution<double>(0.0, sigma)(rng); }
  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }
  core::Vec3 noise(double sigma) { return {gauss(sigma), gauss(sigma), gauss(sigma)}; }
  // A rotation whose +z lies within `half_angle_deg` of `axis`, with a random twist.
  core::Quat in_cone(const core::Vec3& axis, double half_angle_deg) {
    const double tilt = std::sqrt(uniform(0.0, 1.0)) * half_angle_deg * std::numbers::pi / 180.0;
    const double azimuth = uniform(0.0, 2.0 * std::numbers::pi);
    const double twist = uniform(-std::numbers::pi, std::numbers::pi);
    const core::Quat to_axis = core::Quat::FromTwoVectors(core::Vec3::UnitZ(), axis.normalized());
    const core::Vec3 tilt_axis(std::cos(azimuth), std::sin(azimuth), 0.0);
    return (to_axis * Eigen::AngleAxisd(tilt, tilt_axis) * Eigen::AngleAxisd(twist, core::Vec3::UnitZ())).normalized();
  }
};

inline double deg(double radians) { return radians * 180.0 / std::numbers::pi; }

}  // namespace vitreo::rig::calibration::testing
