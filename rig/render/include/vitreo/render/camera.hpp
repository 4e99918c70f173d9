#pragma once
// The stereo operating microscope as two off-axis perspective views.
//
// Both eyes look along the same axis (from above the eye down −z toward the target) and are
// separated by the stereo base along the image's x axis; each eye's frustum is sheared so that the
// two coincide at the convergence distance (the working plane by default). This "parallel axes,
// asymmetric frustum" stereo has zero disparity on the working plane and no vertical parallax,
// unlike toed-in cameras: points nearer the microscope than the working plane (higher z) appear
// further right in the left eye than in the right eye (crossed disparity), points deeper appear
// further left (uncrossed) — what a surgeon's eyes see through a real stereo microscope.
#include "vitreo/render/frame_scene.hpp"
#include "vitreo/render/math.hpp"

namespace vitreo::render {

enum class Eye { Left = 0, Right = 1 };

struct EyeView {
  Vec3 position_mm;
  Mat4 view;
  Mat4 projection;
  Mat4 view_projection;
  float near_mm = 0;
  float far_mm = 0;
  float focus_distance_mm = 0;  // along the view axis
};

struct StereoViews {
  EyeView eye[2];
  Vec3 forward;  // common view axis
  Vec3 right;    // image x axis
  Vec3 up;       // image y axis
};

/// Views for both eyes for an image of `width`×`height` pixels per eye.
StereoViews stereo_views(const Microscope& m, float globe_radius_mm, int width, int height);

}  // namespace vitreo::render
