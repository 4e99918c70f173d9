#pragma once
// The stereo frames the KMS scan-out test shows, and where their regions lie in source pixels.
// Shared by the program in the VM (which presents them) and the host check (which finds them in
// qemu's screendump): solid blocks, so the check does not depend on the scaler's rounding.
#include <cstdint>
#include <vector>

namespace vitreo::kms_test {

inline constexpr int kEyeW = 320, kEyeH = 256, kW = 2 * kEyeW, kH = kEyeH;
struct Rgb {
  std::uint8_t r, g, b;
};
inline constexpr Rgb kRed{230, 20, 20}, kGreen{20, 200, 40}, kWhite{255, 255, 255}, kBlue{30, 40, 220};

// Frame `which` (0 or 1): the left eye is red in frame 0 and green in frame 1, the right eye the
// other way round; a white square at the left eye's centre; a blue bar along the right eye's top.
inline std::vector<std::uint8_t> stereo_test_frame(int which) {
  std::vector<std::uint8_t> px(static_cast<std::size_t>(kW) * kH * 4);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const bool left = x < kEyeW;
      Rgb c = (left == (which == 0)) ? kRed : kGreen;
      if (left && x >= 128 && x < 192 && y >= 96 && y < 160) c = kWhite;
      if (!left && y < 32) c = kBlue;
      std::uint8_t* p = &px[(static_cast<std::size_t>(y) * kW + x) * 4];
      p[0] = c.r;
      p[1] = c.g;
      p[2] = c.b;
      p[3] = 255;
    }
  return px;
}

}  // namespace vitreo::kms_test
