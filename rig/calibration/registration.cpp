#include "rig/calibration/registration.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <cmath>
#include <sstream>

namespace vitreo::rig::calibration {

namespace {
std::string fmt(double v) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(3);
  s << v;
  return s.str();
}
Eigen::Matrix3Xd as_matrix(const std::vector<core::Vec3>& pts) {
  Eigen::Matrix3Xd m(3, static_cast<Eigen::Index>(pts.size()));
  for (std::size_t i = 0; i < pts.size(); ++i) m.col(static_cast<Eigen::Index>(i)) = pts[i];
  return m;
}
}  // namespace

RegistrationResult register_points(const std::vector<core::Vec3>& in_rig, const std::vector<core::Vec3>& in_eye,
                                   const RegistrationLimits& limits) {
  RegistrationResult r;
  r.points = in_rig.size();
  if (in_rig.size() != in_eye.size()) {
    r.error = "touched " + std::to_string(in_rig.size()) + " fiducials but " + std::to_string(in_eye.size()) +
              " are defined";
    return r;
  }
  for (std::size_t i = 0; i < in_rig.size(); ++i) {
    if (!in_rig[i].allFinite() || !in_eye[i].allFinite()) {
      r.error = "fiducial " + std::to_string(i + 1) + " is not a finite point";
      return r;
    }
  }
  const std::size_t need = std::max<std::size_t>(limits.min_points, 3);
  if (in_rig.size() < need) {
    r.error = "too few fiducials: " + std::to_string(in_rig.size()) + " (need at least " + std::to_string(need) + ")";
    return r;
  }
  const Eigen::Matrix3Xd src = as_matrix(in_rig), dst = as_matrix(in_eye);
  // Collinear (or coincident) points leave the rotation about their line free. Both sets are
  // checked: the known fiducials could be defined badly, and the touches could all land in one spot.
  for (const Eigen::Matrix3Xd* m : {&src, &dst}) {
    const Eigen::Matrix3Xd centred = m->colwise() - m->rowwise().mean();
    const Eigen::JacobiSVD<Eigen::Matrix3Xd> svd(centred);
    const double second_extent = svd.singularValues()(1) / std::sqrt(static_cast<double>(m->cols()));
    if (second_extent < limits.min_extent_mm) {
      r.error = std::string("the ") + (m == &src ? "touched" : "defined") +
                " fiducials lie (nearly) on a line: their spread across it is " + fmt(second_extent) +
                " mm (need " + fmt(limits.min_extent_mm) + " mm); touch points around the eye";
      return r;
    }
  }
  // Dynamic-size copies: GCC 12's -Warray-bounds misreads Eigen's AVX loads inside umeyama on
  // 3×N fixed-row matrices (a false positive that -Werror turns into a build failure).
  const Eigen::MatrixXd t = Eigen::umeyama(Eigen::MatrixXd(src), Eigen::MatrixXd(dst), /*with_scaling=*/false);
  r.rig_to_eye.rotation = core::Quat(Eigen::Matrix3d(t.topLeftCorner(3, 3))).normalized();
  r.rig_to_eye.translation_mm = t.topRightCorner(3, 1);
  double sum_sq = 0.0;
  for (std::size_t i = 0; i < in_rig.size(); ++i) {
    const double e = (r.rig_to_eye.apply(in_rig[i]) - in_eye[i]).norm();
    r.residuals_mm.push_back(e);
    sum_sq += e * e;
  }
  r.fre_mm = std::sqrt(sum_sq / static_cast<double>(in_rig.size()));
  if (!(r.fre_mm <= limits.max_fre_mm)) {
    r.error = "fiducial registration error " + fmt(r.fre_mm) + " mm is above the " + fmt(limits.max_fre_mm) +
              " mm limit: a fiducial was touched in the wrong place or in the wrong order";
    return r;
  }
  r.ok = true;
  return r;
}

double target_registration_error(const RigidTransform& rig_to_eye, const std::vector<core::Vec3>& targets_rig,
                                 const std::vector<core::Vec3>& targets_eye) {
  if (targets_rig.empty() || targets_rig.size() != targets_eye.size()) return std::nan("");
  double sum_sq = 0.0;
  for (std::size_t i = 0; i < targets_rig.size(); ++i)
    sum_sq += (rig_to_eye.apply(targets_rig[i]) - targets_eye[i]).squaredNorm();
  return std::sqrt(sum_sq / static_cast<double>(targets_rig.size()));
}

double fle_from_fre(double fre_mm, std::size_t n) {
  if (n <= 2) return std::nan("");
  return fre_mm / std::sqrt(1.0 - 2.0 / static_cast<double>(n));
}

double predicted_tre_mm(const std::vector<core::Vec3>& fiducials_eye, double fle_mm, const core::Vec3& target_eye) {
  const std::size_t n = fiducials_eye.size();
  if (n < 3) return std::nan("");
  const Eigen::Matrix3Xd m = as_matrix(fiducials_eye);
  const core::Vec3 mean = m.rowwise().mean();
  const Eigen::Matrix3Xd c = m.colwise() - mean;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(c * c.transpose());
  const core::Vec3 target = target_eye - mean;
  double sum = 0.0;
  for (int k = 0; k < 3; ++k) {
    const core::Vec3 axis = eig.eigenvectors().col(k);
    // Mean squared distance of the fiducials from principal axis k, and the target's distance from it.
    double f2 = 0.0;
    for (Eigen::Index i = 0; i < c.cols(); ++i) f2 += (c.col(i) - c.col(i).dot(axis) * axis).squaredNorm();
    f2 /= static_cast<double>(n);
    const double d2 = (target - target.dot(axis) * axis).squaredNorm();
    sum += d2 / f2;
  }
  return std::sqrt(fle_mm * fle_mm / static_cast<double>(n) * (1.0 + sum / 3.0));
}

}  // namespace vitreo::rig::calibration
