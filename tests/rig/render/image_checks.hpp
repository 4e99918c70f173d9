#pragma once
// Small image measurements the view tests share: mean colour of a patch, where two frames differ,
// how much of a difference lies near given pixels. Written for the tests, independent of the
// renderer's own code.
#include <cstdint>
#include <vector>

#include "vitreo/render/frame_scene.hpp"

namespace vitreo::render::testing {

struct Rgb {
  double r = 0, g = 0, b = 0;
  double luma() const { return 0.2126 * r + 0.7152 * g + 0.0722 * b; }
  double spread() const;  // max − min channel: 0 = grey/white
};

// Mean colour of the (2k+1)² patch around pixel p (clipped to the image).
Rgb patch(const Image& img, Vec2 p, int k);

// 1 where any channel of a and b differs by more than `threshold` (same size images).
struct Mask {
  int width = 0, height = 0;
  std::vector<std::uint8_t> bits;
  int count() const;
  bool at(int x, int y) const { return x >= 0 && y >= 0 && x < width && y < height && bits[static_cast<std::size_t>(y) * width + x]; }
  // Share of the set pixels that lie within `radius` px of one of `points`.
  double fraction_near(const std::vector<Vec2>& points, float radius) const;
  // Centroid of the set pixels.
  Vec2 centroid() const;
};
Mask diff_mask(const Image& a, const Image& b, int threshold);

// The image turned 180° (what an inverted optical path shows).
Image rotate180(const Image& img);

// Sum of absolute luma differences between horizontal and vertical neighbours inside the box
// [x0, x1) × [y0, y1): how much edge and texture detail a region has (blur lowers it).
double detail(const Image& img, int x0, int y0, int x1, int y1);

// Taking a cue away, to see what it changed: the scene without the meshes `drop` picks; the scene
// with no retina shaded as detached (the detachment cue off, the geometry unchanged).
template <class Pred>
FrameScene without(FrameScene s, Pred drop) {
  std::erase_if(s.meshes, drop);
  return s;
}
FrameScene without_detachment_shading(FrameScene s);

}  // namespace vitreo::render::testing
