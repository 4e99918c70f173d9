#include "rig/calibration/pivot.hpp"

#include <gtest/gtest.h>

#include "tests/rig/calibration/synthetic.hpp"

namespace vitreo::rig::calibration {
namespace {

using testing::kNoiseMm;
using testing::Synth;

// The tracker reports a point up the shaft; the real tip is tip_offset further on, in the
// instrument's frame. Pivoting about a divot at `pivot`: reported = pivot − R·tip_offset (+ noise).
std::vector<PivotPose> pivoting(Synth& s, const core::Vec3& tip_offset, const core::Vec3& pivot, std::size_t n,
                                double half_cone_deg, double noise_mm) {
  std::vector<PivotPose> poses;
  for (std::size_t i = 0; i < n; ++i) {
    const core::Quat q = s.in_cone(core::Vec3(0.2, -0.3, 1.0), half_cone_deg);
    poses.push_back({pivot - q * tip_offset + s.noise(noise_mm), q});
  }
  return poses;
}

const core::Vec3 kTip(1.3, -0.7, 14.5);  // mm: the marker sits 14.5 mm up the shaft, a little off axis
const core::Vec3 kDivot(120.0, -35.0, 410.0);

TEST(Pivot, RecoversInjectedTipOffsetWithin0_1mmUnder0_05mmNoise) {
  Synth s;
  const PivotResult r = calibrate_pivot(pivoting(s, kTip, kDivot, 412, 20.0, kNoiseMm));
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_LT((r.tip_offset_mm - kTip).norm(), 0.1);
  EXPECT_LT((r.pivot_mm - kDivot).norm(), 0.1);
  // Residual of 3-D Gaussian noise with σ per axis: RMS ≈ σ√3 (less the 6 fitted parameters' share).
  EXPECT_NEAR(r.rms_mm, kNoiseMm * std::sqrt(3.0), 0.01);
  EXPECT_EQ(r.residuals_mm.size(), 412u);
  EXPECT_GT(r.spread_deg, 30.0);
  EXPECT_LE(r.spread_deg, 40.0 + 1e-9);
}

TEST(Pivot, ExactWithoutNoise) {
  Synth s;
  const PivotResult r = calibrate_pivot(pivoting(s, kTip, kDivot, 60, 25.0, 0.0));
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_LT((r.tip_offset_mm - kTip).norm(), 1e-9);
  EXPECT_LT(r.rms_mm, 1e-9);
}

TEST(Pivot, SpreadIsTheWidestAngleBetweenTwoShafts) {
  // Two poses tilted ±20° about x: 40° apart, whatever their twist.
  const core::Quat a(Eigen::AngleAxisd(0.349065850398866, core::Vec3::UnitX()));
  const core::Quat b(Eigen::AngleAxisd(-0.349065850398866, core::Vec3::UnitX()) *
                     Eigen::AngleAxisd(1.0, core::Vec3::UnitZ()));
  EXPECT_NEAR(pivot_spread_deg({{core::Vec3::Zero(), a}, {core::Vec3::Zero(), b}}), 40.0, 1e-9);
}

TEST(Pivot, RefusesTooFewPoses) {
  Synth s;
  const PivotResult r = calibrate_pivot(pivoting(s, kTip, kDivot, 10, 20.0, kNoiseMm));
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("too few poses: 10"), std::string::npos) << r.error;
}

TEST(Pivot, RefusesTooLittleSpread) {
  Synth s;
  const PivotResult r = calibrate_pivot(pivoting(s, kTip, kDivot, 300, 3.0, kNoiseMm));
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("too little pivot spread"), std::string::npos) << r.error;
  EXPECT_LT(r.spread_deg, 6.0 + 1e-9);
}

TEST(Pivot, RefusesRotationsAboutOneAxis) {
  // A fan: every pose turns about the same axis through the tip, so the offset along it is free.
  std::vector<PivotPose> poses;
  for (int i = 0; i < 100; ++i) {
    const core::Quat q(Eigen::AngleAxisd((i - 50) * 0.01, core::Vec3::UnitX()));
    poses.push_back({kDivot - q * kTip, q});
  }
  const PivotResult r = calibrate_pivot(poses);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("one axis"), std::string::npos) << r.error;
}

TEST(Pivot, FailsWhenTheTipSlips) {
  Synth s;
  std::vector<PivotPose> poses = pivoting(s, kTip, kDivot, 400, 20.0, kNoiseMm);
  core::Vec3 drift = core::Vec3::Zero();
  for (PivotPose& p : poses) p.position_mm += (drift += s.noise(0.05));  // a random walk: ~1 mm by the end
  const PivotResult r = calibrate_pivot(poses);
  EXPECT_FALSE(r.ok);
  EXPECT_GT(r.rms_mm, PivotLimits{}.max_rms_mm);
  EXPECT_NE(r.error.find("above the"), std::string::npos) << r.error;
}

TEST(Pivot, RefusesNonFinitePoses) {
  Synth s;
  std::vector<PivotPose> poses = pivoting(s, kTip, kDivot, 100, 20.0, 0.0);
  poses[7].position_mm.x() = std::nan("");
  EXPECT_FALSE(calibrate_pivot(poses).ok);
}

}  // namespace
}  // namespace vitreo::rig::calibration
