#pragma once
// The eyepiece test pattern: what a technician looks at through the rig's eyepieces to align the
// two displays and to set the stereo base and convergence (vitreo-calibrate --eyepieces).
//
// On the zero-disparity plane (the convergence distance, so aligned displays show it at the same
// pixels in both eyes): a white grid every 2 mm, and a centre cross made of nonius lines — its upper
// and right arms seen by the left eye only (green), its lower and left arms by the right eye only
// (red). On aligned displays the two halves meet as one straight cross; a shift between the
// displays breaks them apart by that shift, which the technician cancels with the per-eye offsets.
// Two square outlines stand 3 mm nearer and 3 mm deeper than the plane (both eyes): their
// disparity shows the stereo base at work, the nearer one left of the cross, the deeper one right.
// The pattern is drawn by the same renderer and camera as a surgery, so the offsets, stereo base
// and convergence act on it exactly as they will on the eye.
#include "vitreo/render/frame_scene.hpp"

namespace vitreo::render {

struct EyepiecePatternGeometry {
  float grid_mm = 2.0f;           // grid pitch on the plane
  float cross_arm_mm = 3.0f;      // each nonius arm's length from the centre
  float marker_depth_mm = 3.0f;   // the squares' distance before and behind the plane
  float marker_size_mm = 2.0f;    // their side
  float marker_offset_mm = 5.0f;  // their distance left and right of the centre
};

/// The pattern for a microscope `m` (its view, zoom, stereo base, convergence) and images of
/// width×height pixels per eye; lines are 2 pixels wide there.
FrameScene eyepiece_test_pattern(const Microscope& m, float globe_radius_mm, int width, int height,
                                 const EyepiecePatternGeometry& g = {});

}  // namespace vitreo::render
