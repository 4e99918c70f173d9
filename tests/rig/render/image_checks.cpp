#include "image_checks.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <memory>

namespace vitreo::render::testing {

namespace {
const std::uint8_t* px(const Image& img, int x, int y) { return &img.rgba[(static_cast<std::size_t>(y) * img.width + x) * 4]; }
double luma(const std::uint8_t* p) { return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]; }
}  // namespace

double Rgb::spread() const { return std::max({r, g, b}) - std::min({r, g, b}); }

Rgb patch(const Image& img, Vec2 p, int k) {
  Rgb s;
  int n = 0;
  for (int y = static_cast<int>(std::lround(p.y)) - k; y <= static_cast<int>(std::lround(p.y)) + k; ++y) {
    for (int x = static_cast<int>(std::lround(p.x)) - k; x <= static_cast<int>(std::lround(p.x)) + k; ++x) {
      if (x < 0 || y < 0 || x >= img.width || y >= img.height) continue;
      const std::uint8_t* q = px(img, x, y);
      s.r += q[0], s.g += q[1], s.b += q[2];
      ++n;
    }
  }
  if (n > 0) s.r /= n, s.g /= n, s.b /= n;
  return s;
}

int Mask::count() const {
  int n = 0;
  for (auto b : bits) n += b;
  return n;
}

double Mask::fraction_near(const std::vector<Vec2>& points, float radius) const {
  int near = 0, all = 0;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      if (!at(x, y)) continue;
      ++all;
      for (const Vec2& p : points) {
        if ((x - p.x) * (x - p.x) + (y - p.y) * (y - p.y) <= radius * radius) {
          ++near;
          break;
        }
      }
    }
  }
  return all > 0 ? static_cast<double>(near) / all : 1.0;
}

Vec2 Mask::centroid() const {
  double sx = 0, sy = 0;
  int n = 0;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      if (!at(x, y)) continue;
      sx += x, sy += y, ++n;
    }
  }
  return n > 0 ? Vec2{static_cast<float>(sx / n), static_cast<float>(sy / n)} : Vec2{-1, -1};
}

Mask diff_mask(const Image& a, const Image& b, int threshold) {
  Mask m;
  m.width = a.width;
  m.height = a.height;
  m.bits.assign(static_cast<std::size_t>(a.width) * a.height, 0);
  if (a.width != b.width || a.height != b.height) return m;
  for (int y = 0; y < a.height; ++y) {
    for (int x = 0; x < a.width; ++x) {
      const std::uint8_t *p = px(a, x, y), *q = px(b, x, y);
      int d = 0;
      for (int k = 0; k < 3; ++k) d = std::max(d, std::abs(int(p[k]) - int(q[k])));
      m.bits[static_cast<std::size_t>(y) * a.width + x] = d > threshold ? 1 : 0;
    }
  }
  return m;
}

Image rotate180(const Image& img) {
  Image out = img;
  for (int y = 0; y < img.height; ++y) {
    for (int x = 0; x < img.width; ++x) {
      const std::uint8_t* s = px(img, x, y);
      std::uint8_t* d = &out.rgba[(static_cast<std::size_t>(img.height - 1 - y) * img.width + (img.width - 1 - x)) * 4];
      for (int k = 0; k < 4; ++k) d[k] = s[k];
    }
  }
  return out;
}

double detail(const Image& img, int x0, int y0, int x1, int y1) {
  double sum = 0;
  x0 = std::max(x0, 0), y0 = std::max(y0, 0), x1 = std::min(x1, img.width - 1), y1 = std::min(y1, img.height - 1);
  for (int y = y0; y < y1; ++y) {
    for (int x = x0; x < x1; ++x) {
      const double l = luma(px(img, x, y));
      sum += std::abs(l - luma(px(img, x + 1, y))) + std::abs(l - luma(px(img, x, y + 1)));
    }
  }
  return sum;
}

FrameScene without_detachment_shading(FrameScene s) {
  for (auto& m : s.meshes) {
    if (m.material != MaterialKind::Retina) continue;
    auto g = std::make_shared<MeshGeometry>(*m.geometry);
    for (auto& v : g->vertices) v.detachment = 0.0f;
    m.geometry = g;
    m.geometry_version += 1000000;  // new vertex data for a renderer that saw the shaded one
  }
  return s;
}

}  // namespace vitreo::render::testing
