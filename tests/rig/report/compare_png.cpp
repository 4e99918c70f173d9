// compare_png GOLDEN ACTUAL [MAX_SHARE MAX_MEAN]: compares two screenshots of the report page with a
// tolerance for what legitimately varies between machines and runs (anti-aliasing, font hinting,
// the telemetry event count in the header). Per pixel the largest channel difference is taken;
// the images match when they have the same size, at most MAX_SHARE (default 0.02) of the pixels
// differ by more than 48 of 255, and the mean difference is at most MAX_MEAN (default 4).
// Exit 0 match, 1 differ (the measures are printed), 2 unreadable.
#include <png.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace {

struct Rgba {
  png_uint_32 width = 0, height = 0;
  std::vector<png_byte> pixels;  // RGBA, 8 bits each
};

bool load(const char* path, Rgba& out) {
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&image, path)) {
    std::fprintf(stderr, "%s: %s\n", path, image.message);
    return false;
  }
  image.format = PNG_FORMAT_RGBA;
  out.width = image.width;
  out.height = image.height;
  out.pixels.resize(PNG_IMAGE_SIZE(image));
  if (!png_image_finish_read(&image, nullptr, out.pixels.data(), 0, nullptr)) {
    std::fprintf(stderr, "%s: %s\n", path, image.message);
    png_image_free(&image);
    return false;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3 && argc != 5) {
    std::fprintf(stderr, "usage: compare_png GOLDEN ACTUAL [MAX_SHARE MAX_MEAN]\n");
    return 2;
  }
  const double max_share = argc == 5 ? std::atof(argv[3]) : 0.02;
  const double max_mean = argc == 5 ? std::atof(argv[4]) : 4.0;
  Rgba a, b;
  if (!load(argv[1], a) || !load(argv[2], b)) return 2;
  if (a.width != b.width || a.height != b.height) {
    std::printf("sizes differ: %ux%u vs %ux%u\n", a.width, a.height, b.width, b.height);
    return 1;
  }
  const std::size_t n = static_cast<std::size_t>(a.width) * a.height;
  std::size_t over = 0;
  double sum = 0;
  for (std::size_t i = 0; i < n; ++i) {
    int d = 0;
    for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(int(a.pixels[4 * i + c]) - int(b.pixels[4 * i + c])));
    sum += d;
    if (d > 48) ++over;
  }
  const double share = static_cast<double>(over) / static_cast<double>(n), mean = sum / static_cast<double>(n);
  const bool ok = share <= max_share && mean <= max_mean;
  std::printf("%ux%u: %.4f of the pixels differ by more than 48 (limit %.4f), mean difference %.3f (limit %.3f): %s\n", a.width,
              a.height, share, max_share, mean, max_mean, ok ? "match" : "DIFFERENT");
  return ok ? 0 : 1;
}
