#include "vitreo/render/image_compare.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace vitreo::render {

std::string ImageDiff::summary() const {
  if (!same_size) return "size differs";
  char buf[128];
  std::snprintf(buf, sizeof buf, "rmse=%.3f max=%d over(%d)=%.3f%%", rmse, max_abs_diff, threshold,
                100.0 * fraction_over);
  return buf;
}

ImageDiff compare_images(const Image& a, const Image& b, int threshold) {
  ImageDiff d;
  d.threshold = threshold;
  d.same_size = a.width == b.width && a.height == b.height && a.rgba.size() == b.rgba.size() && !a.rgba.empty();
  if (!d.same_size) return d;
  double sq = 0;
  std::size_t over = 0;
  const std::size_t pixels = a.rgba.size() / 4;
  for (std::size_t i = 0; i < pixels; ++i) {
    int worst = 0;
    for (int c = 0; c < 3; ++c) {
      const int diff = std::abs(int(a.rgba[i * 4 + c]) - int(b.rgba[i * 4 + c]));
      sq += double(diff) * diff;
      worst = std::max(worst, diff);
    }
    d.max_abs_diff = std::max(d.max_abs_diff, worst);
    if (worst > threshold) ++over;
  }
  d.rmse = std::sqrt(sq / double(pixels * 3));
  d.fraction_over = double(over) / double(pixels);
  return d;
}

double mean_luminance(const Image& img, int x0, int y0, int w, int h) {
  if (w < 0) w = img.width - x0;
  if (h < 0) h = img.height - y0;
  const int x1 = std::min(img.width, x0 + w), y1 = std::min(img.height, y0 + h);
  x0 = std::max(0, x0);
  y0 = std::max(0, y0);
  double sum = 0;
  long n = 0;
  for (int y = y0; y < y1; ++y) {
    for (int x = x0; x < x1; ++x) {
      const std::uint8_t* p = &img.rgba[(static_cast<std::size_t>(y) * img.width + x) * 4];
      sum += 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
      ++n;
    }
  }
  return n > 0 ? sum / double(n) : 0.0;
}

}  // namespace vitreo::render
