// The KMS display's pure parts (aspect fit, letterboxed conversion to the scan-out format, eye
// selection) and its failure paths on this machine, which has no /dev/dri. Scan-out itself is
// tested on a real KMS device inside the qemu VM (kms-vm/, label vm).
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "vitreo/render/kms_display.hpp"
#include "vitreo/render/render_thread.hpp"

namespace vr = vitreo::render;

namespace {
vr::KmsOptions on_card(const char* card) {
  vr::KmsOptions o;
  o.card = card;
  return o;
}
}  // namespace

TEST(KmsDisplay, FitRectKeepsTheAspectRatioAndCentres) {
  // A 2.5:1 stereo frame on a 4:3 screen spans the width; bands above and below are equal.
  vr::ScreenRect r = vr::fit_rect(2560, 1024, 1024, 768);
  EXPECT_EQ(r.width, 1024);
  EXPECT_EQ(r.height, 409);  // 1024 / 2.5 = 409.6, truncated
  EXPECT_EQ(r.x, 0);
  EXPECT_EQ(r.y, (768 - 409) / 2);
  // One 5:4 eye on a 16:9 panel spans the height, pillarboxed.
  r = vr::fit_rect(1280, 1024, 1920, 1080);
  EXPECT_EQ(r.height, 1080);
  EXPECT_EQ(r.width, 1350);
  EXPECT_EQ(r.x, (1920 - 1350) / 2);
  EXPECT_EQ(r.y, 0);
  // Same aspect: the whole screen.
  r = vr::fit_rect(640, 512, 1280, 1024);
  EXPECT_EQ(r.x, 0);
  EXPECT_EQ(r.y, 0);
  EXPECT_EQ(r.width, 1280);
  EXPECT_EQ(r.height, 1024);
  EXPECT_EQ(vr::fit_rect(0, 10, 100, 100).width, 0);
}

TEST(KmsDisplay, BlitConvertsToXrgbScaledAndLetterboxed) {
  // 4×2 source: columns red, green, blue, white; rows identical. Screen 8×8: the frame is 8×4 at y 2.
  std::vector<std::uint8_t> src(4 * 2 * 4);
  const std::uint8_t cols[4][3] = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}, {255, 255, 255}};
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 4; ++x)
      for (int c = 0; c < 3; ++c) src[(y * 4 + x) * 4 + c] = cols[x][c];
  std::vector<std::uint32_t> screen(8 * 10, 0xDEADBEEFu);  // stride 10 pixels: padding untouched
  vr::blit_letterboxed({src.data(), 4, 2, 16}, screen.data(), 8, 8, 10 * 4);
  for (int y = 0; y < 8; ++y) {
    for (int x = 0; x < 8; ++x) {
      const std::uint32_t v = screen[static_cast<std::size_t>(y) * 10 + x];
      if (y < 2 || y >= 6) {
        EXPECT_EQ(v, 0u) << "band " << x << "," << y;
      } else {
        const auto* c = cols[x / 2];  // each source column covers two screen columns
        EXPECT_EQ(v, (std::uint32_t{c[0]} << 16) | (std::uint32_t{c[1]} << 8) | c[2]) << x << "," << y;
      }
    }
    EXPECT_EQ(screen[static_cast<std::size_t>(y) * 10 + 8], 0xDEADBEEFu);
  }
}

TEST(KmsDisplay, LayoutSelectsTheEye) {
  std::vector<std::uint8_t> sbs(8 * 2 * 4);
  const vr::RgbaView v{sbs.data(), 8, 2, 32};
  EXPECT_EQ(vr::select_layout(v, vr::DisplayLayout::SideBySide).width, 8);
  const vr::RgbaView l = vr::select_layout(v, vr::DisplayLayout::LeftEye), r = vr::select_layout(v, vr::DisplayLayout::RightEye);
  EXPECT_EQ(l.width, 4);
  EXPECT_EQ(l.pixels, sbs.data());
  EXPECT_EQ(r.width, 4);
  EXPECT_EQ(r.pixels, sbs.data() + 16);
  EXPECT_EQ(r.stride_bytes, 32u);
}

TEST(KmsDisplay, MissingCardIsAClearError) {
  try {
    vr::KmsDisplay d(on_card("/dev/dri/card-does-not-exist"));
    FAIL() << "opened a card that does not exist";
  } catch (const vr::KmsError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("/dev/dri/card-does-not-exist"), std::string::npos) << m;
    EXPECT_NE(m.find("cannot open"), std::string::npos) << m;
  }
}

TEST(KmsDisplay, ADeviceThatIsNotKmsIsAClearError) {
  try {
    vr::KmsDisplay d(on_card("/dev/null"));
    FAIL() << "/dev/null accepted as a display";
  } catch (const vr::KmsError& e) {
    EXPECT_NE(std::string(e.what()).find("not a KMS device"), std::string::npos) << e.what();
  }
}

TEST(KmsDisplay, RenderThreadStartFailsWithTheDisplaysReason) {
  vr::RenderThreadOptions o;
  o.render.eye_width = 64;
  o.render.eye_height = 48;
  o.displays.push_back(on_card("/dev/dri/card-does-not-exist"));
  try {
    vr::RenderThread t(o);
    FAIL() << "render thread started without its display";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("card-does-not-exist"), std::string::npos) << e.what();
  }
}
