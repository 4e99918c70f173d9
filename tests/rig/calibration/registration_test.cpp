#include "rig/calibration/registration.hpp"

#include <gtest/gtest.h>

#include "tests/rig/calibration/synthetic.hpp"

namespace vitreo::rig::calibration {
namespace {

using testing::kNoiseMm;
using testing::Synth;

// The injected truth: where the eye sits in the rig.
RigidTransform true_rig_to_eye() {
  RigidTransform t;
  t.rotation = core::Quat(Eigen::AngleAxisd(0.6, core::Vec3(0.3, -0.5, 0.8).normalized()));
  t.translation_mm = core::Vec3(-95.0, 42.0, -380.0);
  return t;
}
core::Vec3 to_rig(const RigidTransform& t, const core::Vec3& eye) { return t.rotation.conjugate() * (eye - t.translation_mm); }

// Eight fiducials around the anterior globe (radius 12 mm) and the limbus ring, as a fixture would carry.
std::vector<core::Vec3> fiducials() {
  std::vector<core::Vec3> f;
  for (int k = 0; k < 6; ++k) {
    const double a = k * std::numbers::pi / 3.0;
    f.emplace_back(12.0 * std::cos(a) * 0.8, 12.0 * std::sin(a) * 0.8, 12.0 * 0.6);
  }
  f.emplace_back(0.0, 0.0, 12.0);
  f.emplace_back(13.0, 0.0, 0.0);
  return f;
}
// Targets a surgeon works at, never touched during registration: the posterior pole, the macula,
// the equator.
const std::vector<core::Vec3> kTargets = {{0.0, 0.0, -12.0}, {3.0, -1.0, -11.5}, {0.0, 12.0, 0.0}, {-8.0, 0.0, -8.0}};

TEST(Registration, RecoversInjectedTransformAndTargetsWithin0_2mm) {
  Synth s;
  const RigidTransform truth = true_rig_to_eye();
  std::vector<core::Vec3> touched;
  for (const core::Vec3& f : fiducials()) touched.push_back(to_rig(truth, f) + s.noise(kNoiseMm));
  const RegistrationResult r = register_points(touched, fiducials());
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_LT(testing::deg(r.rig_to_eye.rotation.angularDistance(truth.rotation)), 1.0);
  std::vector<core::Vec3> targets_rig;
  for (const core::Vec3& t : kTargets) targets_rig.push_back(to_rig(truth, t));
  const double tre = target_registration_error(r.rig_to_eye, targets_rig, kTargets);
  EXPECT_LT(tre, 0.2);
  // FRE of N points with σ per axis: E[FRE²] = (1 − 2/N)·3σ² (Fitzpatrick et al. 1998).
  EXPECT_NEAR(r.fre_mm, kNoiseMm * std::sqrt(3.0 * (1.0 - 2.0 / 8.0)), 0.03);
  EXPECT_EQ(r.residuals_mm.size(), 8u);
}

TEST(Registration, PredictedTreMatchesMonteCarlo) {
  // Independent check of predicted_tre_mm: 400 noisy registrations, the TRE at the posterior pole.
  Synth s;
  const RigidTransform truth = true_rig_to_eye();
  const core::Vec3 target = kTargets[0];
  double sum_sq = 0.0;
  const int trials = 400;
  for (int i = 0; i < trials; ++i) {
    std::vector<core::Vec3> touched;
    for (const core::Vec3& f : fiducials()) touched.push_back(to_rig(truth, f) + s.noise(kNoiseMm));
    const RegistrationResult r = register_points(touched, fiducials());
    ASSERT_TRUE(r.ok) << r.error;
    sum_sq += (r.rig_to_eye.apply(to_rig(truth, target)) - target).squaredNorm();
  }
  const double measured = std::sqrt(sum_sq / trials);
  const double predicted = predicted_tre_mm(fiducials(), kNoiseMm * std::sqrt(3.0), target);
  EXPECT_NEAR(predicted / measured, 1.0, 0.15) << "predicted " << predicted << " measured " << measured;
  EXPECT_NEAR(fle_from_fre(0.05 * std::sqrt(0.75), 8), 0.05, 1e-12);
}

TEST(Registration, RefusesTooFewPoints) {
  const std::vector<core::Vec3> eye = {{0, 0, 12}, {12, 0, 0}, {0, 12, 0}};
  const RegistrationResult r = register_points(eye, eye);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("too few fiducials: 3"), std::string::npos) << r.error;
}

TEST(Registration, RefusesCollinearPoints) {
  std::vector<core::Vec3> line;
  for (int i = 0; i < 6; ++i) line.emplace_back(2.0 * i, 1.0 * i, 0.5 * i);
  const RegistrationResult r = register_points(line, line);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("on a line"), std::string::npos) << r.error;
}

TEST(Registration, RefusesMismatchedCountsAndSwappedTouches) {
  std::vector<core::Vec3> eye = fiducials();
  std::vector<core::Vec3> touched = eye;
  touched.pop_back();
  EXPECT_FALSE(register_points(touched, eye).ok);
  touched = eye;
  std::swap(touched[0], touched[3]);  // the technician touched two fiducials in the wrong order
  const RegistrationResult r = register_points(touched, eye);
  EXPECT_FALSE(r.ok);
  EXPECT_GT(r.fre_mm, RegistrationLimits{}.max_fre_mm);
  EXPECT_NE(r.error.find("wrong order"), std::string::npos) << r.error;
}

}  // namespace
}  // namespace vitreo::rig::calibration
