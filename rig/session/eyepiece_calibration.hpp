#pragma once
// The stereo eyepiece displays' calibration (vitreo-calibrate --eyepieces): the technician looks
// into the eyepieces at the test pattern (rig/render eyepiece_pattern.hpp) and adjusts, by lines on
// standard input, each eye's image shift until the nonius cross is one straight cross, then the
// stereo base and convergence until the depth markers stand comfortably before and behind the grid:
//
//   left DX DY       the left eye's picture shifted DX pixels right and DY up on its display
//   right DX DY      the same for the right eye
//   base MM          the stereo base (1..100 mm; the microscope's 22 by default)
//   convergence MM   the zero-disparity distance (50..2000 mm; 0: at the working plane)
//   show             what is set now
//   done             keep it            q   give up
//
// Every change is drawn at once on the rig's outputs (its displays, frame ring, and the pattern's
// PNGs when asked), by the renderer that draws the surgery, with the settings applied as the rig
// will apply them.
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "rig/calibration/calibration_file.hpp"
#include "vitreo/render/kms_display.hpp"

namespace vitreo::rig {

struct EyepieceRunOptions {
  int eye_width = 640, eye_height = 512;
  std::vector<render::KmsOptions> displays;
  std::string frame_ring_name;
  std::string png_prefix;  // non-empty: PREFIX_{left,right,stereo}.png show the pattern as last set
  calibration::EyepieceRecord start;  // what is set at first (the calibration in force, or the defaults)
};

// The settings the technician kept (done), or nothing when they gave up or the input ended.
// Throws std::runtime_error when the renderer or a display cannot be started.
std::optional<calibration::EyepieceRecord> run_eyepiece_calibration(const EyepieceRunOptions& options, int input_fd, std::FILE* out);

}  // namespace vitreo::rig
