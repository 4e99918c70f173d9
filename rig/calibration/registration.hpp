#pragma once
// Tracker-to-fixture registration: the technician touches fiducial points on the mock eye whose
// positions in the eye frame are known (machined into the fixture). With the calibrated tip, each
// touch gives the same point in the tracker (rig) frame; the rigid transform that best maps one set
// onto the other in the least-squares sense is Umeyama's closed form (S. Umeyama, "Least-squares
// estimation of transformation parameters between two point patterns", IEEE PAMI 13(4), 1991),
// which Eigen implements as Eigen::umeyama.
//
// Errors follow Fitzpatrick, West & Maurer ("Predicting error in rigid-body point-based
// registration", IEEE TMI 17(5), 1998): FRE is the RMS residual at the fiducials used; TRE is the
// error at points of interest that were NOT used — measured when the technician touches targets,
// and predicted from the fiducial configuration otherwise.
#include <string>
#include <vector>

#include "core/common/types.hpp"

namespace vitreo::rig::calibration {

struct RigidTransform {  // x_eye = rotation * x_rig + translation_mm
  core::Quat rotation = core::Quat::Identity();
  core::Vec3 translation_mm = core::Vec3::Zero();
  core::Vec3 apply(const core::Vec3& x) const { return rotation * x + translation_mm; }
};

struct RegistrationLimits {
  std::size_t min_points = 4;          // 3 determine a transform; a 4th makes FRE mean something
  double min_extent_mm = 2.0;          // the fiducials' second principal extent: not on a line
  double max_fre_mm = 0.2;
};

struct RegistrationResult {
  bool ok = false;
  std::string error;
  RigidTransform rig_to_eye;
  double fre_mm = 0.0;                 // RMS at the fiducials
  std::vector<double> residuals_mm;    // per fiducial
  std::size_t points = 0;
};

// `in_rig[i]` and `in_eye[i]` are the same fiducial, touched and known.
RegistrationResult register_points(const std::vector<core::Vec3>& in_rig, const std::vector<core::Vec3>& in_eye,
                                   const RegistrationLimits& limits = {});

// RMS distance between where the transform puts touched targets and where they really are.
double target_registration_error(const RigidTransform& rig_to_eye, const std::vector<core::Vec3>& targets_rig,
                                 const std::vector<core::Vec3>& targets_eye);

// Fitzpatrick et al.'s expected TRE at `target_eye` for fiducials `fiducials_eye` localised with
// RMS error fle_mm: TRE² ≈ FLE²/N · (1 + 1/3 Σ_k d_k²/f_k²), d_k the target's distance from the
// k-th principal axis of the fiducials, f_k the fiducials' RMS distance from it.
double predicted_tre_mm(const std::vector<core::Vec3>& fiducials_eye, double fle_mm, const core::Vec3& target_eye);

// FLE estimated from FRE for N fiducials: FRE² ≈ (1 - 2/N) FLE² (same paper).
double fle_from_fre(double fre_mm, std::size_t n);

}  // namespace vitreo::rig::calibration
