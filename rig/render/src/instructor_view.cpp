#include "vitreo/render/instructor_view.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "bitmap_font.hpp"

namespace vitreo::render {

namespace {

// Darkens a rectangle (a panel behind text), clipped to the image.
void shade(Image& img, int x, int y, int w, int h, float keep) {
  for (int yy = std::max(0, y); yy < std::min(img.height, y + h); ++yy) {
    for (int xx = std::max(0, x); xx < std::min(img.width, x + w); ++xx) {
      std::uint8_t* p = &img.rgba[(static_cast<std::size_t>(yy) * img.width + xx) * 4];
      for (int k = 0; k < 3; ++k) p[k] = static_cast<std::uint8_t>(std::lround(p[k] * keep));
    }
  }
}

void fill(Image& img, int x, int y, int w, int h, std::array<std::uint8_t, 3> c) {
  for (int yy = std::max(0, y); yy < std::min(img.height, y + h); ++yy) {
    for (int xx = std::max(0, x); xx < std::min(img.width, x + w); ++xx) {
      std::uint8_t* p = &img.rgba[(static_cast<std::size_t>(yy) * img.width + xx) * 4];
      p[0] = c[0], p[1] = c[1], p[2] = c[2], p[3] = 255;
    }
  }
}

}  // namespace

InstructorLayout instructor_layout(int width, int height, const InstructorOverlay& o) {
  InstructorLayout l;
  l.scale = std::max(1, height / 320);
  l.line_height = (font::kGlyphHeight + 3) * l.scale;
  const int margin = 4 * l.scale;
  int widest = 0;
  for (const auto& line : o.lines) widest = std::max(widest, font::text_width(line, l.scale));
  l.panel_x = margin;
  l.panel_y = margin;
  l.panel_w = std::min(width - 2 * margin, widest + 2 * margin);
  l.panel_h = static_cast<int>(o.lines.size()) * l.line_height + 2 * margin - 3 * l.scale;
  l.bar_h = 6 * l.scale;
  l.bar_x = margin;
  l.bar_w = std::max(1, width / 2);
  l.bar_y = height - margin - l.bar_h;
  l.events_x = width - margin;
  l.events_y = margin;
  return l;
}

Image compose_instructor_view(const StereoFrame& frame, const InstructorOverlay& o) {
  Image img = frame.eye(0);
  const InstructorLayout l = instructor_layout(img.width, img.height, o);
  const int margin = 4 * l.scale;
  const std::array<std::uint8_t, 3> white{235, 235, 225}, amber{255, 190, 60}, red{255, 70, 50}, green{90, 220, 110};
  if (!o.lines.empty()) {
    shade(img, l.panel_x, l.panel_y, l.panel_w, l.panel_h, 0.35f);
    for (std::size_t i = 0; i < o.lines.size(); ++i) {
      font::draw_text(img, l.panel_x + margin, l.panel_y + margin + static_cast<int>(i) * l.line_height, o.lines[i], white, l.scale);
    }
  }
  // Retina contact force: green below half the damage limit, amber to the limit, red above it.
  const float limit = std::max(o.force_limit_un, 1.0f);
  const float frac = std::clamp(o.retina_force_un / limit, 0.0f, 1.5f) / 1.5f;  // the bar spans 1.5× the limit
  shade(img, l.bar_x, l.bar_y, l.bar_w, l.bar_h, 0.3f);
  const float f = o.retina_force_un / limit;
  fill(img, l.bar_x, l.bar_y, static_cast<int>(std::lround(frac * l.bar_w)), l.bar_h, f < 0.5f ? green : f < 1.0f ? amber : red);
  fill(img, l.bar_x + static_cast<int>(std::lround(l.bar_w / 1.5f)), l.bar_y - l.scale, l.scale, l.bar_h + 2 * l.scale, white);
  char force[64];
  std::snprintf(force, sizeof force, "RETINA FORCE %.0f uN", static_cast<double>(o.retina_force_un));
  font::draw_text(img, l.bar_x + l.bar_w + margin, l.bar_y - l.scale, force, f < 1.0f ? white : red, l.scale);
  // The latest events, newest at the top, right-aligned.
  int y = l.events_y;
  for (auto it = o.events.rbegin(); it != o.events.rend() && y + l.line_height < l.bar_y; ++it) {
    const int w = font::text_width(*it, l.scale);
    shade(img, l.events_x - w - margin, y - l.scale, w + 2 * margin, l.line_height, 0.35f);
    font::draw_text(img, l.events_x - w, y, *it, amber, l.scale);
    y += l.line_height;
  }
  return img;
}

}  // namespace vitreo::render
