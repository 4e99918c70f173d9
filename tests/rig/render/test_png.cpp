#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <stdexcept>

#include "vitreo/render/image_compare.hpp"
#include "vitreo/render/png_io.hpp"

namespace vr = vitreo::render;

TEST(Png, RoundTripIsExactAndRowsAreTopDown) {
  vr::Image img{7, 5, {}};
  for (int i = 0; i < 7 * 5 * 4; ++i) img.rgba.push_back(static_cast<std::uint8_t>(i * 37 + 11));
  const std::string path = ::testing::TempDir() + "vitreo_png_roundtrip.png";
  vr::write_png(path, img);
  const vr::Image back = vr::read_png(path);
  EXPECT_EQ(back.width, 7);
  EXPECT_EQ(back.height, 5);
  EXPECT_EQ(back.rgba, img.rgba);
  const vr::ImageDiff d = vr::compare_images(back, img);
  EXPECT_TRUE(d.same_size);
  EXPECT_EQ(d.max_abs_diff, 0);
  std::remove(path.c_str());
}

TEST(Png, UnreadableFilesThrowWithTheReason) {
  EXPECT_THROW(vr::read_png("/nonexistent/x.png"), std::runtime_error);
  const std::string path = ::testing::TempDir() + "vitreo_not_a_png.png";
  std::ofstream(path) << "this is not a PNG";
  try {
    vr::read_png(path);
    FAIL() << "garbage was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("not a readable PNG"), std::string::npos) << e.what();
  }
  std::remove(path.c_str());
}

TEST(ImageCompare, ReportsRmseAndMaxDiff) {
  vr::Image a{2, 1, {0, 0, 0, 255, 100, 100, 100, 255}};
  vr::Image b = a;
  b.rgba[4] = 130;  // one channel of one pixel differs by 30
  const vr::ImageDiff d = vr::compare_images(a, b, 24);
  EXPECT_EQ(d.max_abs_diff, 30);
  EXPECT_NEAR(d.rmse, std::sqrt(900.0 / 6.0), 1e-9);
  EXPECT_DOUBLE_EQ(d.fraction_over, 0.5);
  EXPECT_FALSE(vr::compare_images(a, vr::Image{1, 1, {0, 0, 0, 0}}).same_size);
}
