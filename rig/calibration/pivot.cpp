#include "rig/calibration/pivot.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

namespace vitreo::rig::calibration {

namespace {
std::string fmt(double v, int digits) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(digits);
  s << v;
  return s.str();
}
}  // namespace

double pivot_spread_deg(const std::vector<PivotPose>& poses) {
  // O(n²) over unit axes is a few milliseconds for the thousands of poses a pivot takes; a cone
  // around the mean axis would understate a spread that is wide in one direction only.
  std::vector<core::Vec3> axes;
  axes.reserve(poses.size());
  for (const PivotPose& p : poses) axes.push_back(p.orientation.normalized() * core::Vec3::UnitZ());
  double min_dot = 1.0;
  for (std::size_t i = 0; i < axes.size(); ++i)
    for (std::size_t j = i + 1; j < axes.size(); ++j) min_dot = std::min(min_dot, axes[i].dot(axes[j]));
  return std::acos(std::clamp(min_dot, -1.0, 1.0)) * 180.0 / std::numbers::pi;
}

PivotResult calibrate_pivot(const std::vector<PivotPose>& poses, const PivotLimits& limits) {
  PivotResult r;
  r.poses = poses.size();
  for (const PivotPose& p : poses) {
    if (!p.position_mm.allFinite() || !p.orientation.coeffs().allFinite() ||
        std::abs(p.orientation.coeffs().norm() - 1.0) > 1e-3) {
      r.error = "a pose is not finite or its orientation is not a unit quaternion";
      return r;
    }
  }
  if (poses.size() < std::max<std::size_t>(limits.min_poses, 3)) {
    r.error = "too few poses: " + std::to_string(poses.size()) + " (need at least " +
              std::to_string(std::max<std::size_t>(limits.min_poses, 3)) + "); keep pivoting for longer";
    return r;
  }
  r.spread_deg = pivot_spread_deg(poses);
  if (r.spread_deg < limits.min_spread_deg) {
    r.error = "too little pivot spread: " + fmt(r.spread_deg, 1) + "° (need at least " + fmt(limits.min_spread_deg, 1) +
              "°); swing the handle wider about the tip";
    return r;
  }
  const Eigen::Index n = static_cast<Eigen::Index>(poses.size());
  Eigen::MatrixXd a(3 * n, 6);
  Eigen::VectorXd rhs(3 * n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const PivotPose& p = poses[static_cast<std::size_t>(i)];
    a.block<3, 3>(3 * i, 0) = p.orientation.normalized().toRotationMatrix();
    a.block<3, 3>(3 * i, 3) = -Eigen::Matrix3d::Identity();
    rhs.segment<3>(3 * i) = -p.position_mm;
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Eigen::VectorXd s = svd.singularValues();
  // Rotations about a single axis leave the offset along that axis (and the pivot along it) free:
  // the smallest singular value collapses. sqrt(n)·sin(spread/2) is the scale a real cone gives.
  if (s(5) < 1e-3 * s(0)) {
    r.error = "the poses turn about one axis only, so the tip's distance along it cannot be found; "
              "swing the handle in two directions (a cone), not just a fan or a twist";
    return r;
  }
  const Eigen::VectorXd x = svd.solve(rhs);
  r.tip_offset_mm = x.head<3>();
  r.pivot_mm = x.tail<3>();
  double sum_sq = 0.0;
  r.residuals_mm.reserve(poses.size());
  for (const PivotPose& p : poses) {
    const double e = (p.orientation.normalized() * r.tip_offset_mm + p.position_mm - r.pivot_mm).norm();
    r.residuals_mm.push_back(e);
    sum_sq += e * e;
    r.max_residual_mm = std::max(r.max_residual_mm, e);
  }
  r.rms_mm = std::sqrt(sum_sq / static_cast<double>(poses.size()));
  if (!(r.rms_mm <= limits.max_rms_mm)) {
    r.error = "pivot RMS " + fmt(r.rms_mm, 3) + " mm is above the " + fmt(limits.max_rms_mm, 3) +
              " mm limit: the tip slipped in the divot, or the instrument is bent; pivot again";
    return r;
  }
  r.ok = true;
  return r;
}

}  // namespace vitreo::rig::calibration
