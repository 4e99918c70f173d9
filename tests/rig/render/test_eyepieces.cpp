// The eyepiece displays' calibration as the renderer applies it: each eye's picture moves on its
// display by exactly the whole pixels asked and the other eye's does not change; the test pattern's
// nonius cross is one cross on aligned displays, its halves each seen by one eye only, parted by
// exactly a display offset; its depth markers' disparity grows with the stereo base. Positions are
// measured from the pixels (coloured lines found by scanning), not from the camera's own projection.
#include <gtest/gtest.h>

#include <cmath>

#include "render_fixture.hpp"
#include "synthetic_scene.hpp"
#include "vitreo/render/eyepiece_pattern.hpp"
#include "vitreo/render/render_thread.hpp"

namespace vr = vitreo::render;
namespace vt = vitreo::render::testing;

namespace {

constexpr int kW = 320, kH = 256;
using Eyepieces = vt::RendererFixture<kW, kH>;

enum class Hue { green, red, yellow };
bool is(const vr::Image& img, int x, int y, Hue h) {
  const std::uint8_t* p = &img.rgba[(static_cast<std::size_t>(y) * img.width + x) * 4];
  switch (h) {
    case Hue::green: return p[1] > 150 && p[0] < 110 && p[2] < 120;
    case Hue::red: return p[0] > 150 && p[1] < 110 && p[2] < 110;
    case Hue::yellow: return p[0] > 150 && p[1] > 150 && p[2] < 120;
  }
  return false;
}
int count(const vr::Image& img, Hue h) {
  int n = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) n += is(img, x, y, h);
  return n;
}

// The nonius cross's centre as the pixels show it: the column of its vertical arm (the mean x of the
// coloured pixels in rows where the arm is thin) and the row of its horizontal arm.
struct Cross {
  double x = 0, y = 0;
};
Cross cross_of(const vr::Image& img, Hue h) {
  double sx = 0, sy = 0;
  int nx = 0, ny = 0;
  for (int y = 0; y < img.height; ++y) {
    int in_row = 0;
    double row_x = 0;
    for (int x = 0; x < img.width; ++x)
      if (is(img, x, y, h)) ++in_row, row_x += x;
    if (in_row > 0 && in_row <= 4) sx += row_x, nx += in_row;  // a row crossing the vertical arm
  }
  for (int x = 0; x < img.width; ++x) {
    int in_col = 0;
    double col_y = 0;
    for (int y = 0; y < img.height; ++y)
      if (is(img, x, y, h)) ++in_col, col_y += y;
    if (in_col > 0 && in_col <= 4) sy += col_y, ny += in_col;  // a column crossing the horizontal arm
  }
  EXPECT_GT(nx, 20);
  EXPECT_GT(ny, 20);
  return {nx ? sx / nx : -1, ny ? sy / ny : -1};
}

vr::FrameScene pattern(const vr::EyepieceSettings& s) {
  vr::Microscope m;
  s.apply(m);
  return vr::eyepiece_test_pattern(m, 12.0f, kW, kH);
}

TEST_F(Eyepieces, TheNoniusCrossIsOneCrossOnAlignedDisplaysAndPartsByExactlyAnOffset) {
  const vr::StereoFrame aligned = render(pattern({}));
  const vr::Image left = aligned.eye(0), right = aligned.eye(1);
  EXPECT_EQ(count(left, Hue::red), 0) << "the right eye's arms are not seen by the left eye";
  EXPECT_EQ(count(right, Hue::green), 0) << "nor the left eye's by the right";
  const Cross g = cross_of(left, Hue::green), r = cross_of(right, Hue::red);
  std::printf("aligned: green cross at (%.2f, %.2f), red at (%.2f, %.2f)\n", g.x, g.y, r.x, r.y);
  EXPECT_NEAR(g.x, r.x, 0.5) << "on the zero-disparity plane both eyes draw the centre at the same pixel";
  EXPECT_NEAR(g.y, r.y, 0.5);
  EXPECT_NEAR(g.x, kW / 2.0, 2.0) << "in the middle of the picture";
  EXPECT_NEAR(g.y, kH / 2.0, 2.0);

  vr::EyepieceSettings shifted;
  shifted.offset_px[1] = {3.0f, -2.0f};  // the right display's picture 3 px right and 2 px down
  const vr::StereoFrame moved = render(pattern(shifted));
  const Cross g2 = cross_of(moved.eye(0), Hue::green), r2 = cross_of(moved.eye(1), Hue::red);
  std::printf("right eye shifted (3, -2): green (%.2f, %.2f), red (%.2f, %.2f)\n", g2.x, g2.y, r2.x, r2.y);
  EXPECT_NEAR(g2.x, g.x, 0.25) << "the left eye's picture does not move";
  EXPECT_NEAR(g2.y, g.y, 0.25);
  EXPECT_NEAR(r2.x - g2.x, 3.0, 0.5);
  EXPECT_NEAR(r2.y - g2.y, 2.0, 0.5) << "y up: −2 is two rows further down the image";
}

TEST_F(Eyepieces, ADisplayOffsetMovesOnlyThatEyesPictureByWholePixels) {
  vt::SyntheticOptions o;
  o.retina_triangles = 3000;
  const vr::FrameScene scene = vt::make_scene(o);
  vr::FrameScene offset_scene = scene;
  vr::EyepieceSettings s;
  s.stereo_base_mm = scene.microscope.stereo_base_mm;
  s.convergence_mm = scene.microscope.convergence_distance_mm;
  s.offset_px[1] = {5.0f, 3.0f};
  s.apply(offset_scene.microscope);
  const vr::StereoFrame a = render(scene), b = render(offset_scene);
  EXPECT_EQ(a.eye(0).rgba, b.eye(0).rgba) << "the left eye is untouched";
  const vr::Image ra = a.eye(1), rb = b.eye(1);
  int same = 0, total = 0;
  for (int y = 10; y < kH - 10; ++y) {
    for (int x = 10; x < kW - 10; ++x) {
      // (x, y) of the moved picture shows what (x − 5, y + 3) showed: 5 right, 3 up.
      const std::uint8_t* p = &rb.rgba[(static_cast<std::size_t>(y) * kW + x) * 4];
      const std::uint8_t* q = &ra.rgba[(static_cast<std::size_t>(y + 3) * kW + (x - 5)) * 4];
      int d = 0;
      for (int k = 0; k < 3; ++k) d = std::max(d, std::abs(int(p[k]) - int(q[k])));
      same += d <= 3;
      ++total;
    }
  }
  std::printf("right eye moved by (5, 3) px: %d of %d interior pixels match the unmoved picture shifted\n", same, total);
  EXPECT_GT(same, 0.99 * total);
  EXPECT_NE(ra.rgba, rb.rgba);
}

TEST_F(Eyepieces, TheDepthMarkersDisparityGrowsWithTheStereoBase) {
  std::pair<double, double> out;
  // The mean column of each yellow square in each eye; disparity = left − right. Without the grid:
  // where a square's line crosses a grid line the two add up to white, which would bias the mean.
  auto disparities = [&](float base) {
    vr::EyepieceSettings s;
    s.stereo_base_mm = base;
    vr::FrameScene scene = pattern(s);
    std::erase_if(scene.meshes, [](const vr::Mesh& m) { return m.eyes == 3 && m.tint.z > 0.5f; });  // the grey grid
    ASSERT_EQ(scene.meshes.size(), 3u);
    const vr::StereoFrame f = render(scene);
    double d[2] = {0, 0};  // near (left of the cross), deep (right of it)
    for (int side = 0; side < 2; ++side) {
      double mean[2] = {0, 0};
      for (int e = 0; e < 2; ++e) {
        const vr::Image img = f.eye(e);
        double sx = 0;
        int n = 0;
        for (int y = 0; y < kH; ++y)
          for (int x = side == 0 ? 0 : kW / 2; x < (side == 0 ? kW / 2 : kW); ++x)
            if (is(img, x, y, Hue::yellow)) sx += x, ++n;
        EXPECT_GT(n, 20);
        mean[e] = n ? sx / n : 0;
      }
      d[side] = mean[0] - mean[1];
    }
    out = {d[0], d[1]};
  };
  disparities(22.0f);
  const auto [near22, deep22] = out;
  disparities(44.0f);
  const auto [near44, deep44] = out;
  std::printf("disparity (px) near/deep: base 22 mm %.2f / %.2f, base 44 mm %.2f / %.2f\n", near22, deep22, near44, deep44);
  EXPECT_GT(near22, 1.0) << "crossed: the nearer square further right in the left eye";
  EXPECT_LT(deep22, -1.0) << "uncrossed: the deeper square further left in the left eye";
  // Parallel-axes stereo: disparity = base · f · (1/z − 1/convergence), f in pixels from the
  // microscope's field (30 mm high at its 180 mm working distance over 256 rows); the squares stand
  // 3 mm nearer and deeper than the 180 mm plane. Within a pixel: each eye's mean column of a
  // 2-pixel line outline is off by up to half a pixel.
  const double f_px = (kH / 2.0) / (15.0 / 180.0);
  auto expected = [&](double base, double z) { return base * f_px * (1.0 / z - 1.0 / 180.0); };
  EXPECT_NEAR(near22, expected(22, 177), 1.0);
  EXPECT_NEAR(deep22, expected(22, 183), 1.0);
  EXPECT_NEAR(near44, expected(44, 177), 1.0);
  EXPECT_NEAR(deep44, expected(44, 183), 1.0);
  EXPECT_GT(near44 - deep44, 1.5 * (near22 - deep22)) << "twice the base, about twice the depth impression";
}

}  // namespace
