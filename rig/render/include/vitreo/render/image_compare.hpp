#pragma once
// Tolerance-based image comparison for golden-image tests: software and hardware rasterisers (and
// Mesa versions) differ in the last bits of filtering and edge coverage, so tests bound an error
// metric instead of demanding identical bytes.
#include <string>

#include "vitreo/render/frame_scene.hpp"

namespace vitreo::render {

struct ImageDiff {
  bool same_size = false;
  double rmse = 0;             // over R, G, B of all pixels, in 0–255 units
  int max_abs_diff = 0;        // largest channel difference
  double fraction_over = 0;    // fraction of pixels with a channel differing by more than `threshold`
  int threshold = 0;
  std::string summary() const;  // "rmse=1.23 max=40 over(24)=0.12%" or "size differs"
};

ImageDiff compare_images(const Image& actual, const Image& expected, int threshold = 24);

/// Mean Rec. 709 luma (0–255) over a rectangle (clipped to the image).
double mean_luminance(const Image& image, int x0 = 0, int y0 = 0, int w = -1, int h = -1);

}  // namespace vitreo::render
