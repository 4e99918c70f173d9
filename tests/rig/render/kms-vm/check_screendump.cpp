// Host side of the KMS scan-out test: reads qemu's screendump (PPM) of the VM's bochs-display and
// checks it shows the second test frame, letterboxed with its aspect ratio kept. The expected layout
// is worked out here from the frame and screen sizes alone (not with the display code's fit_rect),
// and sampled well inside each solid block so scaler rounding cannot matter.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "vm_checks.hpp"
#include "test_pattern.hpp"

namespace kt = vitreo::kms_test;

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: check_screendump DUMP.ppm\n");
    return 2;
  }
  std::ifstream in(argv[1], std::ios::binary);
  std::string magic;
  int w = 0, h = 0, maxval = 0;
  in >> magic >> w >> h >> maxval;
  in.get();
  if (!in || magic != "P6" || w <= 0 || h <= 0 || maxval != 255) {
    std::printf("FAIL: %s is not an 8-bit binary PPM (magic %s, %dx%d, max %d)\n", argv[1], magic.c_str(), w, h, maxval);
    return 1;
  }
  std::vector<unsigned char> px(static_cast<std::size_t>(w) * h * 3);
  in.read(reinterpret_cast<char*>(px.data()), static_cast<std::streamsize>(px.size()));
  CHECK(in.gcount() == static_cast<std::streamsize>(px.size()), "short PPM");
  std::printf("screendump: %dx%d\n", w, h);

  // Aspect fit: the 640×256 frame is wider than any usual screen, so it spans the width.
  const double scale = std::min(static_cast<double>(w) / kt::kW, static_cast<double>(h) / kt::kH);
  const double rw = kt::kW * scale, rh = kt::kH * scale;
  const double x0 = (w - rw) / 2, y0 = (h - rh) / 2;
  auto at = [&](double sx, double sy) {  // source pixel coordinates → screen colour
    const int x = static_cast<int>(std::lround(x0 + sx * scale)), y = static_cast<int>(std::lround(y0 + sy * scale));
    const unsigned char* p = &px[(static_cast<std::size_t>(y) * w + x) * 3];
    return kt::Rgb{p[0], p[1], p[2]};
  };
  auto near = [](kt::Rgb a, kt::Rgb b) { return std::abs(a.r - b.r) <= 8 && std::abs(a.g - b.g) <= 8 && std::abs(a.b - b.b) <= 8; };
  struct Sample {
    const char* what;
    double sx, sy;
    kt::Rgb expected;
  };
  // Frame 1: left eye green, right eye red, white square in the left eye, blue bar on the right.
  const Sample samples[] = {
      {"left eye (green in the second frame)", 40, 200, kt::kGreen},
      {"left eye, upper part", 280, 20, kt::kGreen},
      {"white square at the left eye's centre", 160, 128, kt::kWhite},
      {"right eye (red in the second frame)", 400, 200, kt::kRed},
      {"right eye, far corner", 620, 240, kt::kRed},
      {"blue bar along the right eye's top", 480, 16, kt::kBlue},
  };
  for (const Sample& s : samples) {
    const kt::Rgb c = at(s.sx, s.sy);
    CHECK(near(c, s.expected), "%s: got (%d,%d,%d), expected (%d,%d,%d)", s.what, c.r, c.g, c.b, s.expected.r, s.expected.g,
          s.expected.b);
  }
  // Letterbox bands above and below are black (when the screen leaves any).
  if (y0 >= 4) {
    for (int x : {w / 8, w / 2, 7 * w / 8}) {
      for (int y : {static_cast<int>(y0 / 2), h - 1 - static_cast<int>(y0 / 2)}) {
        const unsigned char* p = &px[(static_cast<std::size_t>(y) * w + x) * 3];
        CHECK(p[0] < 8 && p[1] < 8 && p[2] < 8, "letterbox band at (%d,%d) is (%d,%d,%d), not black", x, y, p[0], p[1], p[2]);
      }
    }
  }
  // Where the frame's edge lands: the first non-black row from the top at the centre column
  // should be the frame's top edge (within a pixel).
  int first = -1;
  for (int y = 0; y < h && first < 0; ++y) {
    const unsigned char* p = &px[(static_cast<std::size_t>(y) * w + w / 4) * 3];
    if (p[0] > 8 || p[1] > 8 || p[2] > 8) first = y;
  }
  CHECK(std::abs(first - y0) <= 1.0, "frame top edge at row %d, expected %.1f", first, y0);
  std::printf("frame placed at (%.1f, %.1f) size %.1fx%.1f; %d checks, %d failed\n", x0, y0, rw, rh, g_checks, g_fail);
  return g_fail == 0 ? 0 : 1;
}
